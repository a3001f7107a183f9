"""Physics core of the transmission drive-rattle model (Theodossiades et al., ENOC 2008).

Pure Python on plain SI floats; knows nothing of FMI.  See docs/model.md.
"""

from .geometry import COAST, DRIVE, HelicalPairGeometry
from .mesh import MeshLoads, MeshModel, PairLoad
from .parameters import MAX_PAIR_SLOTS, MeshParameters, ParameterSpec, specs
from .stepper import ContactEvent, StepResult, WheelState, WheelStepper

__all__ = [
    "COAST", "DRIVE", "MAX_PAIR_SLOTS", "ContactEvent", "HelicalPairGeometry", "MeshLoads",
    "MeshModel", "MeshParameters", "PairLoad", "ParameterSpec", "StepResult", "WheelState",
    "WheelStepper", "specs",
]
