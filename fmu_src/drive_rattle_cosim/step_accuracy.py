"""Accuracy of the coupled system against the communication step (docs/tools.md).

The default system runs in the in-process twin of the co-simulation
(``drive_rattle_cosim.system.simulate``: the model library's compiled loop; the FMUs in any
Jacobi master compute the same numbers) at each communication step, three times with the phase
of engine order 1 moved by 0, 1e-6 and 2e-6 rad: rattle is chaotic, so the spread of these
three runs is the scatter a statistic has at a step anyway.  ``benchmarks/step_accuracy.py``
prints the table; ``python build_fmu.py --update-docs`` writes it into docs/tools.md.
"""

from __future__ import annotations

import functools

from drive_rattle.catalog import UNITS
from drive_rattle.parameters import DrivelineParameters, MeshParameters
from drive_rattle.units import ModelError, describe

from .sweep import rattle_metrics
from .system import simulate

SIGNALS = ["wheel.phi", "wheel.w", "mesh.W", "mesh.W_peak", "mesh.n_contact", "mesh.v_impact",
           "mesh.impacts_drive", "mesh.impacts_coast", "mesh.delta_peak"]
#: The statistics of the table: ``rattle_metrics`` key -> column head.
REPORTED = {"impacts_per_s_drive": "drive impacts/s", "impacts_per_s_coast": "coast impacts/s",
            "mean_impact_speed": "mean impact speed [m/s]", "peak_normal_force": "peak W [N]",
            "rattle_index_W": "rattle index [W]", "mean_wheel_speed": "mean wheel speed [rad/s]"}
PHASES = (0.0, 1e-6, 2e-6)
STEPS = (1e-5, 2e-5, 5e-5, 1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3, 1e-2, 2e-2)
STOP_TIME = 2.0


@functools.cache
def measure(step: float, stop_time: float = STOP_TIME) -> dict:
    """``{metric: (mean, lo, hi)}`` over the phase variants, or ``{"refused": message}``
    (cached: the runs are deterministic; do not change the dictionary)."""
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


def refusal_reason(message: str) -> str:
    """The unit's reason in a refused coupled run's message (without where it happened)."""
    return message.rpartition("doStep: ")[2] or message


def table(steps=STEPS, stop_time: float = STOP_TIME) -> str:
    """The Markdown table: per step the mean and (range) of each statistic, the largest
    relative change of a mean against the finest step's, or the start of the refusal."""
    head = ("| step [s] | " + " | ".join(REPORTED.values())
            + " | largest change against the finest step |\n")
    lines = [head, "|---" * (len(REPORTED) + 2) + "|\n"]
    finest = None
    for step in sorted(steps):
        m = measure(step, stop_time)
        if "refused" in m:
            reason = refusal_reason(m["refused"])
            lines.append(f"| {step:g} | refused: `{reason[:72]}...` |" + " |" * len(REPORTED)
                         + "\n")
            continue
        finest = finest or m
        cells = [f"{mean:.3g} ({lo:.3g}..{hi:.3g})" for mean, lo, hi in m.values()]
        change = max(((abs(m[k][0] - finest[k][0]) / abs(finest[k][0]), k) for k in REPORTED
                      if finest[k][0]), default=(0.0, ""))
        cells.append("—" if m is finest else f"{100 * change[0]:.0f} % ({REPORTED[change[1]]})")
        lines.append(f"| {step:g} | " + " | ".join(cells) + " |\n")
    return "".join(lines)
