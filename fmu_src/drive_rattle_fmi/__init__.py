"""The pythonfmu face of the model library, shared by the slave modules
(fmu_src/slaves/GearMeshRattle.py, fmu_src/slaves/Driveline.py): the slave classes
(registration from the specs, every FMI call forwarded to the library, the status channel of
the status shim).  Runtime: the whole package ships in each FMU (standard library and
pythonfmu only); docs/architecture.md."""

# Imported eagerly for the same reason as drive_rattle's modules (see drive_rattle/__init__.py).
from . import slave  # noqa: F401
