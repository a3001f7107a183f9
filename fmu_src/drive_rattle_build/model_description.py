"""The modelDescription.xml of each FMU, rendered from the specs (``drive_rattle.catalog``) for
both flavours by the one function :func:`render`: FMI 2.0 schema order -- CoSimulation,
UnitDefinitions, LogCategories, DefaultExperiment, ModelVariables and ModelStructure (outputs
without direct feedthrough, InitialUnknowns) -- with units and display units, limits, and the
inputs' start values from the model library.  The flavours differ only in the generation tool,
whether an execution tool is needed and the <SourceFiles> of the native FMU; the build holds
the rest against ``modelDescription_templates/`` (``templates``)."""

from __future__ import annotations

import datetime
import re
from collections.abc import Sequence
from typing import NamedTuple
from xml.etree.ElementTree import Element, SubElement

from drive_rattle import library as binding
from drive_rattle.catalog import UNITS
from drive_rattle.interface import DEFAULT_EXPERIMENT
from drive_rattle.parameters import specs
from drive_rattle.units import input_starts

from .compiler import BuildError
from .library import build_in_place
from .unit_definitions import BASE_UNITS, DISPLAY_UNITS, check_display_unit

#: Capability flags of <CoSimulation> (both flavours implement all of them).
CAPABILITIES = {
    "canHandleVariableCommunicationStepSize": "true",
    "canInterpolateInputs": "false",
    "canBeInstantiatedOnlyOncePerProcess": "false",
    "canNotUseMemoryManagementFunctions": "true",
    "canGetAndSetFMUstate": "true",
    "canSerializeFMUstate": "true",
}
LOG_CATEGORIES = {
    "logStatusWarning": "Messages with status fmi2Warning",
    "logStatusDiscard": "Messages with status fmi2Discard",
    "logStatusError": "Messages with status fmi2Error (rejected calls, with the reason)",
    "logStatusFatal": "Messages with status fmi2Fatal",
    "logAll": "All messages",
}
#: The FMUs' metadata.
ABOUT = {"author": "drive-rattle developers", "version": "0.1.0", "license": "MIT"}


class Item(NamedTuple):
    name: str
    value: int
    description: str


class Enumeration(NamedTuple):
    """The FMI 2.0 enumeration type of an integer-coded parameter."""

    type_name: str  # the <SimpleType name>, the variable's declaredType
    items: list[Item]


def enumeration(spec) -> Enumeration | None:
    """The enumeration type of an integer variable with ``choices`` (else None): named after
    the parameter (``contact.hertz_law`` -> ``ContactHertzLaw``), one item per code named by
    the specs' ``choice_names``, its description the code's meaning from the specs."""
    choices = getattr(spec, "choices", None)  # parameters have them; a signal may
    if spec.fmi_type != "Integer" or not choices:
        return None
    type_name = "".join(part[:1].upper() + part[1:] for part in re.split(r"[._]", spec.name))
    return Enumeration(type_name, [Item(spec.choice_names[code], int(code), text)
                                   for code, text in sorted(choices.items())])


