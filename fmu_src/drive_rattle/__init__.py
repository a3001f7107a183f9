"""The transmission drive-rattle model (Theodossiades et al., ENOC 2008) from Python: the
parameter and interface specs (the one source of every variable's name, unit and limits) and
the two units of the model library (``fmu_src/rattle_model``, C) through a thin ctypes binding.

The runtime of the pythonfmu FMUs (standard library only; the package is copied whole into
each, with the compiled library).  See docs/model.md, and docs/architecture.md for where it
sits.
"""

from . import interface, library, parameters, units  # noqa: F401
from .interface import MAX_PAIR_SLOTS
from .library import DRIVELINE, MESH, LibraryError, ModelError
from .parameters import DrivelineParameters, MeshParameters, ParameterSpec, specs
from .units import (
    DrivelineUnit,
    Event,
    MeshUnit,
    StepReport,
    Unit,
    coupled_start_inputs,
    input_starts,
)

#: The flanks: +1 drive (the pinion leads), -1 coast.
DRIVE, COAST = 1, -1

__all__ = [
    "COAST", "DRIVE", "DRIVELINE", "MAX_PAIR_SLOTS", "MESH", "DrivelineParameters",
    "DrivelineUnit", "Event", "LibraryError", "MeshParameters", "MeshUnit", "ModelError",
    "ParameterSpec", "StepReport", "Unit", "coupled_start_inputs", "input_starts", "specs",
]
