"""The evidence behind the default contact and drag (docs/model.md section 6): the paper's model
-- the mesh alone, pinion from the default engine orders, a constant load M_res -- scanned over
the load relative to M*, and the sensitivity of its statistics to the contact's parameters.

    python benchmarks/calibration.py [--seconds 6] [--out out/calibration.md]

Each case starts smooth (static flank equilibrium) and kicked (+1 rad/s on the wheel), runs
``--seconds`` on the compiled kernel and reports, over whole forcing periods after a 1 s
transient, in windows of 1 s: onsets per second on each flank, the median and 90th-percentile
onset speed (the last onset of each step), the largest penetration and the pairs loaded while in
contact -- mean over the windows, and the largest difference between the two starts.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from drive_rattle import MeshParameters, kernel
from drive_rattle.driveline import DrivelineParameters, EngineOrderKinematics

H = 1e-4
PERIOD = math.pi / DrivelineParameters().w_mean  # orders 2, 4, 6 and the mesh repeat
PARAMS = MeshParameters()
M_STAR = PARAMS.J_wheel * PARAMS.z_pinion / PARAMS.z_wheel * 250.0

LOAD_SCAN = (0.3, 0.4, 0.5, 0.6, 0.7, 0.9, 1.1, 1.3)
SENSITIVITY = (
    ("default", {}),
    ("restitution 0.7", {"restitution": 0.7}),
    ("restitution 0.9", {"restitution": 0.9}),
    ("crowning 2 um", {"crowning": 2e-6}),
    ("crowning 5 um", {"crowning": 5e-6}),
    ("crowning 20 um", {"crowning": 20e-6}),
    ("equivalent sphere (eq. 2)", {"hertz_law": 1}),
    ("friction off", {"friction_enabled": False}),
    ("no dissipation (the paper)", {"dissipation": 0}),
)


def run(load_fraction: float, changes: dict, kick: float, seconds: float) -> list[dict]:
    """Per-window statistics of one start."""
    kin = EngineOrderKinematics(DrivelineParameters())
    load = load_fraction * M_STAR
    phi, w, _ = kin(0.0)
    st = kernel.new_stepper(MeshParameters(**changes), phi, w, load)
    st.restore(replace(st.snapshot(), state=replace(st.state, w=st.state.w + kick)))
    per_window = round(1.0 / PERIOD) * PERIOD  # whole forcing periods, ~1 s
    windows, n = [], round(seconds / H)
    t_start = 1.0
    cur = None
    for k in range(n):
        before = (st.state.impacts_drive, st.state.impacts_coast)
        r = st.step(H, *kin(k * H), load)
        t = (k + 1) * H
        if t <= t_start:
            continue
        index = int((t - t_start) / per_window)
        if cur is None or cur["index"] != index:
            cur = {"index": index, "drive": 0, "coast": 0, "speeds": [], "d_peak": 0.0,
                   "pairs": [], "steps": 0}
            windows.append(cur)
        s = st.state
        cur["drive"] += s.impacts_drive - before[0]
        cur["coast"] += s.impacts_coast - before[1]
        if r.onsets_drive + r.onsets_coast:
            cur["speeds"].append(s.v_impact_last)
        cur["d_peak"] = max(cur["d_peak"], r.delta_peak)
        pairs = st.outputs()["mesh.n_contact"]
        if pairs:
            cur["pairs"].append(pairs)
        cur["steps"] += 1
    full = [w for w in windows if w["steps"] >= round(per_window / H) - 1]
    return [{
        "drive [1/s]": w["drive"] / per_window,
        "coast [1/s]": w["coast"] / per_window,
        "median v [mm/s]": 1e3 * float(np.median(w["speeds"])) if w["speeds"] else 0.0,
        "p90 v [mm/s]": 1e3 * float(np.percentile(w["speeds"], 90)) if w["speeds"] else 0.0,
        "max delta [um]": 1e6 * w["d_peak"],
        "pairs loaded": float(np.mean(w["pairs"])) if w["pairs"] else 0.0,
    } for w in full]


def summary(rows: list[dict]) -> dict:
    return {k: float(np.mean([r[k] for r in rows])) for k in rows[0]}


def case(load_fraction: float, changes: dict, seconds: float) -> tuple[dict, float]:
    """Mean statistics of the smooth start and the largest relative difference of the kicked
    start's (in any statistic)."""
    smooth = summary(run(load_fraction, changes, 0.0, seconds))
    kicked = summary(run(load_fraction, changes, 1.0, seconds))
    spread = max(abs(kicked[k] - smooth[k]) / max(abs(smooth[k]), 1e-9) for k in smooth)
    return smooth, spread


def table(rows: list[tuple[str, dict, float]]) -> str:
    keys = list(rows[0][1])
    lines = ["| case | " + " | ".join(keys) + " | kicked vs smooth |",
             "|---" * (len(keys) + 2) + "|"]
    for name, stats, spread in rows:
        lines.append(f"| {name} | " + " | ".join(f"{stats[k]:.3g}" for k in keys)
                     + f" | {100 * spread:.1f} % |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=6.0)
    ap.add_argument("--out", type=Path, default=Path("out") / "calibration.md")
    args = ap.parse_args(argv)
    wall = time.perf_counter()
    loads = [(f"{f:g} M* = {f * M_STAR:.4g} N.m", *case(f, {}, args.seconds))
             for f in LOAD_SCAN]
    sens = [(name, *case(0.5, changes, args.seconds)) for name, changes in SENSITIVITY]
    text = (f"# Calibration: the mesh alone on the default engine orders, constant load "
            f"({args.seconds:g} s per start, 1 s transient, windows of whole forcing periods)"
            f"\n\nM* = {M_STAR:.4g} N.m\n\n## Load scan (default contact)\n\n{table(loads)}"
            f"\n## Sensitivity at 0.5 M*\n\n{table(sens)}\n"
            f"wall time {time.perf_counter() - wall:.0f} s\n")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
