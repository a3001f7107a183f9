"""The model's static mesh stiffness, measured through the unit, against ISO 6336-1's mesh
stiffness c_gamma_alpha (docs/model.md section 3.7).

ISO 6336-1 method B (the standard's fit to measured stiffness, contact flattening included,
stated for loads of 100 N/mm and above): the single stiffness of an unshifted pair
``c' = C_M C_R C_B cos(beta) / q'``, ``q' = C1 + C2/z_n1 + C3/z_n2`` in the virtual numbers of
teeth ``z_n = z / (cos^2(beta_b) cos(beta))``, with C_M = 0.8 (measured over theoretical),
C_R = C_B = 1 (solid blanks, the basic rack), and the mesh stiffness
``c_gamma_alpha = c' (0.75 eps_alpha + 0.25)`` [N/(mm um)], per mm of face width, transverse.

The model's: the unit started in its static flank equilibrium (``init.in_contact``) under
the torque of a tangential load F_t at the wheel's reference circle (the load per face width
F_t/b of ISO), and under 1 % more, at ``angles`` pinion angles over a base pitch; the
transverse stiffness is the rise of the tangential force at the base circle over the rise of
the transverse displacement along the line of action, ``dF_bt / d(x / cos(beta_b))``
(x = ``mesh.transmission_error``, on the tooth normal), its mean over the angles the mesh
stiffness, compared with ``c_gamma_alpha b``.

    python -m drive_rattle_cosim.mesh_stiffness [--angles 8] [--update docs/model.md]

``--update`` rewrites the block ``<!-- BEGIN mesh stiffness -->...<!-- END mesh stiffness -->``
of the file with this report (tests/analysis/test_mesh_stiffness.py holds docs/model.md's
against a fresh run).
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from pathlib import Path

from drive_rattle.parameters import MeshParameters
from drive_rattle.units import MeshUnit

from .analysis import markdown_table

#: ISO 6336-1 method B: C1, C2, C3 of q' for unshifted gears, and C_M, C_R, C_B.
ISO_C1, ISO_C2, ISO_C3 = 0.04723, 0.15551, 0.25791
ISO_C_M, ISO_C_R, ISO_C_B = 0.8, 1.0, 1.0
#: Loads per face width [N/mm]: the paper scenario's (0.5 M* on the reference pair), a light
#: one, and two where ISO 6336-1's stiffness holds.
LOADS = (0.067, 10.0, 100.0, 200.0)
#: Where ISO 6336-1's stiffness holds [N/mm], and the band the model's must lie in there.
ISO_LOAD = 100.0
ISO_BAND = (0.6, 1.5)
#: The contact geometries compared, each at its defaults (the teeth's compliance on), and
#: the paper's as printed (rigid teeth).
CONTACTS = (
    ("crowned (default)", {}),
    ("paper's ellipsoids", {"contact_geometry": 1}),
    ("line (Palmgren)", {"contact_geometry": 2}),
)
#: Relative rise of the load between the two equilibria.
LOAD_STEP = 0.01


def iso_single_stiffness(p: MeshParameters) -> float:
    """c' [N/(mm um)] of ISO 6336-1 method B."""
    beta_b = math.asin(math.sin(p.beta) * math.cos(p.alpha_n))
    factor = math.cos(beta_b) ** 2 * math.cos(p.beta)
    q_prime = ISO_C1 + ISO_C2 * factor / p.z_pinion + ISO_C3 * factor / p.z_wheel
    return ISO_C_M * ISO_C_R * ISO_C_B * math.cos(p.beta) / q_prime


def iso_mesh_stiffness(p: MeshParameters) -> float:
    """c_gamma_alpha b [N/m]: ISO 6336-1's transverse mesh stiffness of the whole face."""
    c_gamma_alpha = iso_single_stiffness(p) * (0.75 * p.derived()["eps_alpha"] + 0.25)
    return c_gamma_alpha * 1e9 * p.b  # N/(mm um) = 1e9 N/m^2, per m of face width


