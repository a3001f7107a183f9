"""Physics core of the transmission drive-rattle model (Theodossiades et al., ENOC 2008).

Pure Python on plain SI floats; knows nothing of FMI.  See docs/model.md.
"""

# Every module the FMUs run is imported here, eagerly: all pythonfmu FMUs of a process share one
# interpreter, and a host that unpacks one of our FMUs, runs it and deletes its folder (fmpy's
# simulate_fmu does) would otherwise leave a package whose remaining submodules cannot be found
# when the other FMU is instantiated.
from . import driveline, interface, kernel, lubrication, roots  # noqa: F401
from .geometry import COAST, DRIVE, HelicalPairGeometry
from .mesh import MeshLoads, MeshModel, PairLoad
from .parameters import MAX_PAIR_SLOTS, MeshParameters, ParameterSpec, specs
from .stepper import ContactEvent, StepResult, WheelState, WheelStepper

__all__ = [
    "COAST", "DRIVE", "MAX_PAIR_SLOTS", "ContactEvent", "HelicalPairGeometry", "MeshLoads",
    "MeshModel", "MeshParameters", "PairLoad", "ParameterSpec", "StepResult", "WheelState",
    "WheelStepper", "specs",
]
