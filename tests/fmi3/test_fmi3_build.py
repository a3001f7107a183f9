"""The FMI 3.0 FMUs as the build makes them: an interface rendered from the same specs as the
FMI 2.0 FMUs' (the same variables at the same value references, the same causality,
variability, units, limits and starts; the integer codes as Enumerations with named items; the
independent variable time), held against the committed templates, and a token from the GUID
scheme (what every face's FMUs ship, their validation and their binaries' exports:
tests/faces)."""

from __future__ import annotations

import re
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import pytest

from drive_rattle.catalog import UNITS
from drive_rattle.interface import MODELS
from drive_rattle.parameters import specs
from drive_rattle_build import model_description
from drive_rattle_build.fmi3 import (
    fmi3_headers,
    fmi3_token,
    normalised_xml,
    template_path,
)
from drive_rattle_build.native import (
    native_guid,
)
from drive_rattle_build.templates import template_body


def description(fmu: Path) -> ElementTree.Element:
    with zipfile.ZipFile(fmu) as z:
        return ElementTree.fromstring(z.read("modelDescription.xml"))


def header_functions() -> list[str]:
    """The functions fmi3Functions.h declares (every one an FMU binary must export)."""
    text = (fmi3_headers() / "fmi3Functions.h").read_text(encoding="utf-8")
    return re.findall(r"^FMI3_Export\s+\w+TYPE\s+(fmi3\w+);", text, re.M)


@pytest.mark.parametrize("model", MODELS)
def test_interface_is_the_fmi2_interface(fmi3_fmus, model):
    """Every variable of the FMI 2.0 modelDescription (rendered from the same specs) is in
    the FMI 3.0 one with the same value reference, description, causality, variability,
    initial, unit, display unit, limits and start; the types map Real -> Float64, Integer ->
    Int32 or (with choices) Enumeration; time is added; the structure is the same."""
    fmi2 = model_description.render(model, "{G}", "tool", needs_execution_tool=False)
    md = description(fmi3_fmus[model])
    mine = {v.get("name"): v for v in md.find("ModelVariables")}
    choices = {s.name: s.choices for _, s in specs(UNITS[model].parameters) if s.choices}
    type_of = {e.get("name"): e for e in md.find("TypeDefinitions") or []}
    for sv in fmi2.find("ModelVariables"):
        name, typed = sv.get("name"), next(iter(sv))
        v = mine.pop(name)
        for attr in ("valueReference", "description", "causality", "variability", "initial"):
            assert v.get(attr) == sv.get(attr), (name, attr)
        if typed.tag == "Enumeration":  # the FMI 2.0 type, item for item
            assert name in choices
            declared = typed.get("declaredType")
            assert v.tag == "Enumeration" and v.get("declaredType") == declared
            items = [(i.get("name"), int(i.get("value")), i.get("description"))
                     for i in type_of[declared]]
            fmi2_type = next(t for t in fmi2.find("TypeDefinitions") if t.get("name") == declared)
            assert items == [(i.get("name"), int(i.get("value")), i.get("description"))
                             for i in fmi2_type.find("Enumeration")]
            assert [i[1] for i in items] == sorted(choices[name])
        else:
            assert v.tag == {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean",
                             "String": "String"}[typed.tag], name
        for attr in ("unit", "displayUnit", "min", "max"):
            if v.tag != "Enumeration":
                assert v.get(attr) == typed.get(attr), (name, attr)
        start = (v.find("Start").get("value") if v.find("Start") is not None
                 else v.get("start"))
        assert start == typed.get("start"), name
    assert list(mine) == ["time"]
    assert mine["time"].attrib == {
        "name": "time", "valueReference": str(len(fmi2.find("ModelVariables"))),
        "description": "simulation time (the independent variable)",
        "causality": "independent", "variability": "continuous", "unit": "s"}
    outputs2 = [int(u.get("index")) - 1 for u in fmi2.find("ModelStructure/Outputs")]
    structure = md.find("ModelStructure")
    assert [int(u.get("valueReference")) for u in structure.findall("Output")] == outputs2
    assert all(u.get("dependencies") == "" for u in structure.findall("Output"))
    assert [int(u.get("valueReference")) for u in structure.findall("InitialUnknown")] == \
        outputs2
    for attr in ("modelName", "description", "author", "version", "license",
                 "variableNamingConvention"):
        assert md.get(attr) == fmi2.get(attr)
    assert md.find("DefaultExperiment").attrib == fmi2.find("DefaultExperiment").attrib
    cosim = md.find("CoSimulation").attrib
    assert cosim["hasEventMode"] == cosim["mightReturnEarlyFromDoStep"] == "false"
    assert cosim["providesIntermediateUpdate"] == "false"
    assert cosim["canGetAndSetFMUState"] == cosim["canSerializeFMUState"] == "true"


@pytest.mark.parametrize("model", MODELS)
def test_interface_is_the_committed_template(fmi3_fmus, model):
    text = template_body(template_path(model).read_text(encoding="utf-8"))
    assert text == normalised_xml(description(fmi3_fmus[model]))


def test_token_from_the_sources(fmi3_fmus):
    """The token is the GUID scheme's (model, flavour, sources): every build of the same
    sources has it, and it is not the FMI 2.0 FMU's (their states are told apart)."""
    tokens = {m: description(fmi3_fmus[m]).get("instantiationToken") for m in MODELS}
    assert tokens == {m: fmi3_token(m) for m in MODELS}
    assert len(set(tokens.values())) == len(MODELS)
    assert all(re.fullmatch(r"\{[0-9a-f-]{36}\}", t) for t in tokens.values())
    assert not set(tokens.values()) & {native_guid(m) for m in MODELS}
