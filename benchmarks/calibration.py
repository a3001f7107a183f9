"""The evidence behind the default contact and drag (docs/model.md section 6): the paper's model
-- the pinion from the default engine orders, the wheel under a constant load M_res
(``vehicle.model`` = 1) -- scanned over the load relative to M*, and the sensitivity of its
statistics to the contact's parameters.

    python benchmarks/calibration.py [--seconds 20] [--max-seconds 60] [--workers 2]
                                     [--out out/calibration.md]

Each case runs the smooth start (static flank equilibrium) and the kicked start (-1 rad/s on
the wheel) in the model library's compiled coupled loop for ``--seconds``, and on until settled
or ``--max-seconds`` (drive_rattle_cosim.multistability.run_start: windows of whole forcing
periods, the start transient detected and dropped), and reports the smooth start's statistics
after its transient -- onsets per second on each flank, the 10/50/90th percentile of the drive
flank's onset speeds, the largest penetration and the pairs in contact, mean over the windows
-- and whether the kicked start reached the same attractor.  The full grid of starts and
backlashes is ``python -m drive_rattle_cosim.multistability``.
"""

from __future__ import annotations

import argparse
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace
from pathlib import Path

from drive_rattle import DrivelineParameters, MeshParameters
from drive_rattle_cosim import multistability as ms

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
COLUMNS = (("drive [1/s]", "drive_rate", 1.0), ("coast [1/s]", "coast_rate", 1.0),
           ("drive v p10 / p50 / p90 [mm/s]", ("drive_p10", "drive_p50", "drive_p90"), 1e3),
           ("max delta [um]", "delta_max", 1e6), ("pairs loaded", "pairs", 1.0))


def case(load_fraction: float, changes: dict, seconds: float, cap: float
         ) -> tuple[dict, str]:
    """The smooth start's statistics and the kicked start's verdict."""
    mesh = replace(MeshParameters(), **changes)
    drive = ms.paper_driveline(load_fraction * ms.separation_load(mesh, DrivelineParameters()))
    runs = [ms.run_start(mesh, drive, ms.STARTS_BY_KEY[k], min_time=seconds,
                         max_time=max(cap, seconds)) for k in ("smooth", "kick-1")]
    smooth = {name: runs[0].mean(name) for name in ms.STATISTICS}
    if not all(r.settled for r in runs):
        verdict = "unsettled"
    else:
        verdict = "same" if ms.same_attractor(*runs) else (
            f"other: {runs[1].mean('drive_rate'):.4g} / {runs[1].mean('coast_rate'):.4g} "
            f"onsets/s, {runs[1].mean('delta_max') * 1e6:.4g} um")
    return smooth, verdict


def table(rows: list[tuple[str, dict, str]]) -> str:
    lines = ["| case | " + " | ".join(c[0] for c in COLUMNS) + " | kicked start |",
             "|---" * (len(COLUMNS) + 2) + "|"]
    for name, stats, verdict in rows:
        cells = []
        for _, key, factor in COLUMNS:
            keys = key if isinstance(key, tuple) else (key,)
            cells.append(" / ".join(f"{stats[k] * factor:.3g}" for k in keys))
        lines.append(f"| {name} | " + " | ".join(cells) + f" | {verdict} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=20.0, help="shortest run [s]")
    ap.add_argument("--max-seconds", type=float, default=60.0, help="longest run [s]")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", type=Path, default=Path("out") / "calibration.md")
    args = ap.parse_args(argv)
    wall = time.perf_counter()
    m_star = ms.separation_load()
    jobs = [(f"{f:g} M* = {f * m_star:.4g} N.m", f, {}) for f in LOAD_SCAN]
    jobs += [(name, 0.5, changes) for name, changes in SENSITIVITY]
    with ThreadPoolExecutor(max_workers=max(1, args.workers)) as pool:
        done = list(pool.map(lambda j: case(j[1], j[2], args.seconds, args.max_seconds),
                             jobs))
    rows = [(name, *result) for (name, _, _), result in zip(jobs, done, strict=True)]
    n = len(LOAD_SCAN)
    text = (f"# Calibration: the paper's model (constant load) on the default engine orders "
            f"({args.seconds:g}-{args.max_seconds:g} s per start, the start transient dropped, "
            f"windows of whole "
            f"forcing periods)\n\nM* = {m_star:.4g} N.m\n\n## Load scan (default contact)\n\n"
            f"{table(rows[:n])}\n## Sensitivity at 0.5 M*\n\n{table(rows[n:])}\n"
            f"wall time {time.perf_counter() - wall:.0f} s\n")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text, encoding="utf-8")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
