"""FMI glue of the drive-rattle FMUs, shared by the slaves (fmu_src/GearMeshRattle.py,
fmu_src/Driveline.py): registration from the specs, checked stepping, FMU states, the status
channel of the native shim, the modelDescription.  Runtime: the whole package ships in each FMU
(standard library and pythonfmu only); docs/architecture.md."""

# Imported eagerly for the same reason as drive_rattle's modules (see drive_rattle/__init__.py).
from . import boundary, model_description, slave, units  # noqa: F401
