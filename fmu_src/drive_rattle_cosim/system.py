"""The mesh and the driveline coupled in one process, with the same fixed-step coupling as the
FMU co-simulation (Jacobi: every unit steps from the outputs of the last communication point).

This is the in-process twin of the FMU co-simulation: the two units of the model library
coupled in the library's compiled loop (``units.run_coupled``) through the same calls the FMUs
make, so the co-simulation harness must reproduce it bit for bit, which tests the FMI layers
without any tolerance.  The twin also records the located contact onsets the FMUs do not
output.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from drive_rattle.interface import (
    DRIVELINE,
    DRIVELINE_OUTPUTS,
    MESH,
    MESH_INPUTS,
    MESH_OUTPUTS,
)
from drive_rattle.parameters import DrivelineParameters, MeshParameters
from drive_rattle.units import DrivelineUnit, MeshUnit, coupled_start_inputs, run_coupled

#: Signals recorded by :func:`simulate`, with units: the units' public inputs and outputs.
SIGNALS = {
    spec.name: spec.unit
    for spec in (*DRIVELINE_OUTPUTS, *MESH_INPUTS, *MESH_OUTPUTS)
}


@dataclass
class Record:
    """Time series of a run: ``time`` [s] and one list per signal (SI units)."""

    time: list[float] = field(default_factory=list)
    signals: dict[str, list[float]] = field(default_factory=dict)
    onset_times: list[float] = field(default_factory=list)  # [s]
    onset_speeds: list[float] = field(default_factory=list)  # [m/s]
    onset_flanks: list[int] = field(default_factory=list)


def step_nanoseconds(step: float) -> int:
    """The communication step ``step`` [s] in whole nanoseconds, or ValueError for a step that
    is not a positive whole number of nanoseconds (within 1e-6 of one)."""
    step_ns = round(step * 1e9) if math.isfinite(step) else 0
    if step_ns <= 0 or abs(step_ns - step * 1e9) > 1e-6 * step * 1e9:
        raise ValueError(
            f"communication step {step!r} s must be a positive whole number of nanoseconds")
    return step_ns


def communication_points(start: float, step: float, stop: float) -> list[float]:
    """Communication points ``t_k = (t0_ns + k step_ns) / 1e9`` from ``start`` to ``stop`` [s].

    Integer nanoseconds, as libcosim places them; the step from t_k is ``t_{k+1} - t_k``, so
    every master using this grid passes bit-identical times and steps to the units.  Raises
    ValueError for a step that is not a positive whole number of nanoseconds."""
    step_ns = step_nanoseconds(step)
    t0_ns = round(start * 1e9)
    n = round((stop - start) * 1e9 / step_ns)
    return [(t0_ns + k * step_ns) / 1e9 for k in range(n + 1)]


def simulate(mesh_params: MeshParameters | None = None,
             driveline_params: DrivelineParameters | None = None,
             stop_time: float = 0.1, step: float = 1e-4, start_time: float = 0.0,
             signals=None) -> Record:
    """Co-simulate mesh and driveline from ``start_time`` to ``stop_time`` [s] with the
    communication step ``step`` [s] (a whole number of nanoseconds); record ``signals`` (public
    names; default all) at every point, and the contact onsets.  The loop runs in the library
    (``units.run_coupled``)."""
    mp = mesh_params or MeshParameters()
    dp = driveline_params or DrivelineParameters()
    names = list(SIGNALS) if signals is None else list(signals)
    points = communication_points(start_time, step, stop_time)
    # initialization as the co-simulation masters reach it: the exchange of the units' initial
    # outputs run to its fixed point (the FMUs' input start values for the default system)
    mesh_in, wheel = coupled_start_inputs(mp, dp, start_time)
    with MeshUnit(mp, mesh_in["pinion.phi"], mesh_in["pinion.w"], mesh_in["wheel.tau_load"],
                  mesh_in["pinion.a"], start_time=start_time) as mesh, \
            DrivelineUnit(dp, wheel["wheel.phi"], wheel["wheel.w"],
                          start_time=start_time) as drive:
        # a mesh input is recorded as the driveline output that feeds it
        sources = {name: _source(name, mesh, drive) for name in names}
        run = run_coupled(mesh, drive, round(step * 1e9), len(points) - 1,
                          sorted(set(sources.values())))
    integers = {s.name for s in MESH_OUTPUTS if s.fmi_type == "Integer"}
    rec = Record(time=points, onset_times=run.onset_times, onset_speeds=run.onset_speeds,
                 onset_flanks=run.onset_flanks)
    for name in names:
        column = run.columns[sources[name]]
        rec.signals[name] = [int(v) for v in column] if name in integers else column
    return rec


def _source(name: str, mesh, drive) -> str:
    """The recorded variable that gives signal ``name``: an output of either unit."""
    if name in mesh.variables and mesh.variables[name].causality == "output":
        return f"{MESH}.{name}"
    if name in drive.variables and drive.variables[name].causality == "output":
        return f"{DRIVELINE}.{name}"
    raise KeyError(f"signal {name!r} is no output of {MESH} or {DRIVELINE}")
