"""The FMUs' icon, ``model.png`` at the archive's root (FMI 2.0, section 2.3) and
``terminalsAndIcons/icon.png`` in the FMI 3.0 FMUs: a pinion meshing with a wheel; and the
image of their terminals, a shaft's flange (``flange_png``).  Drawn by the build with the
standard library alone (no plotting package is a build dependency), the same bytes on every
build.

    python -m drive_rattle_build.icon out.png     # write it to look at
"""

from __future__ import annotations

import functools
import math
import struct
import sys
import zipfile
import zlib
from pathlib import Path

#: Side of the square icon [px] and samples per pixel side (antialiasing).
SIZE, SUPERSAMPLE = 128, 3
#: The two gears: (centre x, centre y, pitch radius, teeth, phase [rad], RGB), in icon pixels.
#: Tooth counts of the paper's pair would crowd the small icon; these read as a gear pair.
GEARS = (
    (44.0, 70.0, 33.0, 12, 0.0, (70, 110, 170)),  # wheel
    (44.0 + 33.0 + 20.0, 70.0 - 28.0, 0.0, 8, 0.0, (220, 130, 40)),  # pinion (radius below)
)
PINION_RADIUS = 20.0
#: Tooth height over the pitch radius (addendum = dedendum = this / 2) and the hole.
TOOTH, HOLE = 0.24, 0.22


#: A flange's image: side [px] and colour, a filled disc in the grey of the Modelica Standard
#: Library's rotational Flange_a icon (fillColor {95,95,95}).
FLANGE_SIZE, FLANGE_RGB = 32, (95, 95, 95)


def gear_centres() -> dict[str, tuple[float, float]]:
    """The centres of the wheel and the pinion in the icon, in pixels from its top left."""
    wheel, pinion = _gears()
    return {"wheel": (wheel[0], wheel[1]), "pinion": (pinion[0], pinion[1])}


def _gears():
    wheel, pinion = GEARS
    cx, cy, r, z, _, rgb = wheel
    # the pinion sits at the sum of the pitch radii, in the direction it is drawn, with a tooth
    # of one facing a gap of the other on the line of centres
    angle = math.atan2(pinion[1] - cy, pinion[0] - cx)
    px = cx + (r + PINION_RADIUS) * math.cos(angle)
    py = cy + (r + PINION_RADIUS) * math.sin(angle)
    wheel_phase = -angle  # a tooth of the wheel on the line of centres
    pinion_phase = math.pi - angle + math.pi / pinion[3]  # a gap of the pinion facing it
    # the pair centred in the icon
    outer = [(cx, cy, r * (1 + TOOTH / 2)), (px, py, PINION_RADIUS * (1 + TOOTH / 2))]
    left, right = min(x - a for x, _, a in outer), max(x + a for x, _, a in outer)
    top, bottom = min(y - a for _, y, a in outer), max(y + a for _, y, a in outer)
    sx, sy = (SIZE - left - right) / 2, (SIZE - top - bottom) / 2
    return ((cx + sx, cy + sy, r, z, wheel_phase, rgb),
            (px + sx, py + sy, PINION_RADIUS, pinion[3], pinion_phase, pinion[5]))


def _inside(x: float, y: float, gear) -> bool:
    cx, cy, r, z, phase, _ = gear
    dx, dy = x - cx, y - cy
    d = math.hypot(dx, dy)
    if d < HOLE * r or d > r * (1 + TOOTH / 2):
        return False
    # a trapezoidal tooth: flanks over a quarter of the pitch each, tip and root a quarter
    u = ((math.atan2(dy, dx) + phase) * z / (2 * math.pi)) % 1.0
    rise = min(1.0, max(0.0, 4.0 * min(u, 1.0 - u) * 2.0 - 0.5))
    return d <= r * (1 - TOOTH / 2 + TOOTH * rise)


def _png(width: int, height: int, rows: list[bytes]) -> bytes:
    def chunk(kind: bytes, data: bytes) -> bytes:
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    raw = b"".join(b"\0" + row for row in rows)  # filter type 0 on every row
    header = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)  # 8-bit RGBA
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 9))
            + chunk(b"IEND", b""))


@functools.cache  # the same bytes every time; drawing them takes about 1 s of pure Python
def model_png() -> bytes:
    """The icon as PNG bytes (RGBA, transparent outside the gears)."""
    gears = _gears()
    n = SUPERSAMPLE
    rows = []
    for j in range(SIZE):
        row = bytearray()
        for i in range(SIZE):
            hits = [0] * len(gears)
            for a in range(n):
                for b in range(n):
                    x, y = i + (a + 0.5) / n, j + (b + 0.5) / n
                    for k, gear in enumerate(gears):
                        if _inside(x, y, gear):
                            hits[k] += 1
                            break
            total = sum(hits)
            if total == 0:
                row += bytes(4)
                continue
            rgb = [sum(h * g[5][c] for h, g in zip(hits, gears, strict=True)) // total
                   for c in range(3)]
            row += bytes((*rgb, round(255 * total / (n * n))))
        rows.append(bytes(row))
    return _png(SIZE, SIZE, rows)


@functools.cache
def flange_png() -> bytes:
    """A terminal's image as PNG bytes (RGBA): the flange's disc, transparent around it."""
    n, radius = SUPERSAMPLE, FLANGE_SIZE / 2
    rows = []
    for j in range(FLANGE_SIZE):
        row = bytearray()
        for i in range(FLANGE_SIZE):
            hits = sum(math.hypot(i + (a + 0.5) / n - radius, j + (b + 0.5) / n - radius)
                       <= radius for a in range(n) for b in range(n))
            row += bytes((*FLANGE_RGB, round(255 * hits / (n * n))) if hits else bytes(4))
        rows.append(bytes(row))
    return _png(FLANGE_SIZE, FLANGE_SIZE, rows)


def add_icon(fmu: Path) -> None:
    """Add ``model.png`` to the archive ``fmu`` (an FMU without one)."""
    with zipfile.ZipFile(fmu, "a", zipfile.ZIP_DEFLATED) as z:
        if "model.png" in z.namelist():
            raise ValueError(f"{fmu} already has a model.png")
        z.writestr("model.png", model_png())


if __name__ == "__main__":
    target = Path(sys.argv[1] if len(sys.argv) > 1 else "model.png")
    target.write_bytes(model_png())
    print(f"wrote {target}")
