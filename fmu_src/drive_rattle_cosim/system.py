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

import numpy as np

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


def _empty(dtype=float) -> np.ndarray:
    return np.zeros(0, dtype=dtype)


@dataclass
class Record:
    """Time series of a run, as numpy arrays: ``time`` [s] and one array per signal (SI units;
    the integer outputs as int64), and the contact onsets (time [s], normal approach speed
    [m/s], flank: +1 drive, -1 coast)."""

    time: np.ndarray = field(default_factory=_empty)
    signals: dict[str, np.ndarray] = field(default_factory=dict)
    onset_times: np.ndarray = field(default_factory=_empty)  # [s]
    onset_speeds: np.ndarray = field(default_factory=_empty)  # [m/s]
    onset_flanks: np.ndarray = field(default_factory=lambda: _empty(np.int64))


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
    return _seconds(*_grid(start, step, stop)).tolist()


def _grid(start: float, step: float, stop: float) -> tuple[int, int, int]:
    """(t0 [ns], step [ns], steps) of the communication points from ``start`` to ``stop``."""
    step_ns = step_nanoseconds(step)
    return round(start * 1e9), step_ns, round((stop - start) * 1e9 / step_ns)


def _seconds(t0_ns: int, step_ns: int, steps: int) -> np.ndarray:
    """The points (t0_ns + k step_ns) / 1e9 [s], k = 0..steps: whole nanoseconds, exact in
    int64, then one correctly rounded division each."""
    return (t0_ns + step_ns * np.arange(steps + 1, dtype=np.int64)) / 1e9


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
    t0_ns, step_ns, steps = _grid(start_time, step, stop_time)
    # initialization as the co-simulation masters reach it: the exchange of the units' initial
    # outputs run to its fixed point (the FMUs' input start values for the default system)
    mesh_in, wheel = coupled_start_inputs(mp, dp, start_time)
    with MeshUnit(mp, mesh_in["pinion.phi"], mesh_in["pinion.w"], mesh_in["wheel.tau_load"],
                  mesh_in["pinion.a"], start_time=start_time) as mesh, \
            DrivelineUnit(dp, wheel["wheel.phi"], wheel["wheel.w"],
                          start_time=start_time) as drive:
        # a mesh input is recorded as the driveline output that feeds it
        sources = {name: _source(name, mesh, drive) for name in names}
        run = run_coupled(mesh, drive, step_ns, steps, sorted(set(sources.values())))
    integers = {s.name for s in MESH_OUTPUTS if s.fmi_type == "Integer"}
    rec = Record(time=_seconds(t0_ns, step_ns, steps),
                 onset_times=np.array(run.onset_times, dtype=float),
                 onset_speeds=np.array(run.onset_speeds, dtype=float),
                 onset_flanks=np.array(run.onset_flanks, dtype=np.int64))
    for name in names:
        # a copy (the run's buffer goes with it), the integer outputs as integers
        rec.signals[name] = np.array(run.column_buffer(sources[name]),
                                     dtype=np.int64 if name in integers else float)
    return rec


def _source(name: str, mesh, drive) -> str:
    """The recorded variable that gives signal ``name``: an output of either unit."""
    if name in mesh.variables and mesh.variables[name].causality == "output":
        return f"{MESH}.{name}"
    if name in drive.variables and drive.variables[name].causality == "output":
        return f"{DRIVELINE}.{name}"
    raise KeyError(f"signal {name!r} is no output of {MESH} or {DRIVELINE}")
