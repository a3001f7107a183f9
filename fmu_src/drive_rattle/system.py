"""The mesh and the driveline coupled in one process, with the same fixed-step coupling as the
FMU co-simulation (Jacobi: every unit steps from the outputs of the last communication point).

This is the in-process twin of the FMU co-simulation: the co-simulation harness must reproduce
it bit for bit, which tests the FMI layer without any tolerance.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .driveline import Driveline, DrivelineParameters
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


def simulate(mesh_params: MeshParameters | None = None,
             driveline_params: DrivelineParameters | None = None,
             stop_time: float = 0.1, step: float = 1e-4, start_time: float = 0.0,
             signals=None) -> Record:
    """Co-simulate mesh and driveline from ``start_time`` to ``stop_time`` [s] with the
    communication step ``step`` [s]; record ``signals`` (default all) at every point."""
    mp = mesh_params or MeshParameters()
    dp = driveline_params or DrivelineParameters()
    names = list(SIGNALS) if signals is None else list(signals)
    # Initialisation in the order the co-simulation master uses: the driveline's initial
    # outputs (its wheel inputs still at their start values 0), the mesh's equilibrium under
    # its load torque, then the driveline built behind the mesh's initial wheel state.
    first = Driveline(dp, start_time, 0.0, 0.0).outputs()
    mesh = WheelStepper(mp, first["pinion.phi"], first["pinion.w"], first["wheel.tau_load"])
    drive = Driveline(dp, start_time, mesh.state.phi, mesh.state.w)
    rec = Record(signals={n: [] for n in names})
    n_steps = round((stop_time - start_time) / step)
    for k in range(n_steps + 1):
        t = start_time + k * step
        d = drive.outputs()
        _record(rec, t, names, d, mesh)
        if k == n_steps:
            break
        wheel_phi, wheel_w = mesh.state.phi, mesh.state.w
        result = mesh.step(step, d["pinion.phi"], d["pinion.w"], d["pinion.a"],
                           d["wheel.tau_load"])
        for ev in result.events:
            if ev.kind == "onset":
                rec.onset_times.append(t + ev.time)
                rec.onset_speeds.append(ev.speed)
                rec.onset_flanks.append(ev.flank)
        drive.step(t, step, wheel_phi, wheel_w)
    return rec


def _record(rec: Record, t: float, names, driveline_outputs: dict,
            mesh: WheelStepper) -> None:
    rec.time.append(t)
    values = {**mesh_outputs(mesh), **driveline_outputs}
    for n in names:
        rec.signals[n].append(values[n])