def _fmt(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    return str(value)


def variable_rows(model: str) -> list[tuple]:
    """``(name, causality, spec, start)`` of every variable of ``model`` in value-reference
    order (parameters with their defaults, inputs with the library's start values, outputs),
    held against the model library's table (BuildError when they differ)."""
    unit = UNITS[model]
    build_in_place()
    starts = input_starts(unit.kind)
    rows = [(spec.name, "parameter", spec, spec.default) for _, spec in specs(unit.parameters)]
    rows += [(s.name, "input", s, starts[s.name]) for s in unit.inputs]
    rows += [(s.name, "output", s, None) for s in unit.outputs]
    table = binding.variables(unit.kind)
    if [r[0] for r in rows] != [v["name"] for v in table]:
        raise BuildError(f"{model}: the model library's variables are not the specs' "
                         "(rebuild the library: drive-rattle-build --library)")
    return rows


def unit_definitions(root: Element, names: Sequence[str]) -> Element:
    """<UnitDefinitions> of the units ``names`` (base units and display units; the same in
    FMI 2.0 and 3.0), appended to ``root``."""
    units = SubElement(root, "UnitDefinitions")
    for name in names:
        check_display_unit(name, None)
        u = SubElement(units, "Unit", {"name": name})
        SubElement(u, "BaseUnit", {k: str(e) for k, e in BASE_UNITS[name].items()})
        for display, factor in DISPLAY_UNITS.get(name, {}).items():
            SubElement(u, "DisplayUnit", {"name": display, "factor": repr(factor)})
    return units


def render(model: str, guid: str, generation_tool: str, needs_execution_tool: bool,
           sources: Sequence[str] = (), generation_time: str | None = None) -> Element:
    """The complete modelDescription of ``model`` with ``guid``; ``sources``: the C files of
    <SourceFiles> (none: no element)."""
    unit = UNITS[model]
    if generation_time is None:
        generation_time = datetime.datetime.now(datetime.timezone.utc).isoformat(
            timespec="seconds")
    root = Element("fmiModelDescription", {
        "fmiVersion": "2.0", "modelName": model, "guid": guid,
        "description": unit.description, **ABOUT,
        "generationTool": generation_tool, "generationDateAndTime": generation_time,
        "variableNamingConvention": "structured", "numberOfEventIndicators": "0"})
    cosim = SubElement(root, "CoSimulation", {
        "modelIdentifier": model,
        "needsExecutionTool": "true" if needs_execution_tool else "false", **CAPABILITIES})
    if sources:
        files = SubElement(cosim, "SourceFiles")
        for name in sources:
            SubElement(files, "File", {"name": name})

    rows = variable_rows(model)
    unit_definitions(root, sorted({spec.unit for _, _, spec, _ in rows
                                   if spec.fmi_type == "Real"}))
    enumerations = [e for e in (enumeration(spec) for _, _, spec, _ in rows) if e is not None]
    if enumerations:
        types = SubElement(root, "TypeDefinitions")
        for e in enumerations:
            simple = SubElement(SubElement(types, "SimpleType", {"name": e.type_name}),
                                "Enumeration")
            for item in e.items:
                SubElement(simple, "Item", {"name": item.name, "value": str(item.value),
                                            "description": item.description})
    categories = SubElement(root, "LogCategories")
    for name, text in LOG_CATEGORIES.items():
        SubElement(categories, "Category", {"name": name, "description": text})
    SubElement(root, "DefaultExperiment", {k: repr(v) for k, v in DEFAULT_EXPERIMENT.items()})

    variables = SubElement(root, "ModelVariables")
    for vr, (name, causality, spec, start) in enumerate(rows):
        fmi_type = spec.fmi_type
        variability = ("fixed" if causality == "parameter" else
                       "continuous" if fmi_type == "Real" else "discrete")
        attrs = {"name": name, "valueReference": str(vr), "description": spec.description,
                 "causality": causality, "variability": variability}
        typed = {}
        if causality != "output":
            typed["start"] = _fmt(start)
            if fmi_type in ("Real", "Integer"):
                if spec.minimum is not None:
                    typed["min"] = _fmt(spec.minimum)
                if spec.maximum is not None:
                    typed["max"] = _fmt(spec.maximum)
        if causality == "parameter":
            attrs["initial"] = "exact"
        if fmi_type == "Real":
            check_display_unit(spec.unit, spec.display_unit)
            typed["unit"] = spec.unit
            if spec.display_unit:
                typed["displayUnit"] = spec.display_unit
            # attribute order as the schema lists them: unit first, to read
            typed = {k: typed[k] for k in ("unit", "displayUnit", "min", "max", "start")
                     if k in typed}
        declared = enumeration(spec)
        if declared is not None:  # set and got with fmi2SetInteger/GetInteger, as an Integer
            fmi_type = "Enumeration"
            typed = {"declaredType": declared.type_name,
                     **{k: typed[k] for k in ("min", "max", "start") if k in typed}}
        sv = SubElement(variables, "ScalarVariable", attrs)
        SubElement(sv, fmi_type, typed)

    structure = SubElement(root, "ModelStructure")
    indices = [str(vr + 1) for vr, row in enumerate(rows) if row[1] == "output"]
    outputs_el = SubElement(structure, "Outputs")
    for index in indices:
        # co-simulation outputs are values at the communication point, computed by the last
        # step from the inputs held over it: no direct feedthrough of the current inputs
        SubElement(outputs_el, "Unknown", {"index": index, "dependencies": ""})
    initial = SubElement(structure, "InitialUnknowns")
    for index in indices:
        # initial outputs depend on the parameters and the initial inputs (the start solved)
        SubElement(initial, "Unknown", {"index": index})
    return root