def static_stiffness(p: MeshParameters, load_per_width: float, angles: int = 8) -> float:
    """The mean transverse static mesh stiffness [N/m] of the parameters at the load
    ``load_per_width`` [N/mm] (module docstring)."""
    d = p.derived()
    q = p.with_public(friction_enabled=False, init_in_contact=True)
    torque = load_per_width * 1e3 * p.b * d["r_wheel"]
    stiffness = []
    for j in range(angles):
        phi = j / angles * d["base_pitch"] / d["rb_pinion"]
        x = []
        for tau in (torque, torque * (1.0 + LOAD_STEP)):
            with MeshUnit(q, phi, 0.0, tau) as unit:
                x.append(unit.get(("mesh.transmission_error",))["mesh.transmission_error"])
        force = torque * LOAD_STEP / d["rb_wheel"]
        stiffness.append(force / ((x[1] - x[0]) / d["normal_factor"]))
    return math.fsum(stiffness) / len(stiffness)


def stiffness_ratios(contacts=CONTACTS, loads=LOADS, angles: int = 8,
                     teeth: int | None = None) -> dict[str, list[float]]:
    """{contact: [static stiffness / (c_gamma_alpha b) at each load]}, the teeth's compliance
    at each contact's default or ``teeth`` (0 rigid, 1 on)."""
    out = {}
    for name, changes in contacts:
        changes = dict(changes) if teeth is None else {**changes, "tooth_compliance": teeth}
        p = MeshParameters(**changes)
        iso = iso_mesh_stiffness(p)
        out[name] = [static_stiffness(p, q, angles) / iso for q in loads]
    return out


def table(ratios: dict[str, list[float]], loads=LOADS) -> str:
    """The ratios as a markdown table, a row per load."""
    rows = [(f"{q:g} N/mm", *(f"{ratios[c][i]:.2f} ×" for c in ratios))
            for i, q in enumerate(loads)]
    return markdown_table(rows, ("load per face width", *ratios))


def report(angles: int = 8) -> str:
    p = MeshParameters()
    c_single = iso_single_stiffness(p)
    c_mesh = iso_mesh_stiffness(p) / (1e9 * p.b)
    lines = [f"ISO 6336-1 method B, reference pair: c' = {c_single:.3g}, c_gamma_alpha = "
             f"{c_mesh:.3g} N/(mm um), c_gamma_alpha b = {iso_mesh_stiffness(p):.3g} N/m", ""]
    for title, teeth in (("rigid teeth (tooth.compliance = 0)", 0),
                         ("with the teeth's compliance (tooth.compliance = 1)", 1)):
        lines += [f"Static mesh stiffness over c_gamma_alpha b, {title}:", "",
                  table(stiffness_ratios(angles=angles, teeth=teeth))]
    return "\n".join(lines).rstrip("\n")


#: The block of a document that holds the report.
BLOCK = "mesh stiffness"
_BLOCK = re.compile(rf"(<!-- BEGIN {BLOCK} -->)(.*?)(<!-- END {BLOCK} -->)", re.S)


def update(text: str, body: str) -> str:
    """``text`` with the body of its block replaced; ValueError without exactly one block."""
    if len(_BLOCK.findall(text)) != 1:
        raise ValueError(f"the text needs one block <!-- BEGIN {BLOCK} --> ... "
                         f"<!-- END {BLOCK} -->")
    return _BLOCK.sub(lambda m: m[1] + "\n" + body + "\n" + m[3], text)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--angles", type=int, default=8,
                        help="pinion angles over a base pitch (default 8)")
    parser.add_argument("--update", type=Path, default=None,
                        help="rewrite the report's block in this file (docs/model.md)")
    args = parser.parse_args(argv)
    text = report(args.angles)
    if args.update is None:
        print(text)
        return 0
    try:
        args.update.write_text(update(args.update.read_text(encoding="utf-8"), text),
                               encoding="utf-8")
    except (OSError, ValueError) as err:
        print(f"mesh_stiffness: {err}", file=sys.stderr)
        return 1
    print(f"updated {args.update}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
