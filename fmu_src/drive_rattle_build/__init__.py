"""The build of the drive-rattle FMUs: from the specs, the model library's C sources, the
runtime packages and the slave modules to ``dist/GearMeshRattle.fmu``, ``dist/Driveline.fmu``,
``dist/DriveRattle.ssp`` (with ``dist/DriveRattle_outputs.ssp``: every output a system output;
both bundle the FMUs with the integer codes declared Integers, for libcosim and ecos), the
native FMUs in ``dist/native/`` and the FMI 3.0 FMUs in ``dist/fmi3/``.

Needs a source checkout (it reads ``fmu_src/`` and ``regression/``), pythonfmu, fmpy and a C
compiler (``compiler.c_compiler``).  Command line: ``drive-rattle-build`` (or ``python
build_fmu.py`` in the clone); from Python::

    from drive_rattle_build import build_fmus
    fmus = build_fmus("dist")        # {"GearMeshRattle": Path, "Driveline": Path}

Modules, one job each: ``paths`` (where sources and results are), ``compiler`` (the C
compiler), ``model_tables`` (the library's tables from the specs), ``library`` (the model
library), ``shim`` (the pythonfmu FMUs' status shim), ``documentation`` (the interface pages
and tables), ``templates`` (the interface check), ``fmu`` (packaging and validation),
``native`` (the native FMUs), ``fmi3`` and ``model_description_fmi3`` (the FMI 3.0 FMUs),
``terminals`` (their terminals and icon), ``platforms`` (the binaries' platforms, a binary
compiled into a finished FMU), ``icon`` (the images), ``system`` (the SSP files), ``cli``.
The names below are imported on first use, so that building the library alone needs none of
the rest.
"""

from importlib import import_module

_EXPORTS = {"BuildError": "compiler", "c_compiler": "compiler", "build": "fmu",
            "build_fmus": "fmu", "build_one": "fmu", "package": "fmu", "validate": "fmu",
            "write_system": "system", "write_systems": "system",
            "build_in_place": "library", "build_fmi3": "fmi3"}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'drive_rattle_build' has no attribute {name!r}")
    return getattr(import_module(f".{module}", __name__), name)
