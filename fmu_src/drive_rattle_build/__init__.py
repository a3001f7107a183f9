"""The build of the drive-rattle FMUs: from the runtime packages, the slave modules and the C
sources to ``dist/GearMeshRattle.fmu``, ``dist/Driveline.fmu``, ``dist/DriveRattle.ssp`` and
``dist/DriveRattle_outputs.ssp``.

Needs a source checkout (it reads ``fmu_src/`` and ``regression/``), pythonfmu, fmpy and a C
compiler (``compiler.c_compiler``).  Command line: ``drive-rattle-build`` (or ``python
build_fmu.py`` in the clone); from Python::

    from drive_rattle_build import build_fmus
    fmus = build_fmus("dist")        # {"GearMeshRattle": Path, "Driveline": Path}

Modules, one job each: ``paths`` (where sources and results are), ``compiler`` (the C
compiler), ``kernel`` (the kernel's layout header and library), ``shim`` (the native status
shim), ``documentation`` (the interface pages and tables), ``templates`` (the interface
check), ``fmu`` (packaging and validation), ``system`` (the SSP files), ``cli``.
"""

from .compiler import BuildError, c_compiler
from .fmu import build, build_fmus, build_one, package, validate
from .system import write_system, write_systems

__all__ = ["BuildError", "build", "build_fmus", "build_one", "c_compiler", "package",
           "validate", "write_system", "write_systems"]
