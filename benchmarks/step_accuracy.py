"""Accuracy of the coupled system against the communication step (docs/tools.md).

    python benchmarks/step_accuracy.py [--stop-time 2] [--steps 1e-5 2e-5 ... 1e-2]

Runs the default system with the in-process twin of the co-simulation
(``drive_rattle_cosim.system.simulate``: the model library's compiled loop; the FMUs in any
Jacobi master compute the same numbers) at each communication step, three times with the
phase of engine order 1 moved by 0, 1e-6 and 2e-6 rad: rattle is chaotic, so the spread of these
three runs is the scatter a statistic has at a step anyway.  Prints, per step, the mean and the
range of the rattle statistics over the three runs, or the message of the refused step.
"""

from __future__ import annotations

import argparse
import time

from drive_rattle.catalog import UNITS
from drive_rattle.parameters import DrivelineParameters, MeshParameters
from drive_rattle.units import ModelError, describe
from drive_rattle_cosim.sweep import rattle_metrics
from drive_rattle_cosim.system import simulate

SIGNALS = ["wheel.phi", "wheel.w", "mesh.W", "mesh.W_peak", "mesh.n_contact", "mesh.v_impact",
           "mesh.impacts_drive", "mesh.impacts_coast", "mesh.delta_peak"]
REPORTED = {"impacts_per_s_drive": "drive impacts/s", "impacts_per_s_coast": "coast impacts/s",
            "mean_impact_speed": "mean impact speed [m/s]", "peak_normal_force": "peak W [N]",
            "rattle_index_W": "rattle index [W]", "mean_wheel_speed": "mean wheel speed [rad/s]"}
PHASES = (0.0, 1e-6, 2e-6)
DEFAULT_STEPS = (1e-5, 2e-5, 5e-5, 1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3, 1e-2, 2e-2)


def measure(step: float, stop_time: float) -> dict:
    """``{metric: (mean, lo, hi)}`` over the phase variants, or ``{"refused": message}``."""
    normal_mass = describe(UNITS["GearMeshRattle"].kind, {})["normal_mass"]
    runs = []
    for phase in PHASES:
        dp = DrivelineParameters(phase_1=phase)
        try:
            rec = simulate(MeshParameters(), dp, stop_time=stop_time, step=step,
                           signals=SIGNALS)
        except (ValueError, ModelError) as err:
            return {"refused": str(err)}
        runs.append(rattle_metrics(rec.time, rec.signals, normal_mass))
    return {k: (sum(r[k] for r in runs) / len(runs), min(r[k] for r in runs),
                max(r[k] for r in runs)) for k in REPORTED}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--stop-time", type=float, default=2.0, help="[s]")
    ap.add_argument("--steps", type=float, nargs="+", default=list(DEFAULT_STEPS), help="[s]")
    args = ap.parse_args(argv)
    print("| step [s] | " + " | ".join(REPORTED.values()) + " |")
    print("|---" * (len(REPORTED) + 1) + "|")
    for step in args.steps:
        wall = time.perf_counter()
        m = measure(step, args.stop_time)
        if "refused" in m:
            print(f"| {step:g} | refused: {m['refused'][:120]} |")
            continue
        cells = [f"{mean:.3g} ({lo:.3g}..{hi:.3g})" for mean, lo, hi in m.values()]
        wall = time.perf_counter() - wall
        print(f"| {step:g} | " + " | ".join(cells) + f" |  <!-- {wall:.0f} s -->", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
