"""The mesh and the driveline coupled in one process, with the same fixed-step coupling as the
FMU co-simulation (Jacobi: every unit steps from the outputs of the last communication point).

This is the in-process twin of the FMU co-simulation: the co-simulation harness must reproduce
it bit for bit, which tests the FMI layer without any tolerance.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from .driveline import (
    DrivelineParameters,
    EngineOrderKinematics,
    OutputShaft,
    SpeedTableKinematics,
)
from .interface import DRIVELINE_OUTPUTS, MESH_INPUTS, MESH_OUTPUTS, mesh_outputs
from .parameters import MeshParameters
from .stepper import WheelStepper

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


def input_kinematics(p: DrivelineParameters, t_start: float = 0.0, resources: Path | None = None):
    """The input-shaft kinematics the parameters select: a speed table or engine orders."""
    if p.speed_table:
        path = Path(p.speed_table)
        if not path.is_absolute() and resources is not None and (resources / path).exists():
            path = resources / path
        return SpeedTableKinematics(path, p.phi_start)
    return EngineOrderKinematics(p, t_start)


def simulate(mesh_params: MeshParameters | None = None,
             driveline_params: DrivelineParameters | None = None,
             stop_time: float = 0.1, step: float = 1e-4, start_time: float = 0.0,
             signals=None) -> Record:
    """Co-simulate mesh and driveline from ``start_time`` to ``stop_time`` [s] with the
    communication step ``step`` [s]; record ``signals`` (default all) at every point."""
    mp = mesh_params or MeshParameters()
    dp = driveline_params or DrivelineParameters()
    names = list(SIGNALS) if signals is None else list(signals)
    kin = input_kinematics(dp, start_time)
    phi_p, w_p, a_p = kin(start_time)
    # Initialisation in the order the co-simulation master uses: the driveline's initial
    # load (its wheel inputs still at their start values), then the mesh's equilibrium under
    # it, then the driveline's shaft set in steady state behind the wheel.
    mesh = WheelStepper(mp, phi_p, w_p, OutputShaft(dp, 0.0, 0.0).tau_load)
    shaft = OutputShaft(dp, mesh.state.phi, mesh.state.w)
    rec = Record(signals={n: [] for n in names})
    n_steps = round((stop_time - start_time) / step)
    for k in range(n_steps + 1):
        t = start_time + k * step
        _record(rec, t, names, (phi_p, w_p, a_p), shaft, mesh)
        if k == n_steps:
            break
        wheel_phi, wheel_w = mesh.state.phi, mesh.state.w
        result = mesh.step(step, phi_p, w_p, a_p, shaft.tau_load)
        for ev in result.events:
            if ev.kind == "onset":
                rec.onset_times.append(t + ev.time)
                rec.onset_speeds.append(ev.speed)
                rec.onset_flanks.append(ev.flank)
        shaft.step(step, wheel_phi, wheel_w)
        phi_p, w_p, a_p = kin(start_time + (k + 1) * step)
    return rec


def _record(rec: Record, t: float, names, pinion, shaft: OutputShaft,
            mesh: WheelStepper) -> None:
    rec.time.append(t)
    values = mesh_outputs(mesh)
    values.update({"pinion.phi": pinion[0], "pinion.w": pinion[1], "pinion.a": pinion[2],
                   "wheel.tau_load": shaft.tau_load, "vehicle.w": shaft.state.w})
    for n in names:
        rec.signals[n].append(values[n])


