"""FMI layer of the drive-rattle FMUs (pythonfmu slaves, modelDescription, native status shim)."""

# Imported eagerly for the same reason as drive_rattle's modules (see drive_rattle/__init__.py).
from . import model_description, slave, units  # noqa: F401
