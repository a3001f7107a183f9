"""Where the build finds its sources and puts its results (a source checkout: the build runs
from the repository, not from an installed wheel)."""

from __future__ import annotations

from pathlib import Path

#: The repository root.
ROOT = Path(__file__).resolve().parents[2]
#: The Python sources: the runtime packages, the slave modules and the C sources.
SOURCE = ROOT / "fmu_src"
#: The model library: the one C implementation of the model (rattle_model.h).
MODEL_SOURCE = SOURCE / "rattle_model"
#: The FMI 2.0 face of the native FMUs and what it shares with the pythonfmu FMUs' status shim.
FMI2_SOURCE = SOURCE / "fmi2"
#: The FMI 3.0 face of the native FMI 3.0 FMUs (it compiles fmi2/rattle_fmi_common.c too).
FMI3_SOURCE = SOURCE / "fmi3"
#: The packages copied whole into every pythonfmu FMU (standard library only;
#: docs/architecture.md).
RUNTIME_PACKAGES = ("drive_rattle", "drive_rattle_fmi")
#: The committed normalised modelDescriptions (a checked output of the build).
TEMPLATES = ROOT / "modelDescription_templates"
#: The default output folder.
DIST = ROOT / "dist"
#: The documentation page whose interface tables the build generates.
FMI_DOCS = ROOT / "docs" / "fmi.md"
#: The tools guide, whose numbers the build computes (drive_rattle_cosim.tools_doc).
TOOLS_DOCS = ROOT / "docs" / "tools.md"


def slave_module(model: str) -> Path:
    """The slave module of ``model`` (class = file stem = the FMU's model identifier)."""
    return SOURCE / f"{model}.py"
