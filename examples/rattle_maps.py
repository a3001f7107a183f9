"""Rattle maps: the rattle index (impact kinetic energy per second) of the co-simulated
paper scenario over two parameter planes, as PNG heat maps --

* backlash x drag torque,
* order-2 amplitude x engine speed --

each a grid sweep on dask (LocalCluster) with results written case by case, so that an
interrupted run resumes where it stopped.

    python examples/rattle_maps.py [--points 5] [--stop-time 0.3] [--workers 2]
                                   [--out out/rattle_maps]
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from drive_rattle_cosim.fmus import build_fmus
from drive_rattle_cosim.sweep import grid_design, read_results, run_sweep

ROOT = Path(__file__).resolve().parents[1]
RPM = 2 * math.pi / 60

#: (file stem, x parameter, x range, x display factor and label, y ...)
MAPS = (
    ("backlash_drag",
     "GearMeshRattle.gear.backlash", (0.05e-3, 0.25e-3), 1e3, "normal backlash [mm]",
     "Driveline.vehicle.drag", (0.10, 0.30), 1.0, "drag torque [N·m]"),
    ("amplitude_speed",
     "Driveline.engine.amplitude[1]", (100.0, 600.0), 1.0, "order-2 amplitude [rad/s²]",
     "Driveline.engine.w_mean", (700 * RPM, 1500 * RPM), 1 / RPM, "engine speed [rpm]"),
)


def run(points: int = 5, stop_time: float = 0.3, workers: int = 2,
        out_dir: str | Path = "out/rattle_maps", fmu_dir: str | Path | None = None,
        progress: bool = True) -> dict:
    """Sweep both planes and draw the maps; returns the written files and the sweep counts."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if fmu_dir is None:
        fmu_dir = build_fmus(ROOT / "dist")["GearMeshRattle"].parent
    files, counts = [], {}
    for stem, xname, xr, xf, xlabel, yname, yr, yf, ylabel in MAPS:
        results = out / f"{stem}.csv"
        cases = grid_design({xname: xr, yname: yr}, points)
        counts[stem] = run_sweep(cases, results, fmu_dir, stop_time, workers=workers,
                                 progress=progress)
        files += [results, _heat_map(read_results(results), xname, xf, xlabel, yname, yf,
                                     ylabel, out / f"{stem}.png", stop_time)]
    return {"files": files, "counts": counts}


def _heat_map(rows, xname, xf, xlabel, yname, yf, ylabel, path: Path, stop_time) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm, Normalize

    xs = sorted({r[xname] for r in rows})
    ys = sorted({r[yname] for r in rows})
    z = np.full((len(ys), len(xs)), np.nan)
    for r in rows:
        z[ys.index(r[yname]), xs.index(r[xname])] = r["rattle_index_W"]
    positive = z[np.isfinite(z) & (z > 0)]
    if positive.size and positive.max() > positive.min():  # log colours over the impacts
        norm, z = LogNorm(positive.min(), positive.max()), np.maximum(z, positive.min())
    else:  # no impact, or all equal: a log scale has no range
        norm = Normalize()
    fig, ax = plt.subplots(figsize=(6, 4.5))
    mesh = ax.pcolormesh(np.asarray(xs) * xf, np.asarray(ys) * yf, z, shading="nearest",
                         norm=norm, cmap="magma")
    fig.colorbar(mesh, ax=ax, label="rattle index: impact energy per second [W]")
    failed = [(r[xname] * xf, r[yname] * yf) for r in rows if r["error"]]
    if failed:
        ax.plot(*zip(*failed, strict=True), "x", color="cyan", label="failed case")
        ax.legend()
    ax.set(xlabel=xlabel, ylabel=ylabel, title=f"Rattle index ({stop_time:g} s per case)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=5, help="grid points per parameter")
    ap.add_argument("--stop-time", type=float, default=0.3, help="simulated time per case [s]")
    ap.add_argument("--workers", type=int, default=2, help="dask worker processes")
    ap.add_argument("--out", default="out/rattle_maps")
    ap.add_argument("--fmu-dir", default=None, help="folder with built FMUs (default: build)")
    args = ap.parse_args(argv)
    result = run(args.points, args.stop_time, args.workers, args.out, args.fmu_dir)
    for stem, c in result["counts"].items():
        print(f"{stem}: {c['done']} cases run ({c['failed']} failed), {c['skipped']} resumed")
    for f in result["files"]:
        print("wrote", f)
    return 0


if __name__ == "__main__":
    sys.exit(main())
