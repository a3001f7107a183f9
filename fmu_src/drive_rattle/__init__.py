"""Physics core of the transmission drive-rattle model (Theodossiades et al., ENOC 2008): the
runtime that ships inside the FMUs (the whole package is copied into each; standard library
only).

Pure Python on plain SI floats; knows nothing of FMI.  See docs/model.md, and
docs/architecture.md for where it sits.
"""

# Every module is imported here, eagerly: all pythonfmu FMUs of a process share one
# interpreter, and a host that unpacks one of our FMUs, runs it and deletes its folder (fmpy's
# simulate_fmu does) would otherwise leave a package whose remaining submodules cannot be found
# when the other FMU is instantiated.
from . import (  # noqa: F401
    driveline,
    hertz,
    interface,
    kernel,
    kernel_layout,
    lubrication,
    roots,
    snapshots,
)
from .driveline import DrivelineModel, DrivelineParameters
from .geometry import COAST, DRIVE, MAX_PAIR_SLOTS, HelicalPairGeometry
from .mesh import MeshLoads, MeshModel, PairLoad
from .parameters import MeshParameters, ParameterSpec, specs
from .stepper import (
    ContactEvent,
    PinionState,
    StepResult,
    WheelSnapshot,
    WheelState,
    WheelStepper,
    WheelStepperBase,
)

__all__ = [
    "COAST", "DRIVE", "MAX_PAIR_SLOTS", "ContactEvent", "DrivelineModel", "DrivelineParameters",
    "HelicalPairGeometry", "MeshLoads", "MeshModel", "MeshParameters", "PairLoad",
    "ParameterSpec", "PinionState", "StepResult", "WheelSnapshot", "WheelState", "WheelStepper",
    "WheelStepperBase", "specs",
]
