"""Which phase starts reach the periodic orbit at 0.4 M* and 0.2 mm, per engine and per last bit
(docs/analysis.md section 7, docs/model.md section 6.2).

At that point of the paper's model (default physics with rigid teeth, ``tooth.compliance`` = 0,
where it was found) a periodic orbit -- one impact per flank and forcing period -- coexists with
the chaotic rattle, and its basin is small.  ``--teeth compliant`` runs today's default (the
teeth's compliance in series with the contact) instead.  This runs the
smooth start at N - 1 phases of the forcing cycle (``multistability.phase_starts``) for a fixed
time in each variant and reports the phases whose run is in the orbit at its end (exactly one
drive and one coast onset in each of the last ``--periods`` forcing periods):

* ``library``: the model library's compiled loop (the study's default engine);
* ``fmu``: the FMUs of ``--fmu-dir`` in the harness (FMI 2.0 or 3.0), the same arithmetic;
* ``fmu-accumulated``: the same FMUs on the points of a master that accumulates its time,
  ``t += h`` (ecos, fmpy's SSP runner): step sizes and times that differ in the last bits;
* ``angle+1ulp``, ``angle-1ulp``: the library with each start's pinion start angle
  (``pinion.phi_start``) moved by one unit in the last place.

    python benchmarks/orbit_reach.py [--fmu-dir dist/fmi3] [--phases 24] [--seconds 60]
        [--select 11,12] [--variants library,fmu,...] [--teeth rigid|compliant] [--workers 2]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path

import numpy as np

from drive_rattle import DrivelineParameters, MeshParameters
from drive_rattle_cosim import multistability as ms

LOAD, BACKLASH, STEP = 0.4, 0.2e-3, 1e-4
VARIANTS = ("library", "fmu", "fmu-accumulated", "angle+1ulp", "angle-1ulp")
#: ``tooth.compliance`` per ``--teeth``
TEETH = {"rigid": 0, "compliant": 1}


def point(teeth: str = "rigid") -> tuple[MeshParameters, DrivelineParameters]:
    mesh = replace(MeshParameters(), backlash=BACKLASH, tooth_compliance=TEETH[teeth])
    drive = DrivelineParameters()
    return mesh, ms.paper_driveline(LOAD * ms.separation_load(mesh, drive), drive)


def final_onsets(job) -> tuple[str, int, int, int]:
    """``(variant, k, drive onsets, coast onsets)`` in the last ``periods`` forcing periods of
    the run of phase start k/n for ``seconds``."""
    variant, k, n, seconds, periods, fmu_dir, teeth = job
    mesh, drive = ms.start_parameters(*point(teeth), ms.Start(f"phase {k}/{n}", phase=k / n))
    if variant.startswith("angle"):
        drive = replace(drive, phi_start=math.nextafter(
            drive.phi_start, math.inf if variant == "angle+1ulp" else -math.inf))
    if variant.startswith("fmu"):
        grid = "accumulated" if variant == "fmu-accumulated" else "nanoseconds"
        engine = ms.FmuEngine(mesh, drive, STEP, fmu_dir, grid)
    else:
        engine = ms.LibraryEngine(mesh, drive, STEP)
    try:
        chunk = engine.advance(round(seconds / STEP))
    finally:
        engine.close()
    end = float(chunk.time[-1])
    t, flanks = np.asarray(chunk.onset_times), np.asarray(chunk.onset_flanks)
    last = t > end - periods * ms.forcing_period(mesh, drive)
    return (variant, k, int(np.sum(last & (flanks == ms.DRIVE))),
            int(np.sum(last & (flanks == ms.COAST))))


def reach(variants, phases: int, seconds: float, periods: int, fmu_dir: Path | None,
          select=None, workers: int = 2, teeth: str = "rigid") -> dict[str, list[int]]:
    """``{variant: [k, ...]}``: the phases k/phases whose run ends in the orbit."""
    ks = list(select or range(1, phases))
    jobs = [(v, k, phases, seconds, periods, fmu_dir, teeth) for v in variants for k in ks]
    with ProcessPoolExecutor(max_workers=max(1, workers)) as pool:
        results = list(pool.map(final_onsets, jobs))
    return {v: [k for w, k, d, c in results if w == v and d == c == periods] for v in variants}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fmu-dir", type=Path, default=Path("dist") / "fmi3")
    ap.add_argument("--phases", type=int, default=24)
    ap.add_argument("--seconds", type=float, default=60.0, help="each run [s]")
    ap.add_argument("--periods", type=int, default=20,
                    help="the orbit: one onset per flank in each of the last PERIODS periods")
    ap.add_argument("--select", default="", help="only these phases k (comma-separated)")
    ap.add_argument("--variants", default=",".join(VARIANTS))
    ap.add_argument("--teeth", choices=tuple(TEETH), default="rigid",
                    help="tooth.compliance: rigid (0, where the orbit was found) or compliant "
                         "(1, today's default)")
    ap.add_argument("--workers", type=int, default=2, help="processes")
    args = ap.parse_args(argv)
    variants = [v.strip() for v in args.variants.split(",")]
    unknown = [v for v in variants if v not in VARIANTS]
    if unknown:
        ap.error(f"--variants: unknown {unknown[0]!r}; allowed: {', '.join(VARIANTS)}")
    select = [int(k) for k in args.select.split(",") if k.strip()]
    wall = time.perf_counter()
    found = reach(variants, args.phases, args.seconds, args.periods, args.fmu_dir, select,
                  args.workers, args.teeth)
    tried = len(select) if select else args.phases - 1
    print(f"| variant ({args.teeth} teeth) | phase starts k/{args.phases} in the orbit after "
          f"{args.seconds:g} s | of |")
    print("|---|---|---|")
    for v, ks in found.items():
        print(f"| {v} | {', '.join(map(str, ks)) or 'none'} | {len(ks)} of {tried} |")
    print(f"({time.perf_counter() - wall:.0f} s)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
