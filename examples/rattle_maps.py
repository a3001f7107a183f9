"""Rattle maps: the rattle index (impact kinetic energy per second) of the co-simulated paper
scenario over two parameter planes, as PNG heat maps --

* backlash x drag torque,
* order-2 amplitude x engine speed --

each a grid sweep on dask (LocalCluster) with results written case by case, so that an
interrupted run resumes where it stopped.  With ``--starts smooth,free`` (or any starts of
``drive_rattle_cosim.multistability``: kicks, free, phase-shifted orders) every cell runs from
each start, the map shows the value of the start listed first in
``multistability.STARTS`` (smooth, kicks, free, phases), and a cell whose starts disagree beyond
their window scatter -- the rattle index of two starts apart by more than twice the root sum of
squares of their window-to-window standard deviations plus 1 % -- is cross-hatched as
multistable (docs/analysis.md section 7).  The cases run on the model library's compiled loop
(the FMUs' numbers bit for bit, tests/cosim/test_sweep.py); ``--fmu-dir`` runs them on built
FMUs in the fmpy harness instead.  Every case runs a start transient (left out) and
then several equal windows; a map shows the mean over the windows, hatched where the
window-to-window scatter exceeds a stated fraction of the value, next to a map of that scatter.

    python examples/rattle_maps.py [--points 5] [--transient 1] [--window 1] [--windows 3]
                                   [--starts smooth] [--workers 2] [--out out/rattle_maps]
                                   [--fmu-dir dist]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from drive_rattle.parameters import DrivelineParameters, MeshParameters
from drive_rattle_build.library import build_in_place
from drive_rattle_cosim import multistability
from drive_rattle_cosim.sweep import Case, grid_design, read_results, run_sweep

RPM = 2 * math.pi / 60

#: (file stem, x parameter, x range, x display factor and label, y ...)
MAPS = (
    ("backlash_drag",
     "GearMeshRattle.gear.backlash", (0.05e-3, 0.25e-3), 1e3, "normal backlash [mm]",
     # 0.2-1.2 M* of the default wheel and orders (M* = 0.1667 N.m, docs/model.md 6.1)
     "Driveline.vehicle.drag", (0.0333, 0.2), 1.0, "drag torque [N·m]"),
    ("amplitude_speed",
     "Driveline.engine.amplitude[1]", (100.0, 600.0), 1.0, "order-2 amplitude [rad/s²]",
     "Driveline.engine.w_mean", (700 * RPM, 1500 * RPM), 1 / RPM, "engine speed [rpm]"),
)
#: Hatch a cell whose window-to-window standard deviation exceeds this fraction of its mean.
SCATTER_LIMIT = 0.2
#: Starts of a cell disagree when their rattle indices differ by more than SEPARATION root sums
#: of squares of their window scatters plus this fraction of the larger (the multistability
#: study's test on its energy-rate statistic).
START_FLOOR = 0.01
#: The public parameters a start sets, per unit (a case names all of them, so that every row
#: of a sweep has the same columns).
START_PARAMETERS = {
    "GearMeshRattle": {"init.in_contact": "init_in_contact", "wheel.phi_start": "phi_start",
                       "wheel.w_start": "w_start"},
    "Driveline": {"pinion.phi_start": "phi_start",
                  **{f"engine.phase[{k}]": f"phase_{k}" for k in range(1, 5)}},
}


def start_cases(cases: list[Case], starts: list[str]) -> dict[str, tuple[Case, int]]:
    """Each case once per start (names of multistability.STARTS_BY_KEY), with the parameters
    that start sets: case id -> (case, the start's place in multistability.STARTS); one start
    "smooth": the cases as they are (the default start)."""
    if starts == ["smooth"]:
        return {c.case_id: (c, 0) for c in cases}
    out = {}
    for case in cases:
        split = {unit: {k.split(".", 1)[1]: v for k, v in case.parameters.items()
                        if k.startswith(unit + ".")} for unit in START_PARAMETERS}
        mesh = MeshParameters.from_public(split["GearMeshRattle"])
        drive = DrivelineParameters.from_public(split["Driveline"])
        for key in starts:
            m, d = multistability.start_parameters(mesh, drive,
                                                   multistability.STARTS_BY_KEY[key])
            extra = {}
            for unit, params in (("GearMeshRattle", m), ("Driveline", d)):
                for public, attr in START_PARAMETERS[unit].items():
                    extra[f"{unit}.{public}"] = float(getattr(params, attr))
            c = Case.of({**case.parameters, **extra})
            out[c.case_id] = (c, list(multistability.STARTS_BY_KEY).index(key))
    return out


def disagreeing(values: list[tuple[float, float]], separation: float = 2.0,
                floor: float = START_FLOOR) -> bool:
    """Whether the (mean, window scatter) of a cell's starts disagree beyond their scatter."""
    for i, (m1, s1) in enumerate(values):
        for m2, s2 in values[i + 1:]:
            s1_, s2_ = (s if math.isfinite(s) else 0.0 for s in (s1, s2))
            if abs(m1 - m2) > separation * math.hypot(s1_, s2_) + floor * max(abs(m1),
                                                                               abs(m2)):
                return True
    return False


def run(points: int = 5, transient: float = 1.0, window: float = 1.0, windows: int = 3,
        workers: int = 2, out_dir: str | Path = "out/rattle_maps",
        fmu_dir: str | Path | None = None, progress: bool = True,
        scatter_limit: float = SCATTER_LIMIT, starts=("smooth",)) -> dict:
    """Sweep both planes (``points`` values per parameter; each case ``transient`` +
    ``windows`` x ``window`` seconds, from each of ``starts``) and draw the maps; returns the
    written files, the sweep counts and the multistable cells per map."""
    if not (points >= 2 and windows >= 1 and window > 0 and transient >= 0):
        raise ValueError(f"points = {points!r}, windows = {windows!r}, window = {window!r} s, "
                         f"transient = {transient!r} s; allowed: points >= 2, windows >= 1, "
                         "window > 0, transient >= 0")
    starts = [k.strip().replace(" ", "") for k in starts]
    unknown = [k for k in starts if k not in multistability.STARTS_BY_KEY]
    if unknown or not starts or len(set(starts)) != len(starts):
        raise ValueError(f"starts = {starts!r}; allowed: distinct names of "
                         f"{', '.join(multistability.STARTS_BY_KEY)}")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    build_in_place()  # the library of this checkout's sources (the workers load it)
    stop_time = transient + windows * window
    settings = {"transient [s]": transient, "window [s]": window, "windows": windows}
    if starts != ["smooth"]:
        settings["starts"] = starts
    files, counts, multistable = [], {}, {}
    for stem, xname, xr, xf, xlabel, yname, yr, yf, ylabel in MAPS:
        results = out / f"{stem}.csv"
        _same_settings(out / f"{stem}.settings.json", settings, results)
        cases = start_cases(grid_design({xname: xr, yname: yr}, points), starts)
        counts[stem] = run_sweep([c for c, _ in cases.values()], results, fmu_dir, stop_time,
                                 workers=workers, progress=progress, transient=transient,
                                 window=window)
        rows = [{**r, "start": cases[r["case_id"]][1]} for r in read_results(results)]
        title = (f"{windows} windows of {window:g} s per case after a {transient:g} s "
                 "transient")
        if len(starts) > 1:
            title += f"; starts: {', '.join(starts)}"
        path, multistable[stem] = _heat_map(rows, (xname, xf, xlabel),
                                            (yname, yf, ylabel), out / f"{stem}.png", title,
                                            scatter_limit)
        files += [results, path]
    return {"files": files, "counts": counts, "stop_time": stop_time,
            "multistable": multistable}


def _same_settings(path: Path, settings: dict, results: Path) -> None:
    """A sweep resumes only with the settings it started with (the case ids are those of the
    parameters alone)."""
    if results.exists() and path.exists():
        before = json.loads(path.read_text(encoding="utf-8"))
        if before != settings:
            raise ValueError(f"{results} was run with {before}, not {settings}; use another "
                             "--out or delete it")
    path.write_text(json.dumps(settings), encoding="utf-8")


def _grid(rows, name):
    return sorted({r[name] for r in rows})


def _edges(values: np.ndarray) -> np.ndarray:
    """Cell edges around grid values (midpoints; the end cells symmetric)."""
    if len(values) == 1:
        return np.array([values[0] - 0.5, values[0] + 0.5]) * (abs(values[0]) or 1.0)
    mid = (values[1:] + values[:-1]) / 2
    return np.concatenate([[2 * values[0] - mid[0]], mid, [2 * values[-1] - mid[-1]]])


def _heat_map(rows, x, y, path: Path, title: str, scatter_limit: float
              ) -> tuple[Path, list[tuple[float, float]]]:
    """Draw a map; returns its file and the (x, y) of its multistable cells."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm, Normalize
    from matplotlib.patches import Patch, Rectangle

    (xname, xf, xlabel), (yname, yf, ylabel) = x, y
    xs, ys = _grid(rows, xname), _grid(rows, yname)
    mean = np.full((len(ys), len(xs)), np.nan)
    spread = np.full_like(mean, np.nan)
    by_cell: dict[tuple[int, int], list[tuple[float, float]]] = {}
    # the row of the start first in multistability.STARTS shows (drawn last)
    for r in sorted(rows, key=lambda r: -r["start"]):
        i, j = ys.index(r[yname]), xs.index(r[xname])
        if not r["error"]:
            by_cell.setdefault((i, j), []).append(
                (r["rattle_index_W"], r.get("rattle_index_W_std", math.nan)))
        mean[i, j] = r["rattle_index_W"]
        std = r.get("rattle_index_W_std", math.nan)
        spread[i, j] = std / mean[i, j] if mean[i, j] > 0 else math.nan
    split = {cell for cell, values in by_cell.items() if disagreeing(values)}
    xv, yv = np.asarray(xs) * xf, np.asarray(ys) * yf
    xe, ye = _edges(xv), _edges(yv)
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12, 5), layout="constrained")
    positive = mean[np.isfinite(mean) & (mean > 0)]
    if positive.size and positive.max() > positive.min():  # log colours over the impacts
        norm, shown = LogNorm(positive.min(), positive.max()), np.maximum(mean, positive.min())
    else:  # no impact, or all equal: a log scale has no range
        norm, shown = Normalize(), mean
    m1 = ax.pcolormesh(xe, ye, shown * 1e3, norm=_scaled(norm, 1e3), cmap="magma")
    fig.colorbar(m1, ax=ax, label="rattle index: impact energy per second [mW]")
    m2 = ax2.pcolormesh(xe, ye, spread * 100, cmap="viridis", vmin=0,
                        vmax=max(100.0, float(np.nanmax(spread, initial=0)) * 100))
    fig.colorbar(m2, ax=ax2, label="window-to-window std / mean [%]")
    handles = []
    for i in range(len(ys)):
        for j in range(len(xs)):
            cell = (xe[j], ye[i]), xe[j + 1] - xe[j], ye[i + 1] - ye[i]
            if spread[i, j] > scatter_limit:
                ax.add_patch(Rectangle(*cell, fill=False, hatch="//", ec="cyan", lw=0))
            if (i, j) in split:
                ax.add_patch(Rectangle(*cell, fill=False, hatch="xx", ec="lime", lw=1.5))
            if np.isfinite(mean[i, j]):
                text = "no\nimpact" if mean[i, j] == 0 else f"{mean[i, j] * 1e3:.3g}"
                _label(ax, xv[j], yv[i], text, m1.to_rgba(shown[i, j] * 1e3))
            if np.isfinite(spread[i, j]):
                _label(ax2, xv[j], yv[i], f"{spread[i, j] * 100:.0f} %",
                       m2.to_rgba(spread[i, j] * 100))
    if np.any(spread > scatter_limit):
        handles.append(Patch(fill=False, hatch="///", ec="cyan",
                             label=f"scatter > {scatter_limit:.0%} of the value"))
    if split:
        handles.append(Patch(fill=False, hatch="xx", ec="lime",
                             label="multistable: starts disagree beyond their scatter"))
    failed = [(r[xname] * xf, r[yname] * yf) for r in rows if r["error"]]
    if failed:
        handles += ax.plot(*zip(*failed, strict=True), "x", color="cyan", ms=10,
                           label="failed case")
    if handles:
        ax.legend(handles=handles, loc="upper left", fontsize=7, framealpha=0.9)
    for a in (ax, ax2):
        a.set_xticks(xv, [f"{v:.4g}" for v in xv])
        a.set_yticks(yv, [f"{v:.4g}" for v in yv])
        a.set(xlabel=xlabel, ylabel=ylabel)
    ax.set_title("Rattle index (mean over the windows)", fontsize=10)
    ax2.set_title("Its scatter over the windows", fontsize=10)
    fig.suptitle(title, fontsize=10)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path, sorted((xs[j], ys[i]) for i, j in split)


def _label(ax, x, y, text: str, background) -> None:
    """Cell text in black or white, whichever reads on the cell's colour, on a faint box so
    that hatching does not cross it."""
    r, g, b, _ = background
    dark = 0.299 * r + 0.587 * g + 0.114 * b < 0.5  # luma (ITU-R BT.601)
    ax.text(x, y, text, ha="center", va="center", fontsize=7.5,
            color="white" if dark else "black",
            bbox={"boxstyle": "round,pad=0.15", "lw": 0, "fc": background})


def _scaled(norm, factor: float):
    """``norm`` for values multiplied by ``factor``."""
    from matplotlib.colors import LogNorm, Normalize

    if isinstance(norm, LogNorm):
        return LogNorm(norm.vmin * factor, norm.vmax * factor)
    return Normalize()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=5, help="grid points per parameter")
    ap.add_argument("--transient", type=float, default=1.0,
                    help="start transient per case, left out [s]")
    ap.add_argument("--window", type=float, default=1.0, help="window of the statistics [s]")
    ap.add_argument("--windows", type=int, default=3, help="windows per case")
    ap.add_argument("--starts", default="smooth",
                    help="starts of every cell, comma-separated (of "
                         f"{', '.join(multistability.STARTS_BY_KEY)}); with two or more, "
                         "cells whose starts disagree beyond their scatter are marked")
    ap.add_argument("--workers", type=int, default=2, help="dask worker processes")
    ap.add_argument("--out", default="out/rattle_maps")
    ap.add_argument("--fmu-dir", default=None,
                    help="run the cases on the FMUs of this folder in the fmpy harness "
                         "(default: the model library's compiled loop)")
    args = ap.parse_args(argv)
    result = run(args.points, args.transient, args.window, args.windows, args.workers,
                 args.out, args.fmu_dir, starts=args.starts.split(","))
    for stem, c in result["counts"].items():
        print(f"{stem}: {c['done']} cases run ({c['failed']} failed), {c['skipped']} resumed; "
              f"{len(result['multistable'][stem])} multistable cells")
    for f in result["files"]:
        print("wrote", f)
    return 0


if __name__ == "__main__":
    sys.exit(main())
