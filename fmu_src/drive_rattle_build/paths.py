"""Where the build finds its sources and puts its results.

Two layouts hold the same files:

* a **source checkout** (a clone, or an editable install of one): the C sources under
  ``fmu_src/``, the templates in ``modelDescription_templates/``, the references in
  ``regression/``, the documentation in ``docs/``;
* an **installed wheel** (or sdist): the same C sources, slave modules and templates are
  package data of this package (``drive_rattle_build/sources/``, ``drive_rattle_build/
  templates/``; the references of ``drive_rattle_cosim/references/``), mapped there by
  ``[tool.setuptools.package-dir]`` in pyproject.toml. There is no ``docs/`` to regenerate,
  and the default output folder is ``./dist`` of the working directory.

The checkout layout wins where both could apply (an editable install builds from the clone).
"""

from __future__ import annotations

from pathlib import Path

_PACKAGE = Path(__file__).resolve().parent
#: The repository root of a source checkout (meaningless in an installed wheel).
ROOT = _PACKAGE.parents[1]
#: True in a source checkout, False in an installed wheel.
CHECKOUT = (ROOT / "pyproject.toml").is_file() and (ROOT / "fmu_src" / "rattle_model").is_dir()
#: The folder of the C sources and the slave modules.
SOURCE = ROOT / "fmu_src" if CHECKOUT else _PACKAGE / "sources"
#: The model library: the one C implementation of the model (rattle_model.h).
MODEL_SOURCE = SOURCE / "rattle_model"
#: The model library's test-only files: the probes of its laws at given arguments (rm_probe.h).
#: Compiled into the library built in place (what the Python API and the tests load), never into
#: a shipped FMU's binary nor its sources/.
TEST_ONLY_SOURCES = ("probe.c", "rm_probe.h")
#: What every FMI face shares, of no FMI version (rattle_fmi_common.c: instantiate's checks,
#: the resources folder, marker files, printable paths, the state envelope).
FMI_COMMON_SOURCE = SOURCE / "fmi_common"
#: The FMI 2.0 face of the native FMUs and what it shares with the pythonfmu FMUs' status shim.
FMI2_SOURCE = SOURCE / "fmi2"
#: The FMI 3.0 face of the native FMI 3.0 FMUs.
FMI3_SOURCE = SOURCE / "fmi3"
#: The slave modules of the pythonfmu FMUs (class = file stem = the FMU's model identifier).
SLAVE_SOURCE = SOURCE / "slaves"
#: The packages copied whole into every pythonfmu FMU (standard library only;
#: docs/architecture.md).
RUNTIME_PACKAGES = ("drive_rattle", "drive_rattle_fmi")
#: The committed normalised modelDescriptions (a checked output of the build).
TEMPLATES = ROOT / "modelDescription_templates" if CHECKOUT else _PACKAGE / "templates"
#: The default output folder.
DIST = ROOT / "dist" if CHECKOUT else Path("dist")
#: The documentation page whose interface tables the build generates (a checkout only).
FMI_DOCS = ROOT / "docs" / "fmi.md"
#: The tools guide, whose numbers the build computes (drive_rattle_build.tools_doc).
TOOLS_DOCS = ROOT / "docs" / "tools.md"


def runtime_package(name: str) -> Path:
    """The folder of the runtime package ``name`` (of ``RUNTIME_PACKAGES``), where it is
    imported from: ``fmu_src/<name>`` in a checkout, site-packages in a wheel."""
    import importlib

    return Path(importlib.import_module(name).__file__).resolve().parent


def model_files(pattern: str = "*.[ch]", test_only: bool = False) -> list[Path]:
    """The model library's files matching ``pattern``, sorted: those that ship
    (``TEST_ONLY_SOURCES`` left out), or all of them with ``test_only``."""
    return sorted(p for p in MODEL_SOURCE.glob(pattern)
                  if test_only or p.name not in TEST_ONLY_SOURCES)


def slave_module(model: str) -> Path:
    """The slave module of ``model`` (class = file stem = the FMU's model identifier)."""
    return SLAVE_SOURCE / f"{model}.py"
