"""Every unit of the system with its specs, declared once: the model identifier (the FMU's), the
model library's unit kind, the parameter class, the inputs and outputs, and the descriptions
the FMUs carry.  The slaves, the modelDescription of both flavours, the documentation and the
studies take a unit's specs from here."""

from __future__ import annotations

from dataclasses import dataclass

from . import interface, library
from .parameters import DrivelineParameters, MeshParameters


@dataclass(frozen=True)
class UnitSpec:
    """One unit of the system."""

    model: str  # model identifier of its FMUs (interface.MODELS)
    kind: int  # the model library's unit kind (library.MESH, library.DRIVELINE)
    parameters: type  # its parameter class (drive_rattle.parameters)
    inputs: tuple  # its inputs' SignalSpecs (drive_rattle.interface)
    outputs: tuple  # its outputs' SignalSpecs
    description: str  # one sentence: the modelDescription's description
    summary: str  # what goes in and out, for documentation


UNITS: dict[str, UnitSpec] = {
    interface.MESH: UnitSpec(
        interface.MESH, library.MESH, MeshParameters, interface.MESH_INPUTS,
        interface.MESH_OUTPUTS,
        "Transmission drive rattle: gear-mesh impact (Hertz, every tooth pair, both flanks) and "
        "flank friction of a helical pair with backlash; kinematic pinion, wheel integrated "
        "inside (Theodossiades, Rahnejat, De la Cruz, Kelly, ENOC 2008)",
        "Helical gear mesh with backlash: Hertzian impacts of every tooth pair on both flanks "
        "and mixed boundary/viscous flank friction; pinion kinematics in, wheel motion and "
        "torques out."),
    interface.DRIVELINE: UnitSpec(
        interface.DRIVELINE, library.DRIVELINE, DrivelineParameters,
        interface.DRIVELINE_INPUTS, interface.DRIVELINE_OUTPUTS,
        "Driveline around the drive-rattle gear mesh: input-shaft kinematics from engine orders "
        "or a measured speed table, output shaft as a torsional spring-damper to a reflected "
        "vehicle inertia with drag",
        "Engine-order (or measured) pinion kinematics out; wheel angle and speed in, "
        "output-shaft load torque out."),
}
if tuple(UNITS) != interface.MODELS:
    raise ImportError("catalog.UNITS must list interface.MODELS in order")
