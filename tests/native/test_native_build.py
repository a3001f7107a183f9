"""The native FMI 2.0 FMUs as the build makes them: an interface rendered from the specs and
held against the committed templates, and a GUID derived from the sources (what every face's
FMUs ship, their validation and their binaries' exports: tests/faces)."""

from __future__ import annotations

import re
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import pytest

from drive_rattle.interface import MODELS
from drive_rattle_build.native import (
    interface_diff,
    native_guid,
)


def description(fmu: Path) -> ElementTree.Element:
    with zipfile.ZipFile(fmu) as z:
        return ElementTree.fromstring(z.read("modelDescription.xml"))


@pytest.mark.parametrize("model", MODELS)
def test_interface_is_the_templates(native_fmus, model):
    """Same variables, value references, types, causalities, units, limits, starts and
    structure as the committed template (the pythonfmu FMU's); only the GUID, the generation
    tool, needsExecutionTool and the source files are the native flavour's own."""
    md = description(native_fmus[model])
    assert interface_diff(model, md) == []
    assert md.find("CoSimulation").get("needsExecutionTool") == "false"
    assert "native C" in md.get("generationTool")


def test_guid_from_the_sources(native_fmus):
    """The GUID is derived from the model, the flavour and the sources (library and glue):
    every build of the same sources has it, so a state saved by one restores in another."""
    guids = {model: description(native_fmus[model]).get("guid") for model in MODELS}
    assert guids == {model: native_guid(model) for model in MODELS}
    assert len(set(guids.values())) == len(MODELS)
    assert all(re.fullmatch(r"\{[0-9a-f-]{36}\}", g) for g in guids.values())
