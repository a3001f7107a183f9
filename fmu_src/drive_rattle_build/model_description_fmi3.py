"""The FMI 3.0 modelDescription.xml of the native FMI 3.0 FMUs, rendered from the same specs
(``drive_rattle.catalog``, ``drive_rattle.parameters``) and the same rows as the FMI 2.0
modelDescription (``model_description.variable_rows``, ``unit_definitions``, ``ABOUT``), so
that both describe one interface: the same variables at the same value references, with the
same causality, variability, initial, units, display units, limits and start values.

What FMI 3.0 adds or names differently:

* ``instantiationToken`` instead of ``guid`` (the same GUID scheme, ``identity.fmu_guid``);
* the FMI 3.0 types: Real -> ``<Float64>``, Integer -> ``<Int32>``, Boolean, String (its
  start a ``<Start value=...>`` child); an Integer whose spec has ``choices`` (code ->
  description) becomes an ``<Enumeration declaredType=...>`` of an ``<EnumerationType>`` in
  ``<TypeDefinitions>`` with a named item per code (the FMI 2.0 face's types,
  ``model_description.enumeration``: the specs' ``choice_names``);
* the independent variable ``time`` (FMI 3.0 requires exactly one), a Float64 in s at the value
  reference after the unit's variables (``time_value_reference``), first in the list;
* ``<CoSimulation>`` with FMI 3.0's capability flags (:data:`CAPABILITIES`): no event mode, no
  early return, no intermediate update (docs/fmi3.md says why), no ``<SourceFiles>`` (FMI 3.0
  lists the sources in ``sources/buildDescription.xml``: ``fmi3.build_description``);
* ``<ModelStructure>`` by value reference: ``<Output dependencies="">`` (no direct
  feedthrough) and ``<InitialUnknown>`` for every output.

The FMI 2.0 renderer is untouched by this module: it only reads what ``model_description``
exposes.
"""

from __future__ import annotations

import datetime
from xml.etree.ElementTree import Element, SubElement

from drive_rattle.catalog import UNITS
from drive_rattle.interface import DEFAULT_EXPERIMENT

from .model_description import ABOUT, _fmt, enumeration, unit_definitions, variable_rows
from .unit_definitions import check_display_unit

#: <CoSimulation>'s attributes after modelIdentifier, in the schema's order.
CAPABILITIES = {
    "needsExecutionTool": "false",
    "canBeInstantiatedOnlyOncePerProcess": "false",
    "canGetAndSetFMUState": "true",
    "canSerializeFMUState": "true",
    "providesDirectionalDerivatives": "false",
    "providesAdjointDerivatives": "false",
    "providesPerElementDependencies": "false",
    "canHandleVariableCommunicationStepSize": "true",
    "maxOutputDerivativeOrder": "0",
    "providesIntermediateUpdate": "false",
    "mightReturnEarlyFromDoStep": "false",
    "canReturnEarlyAfterIntermediateUpdate": "false",
    "hasEventMode": "false",
    "providesEvaluateDiscreteStates": "false",
}
#: The log categories (fmi3_functions.c knows the same names; a test holds them equal).
LOG_CATEGORIES = {
    "logStatusWarning": "Messages with status fmi3Warning (logged when this category or "
                        "logAll is on)",
    "logStatusDiscard": "Messages with status fmi3Discard",
    "logStatusError": "Messages with status fmi3Error (rejected calls, with the reason; "
                      "always logged)",
    "logStatusFatal": "Messages with status fmi3Fatal (always logged)",
    "logAll": "All messages",
}
#: The FMI 3.0 element of each spec type (an Integer with choices: ``ENUMERATION``).
TYPES = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean", "String": "String"}
ENUMERATION = "Enumeration"
#: The independent variable.
TIME_NAME, TIME_UNIT = "time", "s"


def is_enumeration(spec) -> bool:
    """An Integer parameter whose spec names its codes (``choices``) is an Enumeration; the
    model library's tables say the same (``n_choices > 0``), which fmi3_functions.c reads."""
    return spec.fmi_type == "Integer" and bool(getattr(spec, "choices", None))


def fmi3_type(spec) -> str:
    """The FMI 3.0 element of ``spec``'s variables."""
    return ENUMERATION if is_enumeration(spec) else TYPES[spec.fmi_type]


def time_value_reference(model: str) -> int:
    """The value reference of the independent variable ``time``: the first after the unit's
    variables (theirs are the model library's indices, as in the FMI 2.0 FMUs)."""
    return len(variable_rows(model))


def render(model: str, token: str, generation_tool: str, generation_time: str | None = None
           ) -> Element:
    """The complete FMI 3.0 modelDescription of ``model`` with the instantiation token
    ``token``."""
    unit = UNITS[model]
    rows = variable_rows(model)
    if generation_time is None:
        generation_time = datetime.datetime.now(datetime.timezone.utc).isoformat(
            timespec="seconds")
    root = Element("fmiModelDescription", {
        "fmiVersion": "3.0", "modelName": model, "instantiationToken": token,
        "description": unit.description, **ABOUT,
        "generationTool": generation_tool, "generationDateAndTime": generation_time,
        "variableNamingConvention": "structured"})
    SubElement(root, "CoSimulation", {"modelIdentifier": model, **CAPABILITIES})
    unit_definitions(root, sorted({TIME_UNIT} | {spec.unit for _, _, spec, _ in rows
                                                 if spec.fmi_type == "Real"}))

    enumerations = [spec for _, _, spec, _ in rows if is_enumeration(spec)]
    if enumerations:
        types = SubElement(root, "TypeDefinitions")
        for spec in enumerations:
            # no description on the type (the variable has it): fmpy 0.3.19 cannot read one
            declared = enumeration(spec)  # the FMI 2.0 face's types: one source
            t = SubElement(types, "EnumerationType", {"name": declared.type_name})
            for item in declared.items:
                SubElement(t, "Item", {"name": item.name, "value": str(item.value),
                                       "description": item.description})
    categories = SubElement(root, "LogCategories")
    for name, text in LOG_CATEGORIES.items():
        SubElement(categories, "Category", {"name": name, "description": text})
    SubElement(root, "DefaultExperiment", {k: repr(v) for k, v in DEFAULT_EXPERIMENT.items()})

    variables = SubElement(root, "ModelVariables")
    SubElement(variables, "Float64", {
        "name": TIME_NAME, "valueReference": str(len(rows)),
        "description": "simulation time (the independent variable)",
        "causality": "independent", "variability": "continuous", "unit": TIME_UNIT})
    for vr, (name, causality, spec, start) in enumerate(rows):
        element = fmi3_type(spec)
        variability = ("fixed" if causality == "parameter" else
                       "continuous" if element == "Float64" else "discrete")
        attrs = {"name": name, "valueReference": str(vr), "description": spec.description,
                 "causality": causality, "variability": variability}
        if causality == "parameter":
            attrs["initial"] = "exact"
        if element == ENUMERATION:
            attrs["declaredType"] = enumeration(spec).type_name
        if element == "Float64":
            check_display_unit(spec.unit, spec.display_unit)
            attrs["unit"] = spec.unit
            if spec.display_unit:
                attrs["displayUnit"] = spec.display_unit
        if causality != "output" and element in ("Float64", "Int32"):
            if spec.minimum is not None:
                attrs["min"] = _fmt(spec.minimum)
            if spec.maximum is not None:
                attrs["max"] = _fmt(spec.maximum)
        if causality != "output" and element != "String":
            attrs["start"] = _fmt(start)
        variable = SubElement(variables, element, attrs)
        if causality != "output" and element == "String":
            SubElement(variable, "Start", {"value": start})

    structure = SubElement(root, "ModelStructure")
    outputs = [str(vr) for vr, row in enumerate(rows) if row[1] == "output"]
    for vr in outputs:
        # co-simulation outputs are values at the communication point, computed by the last
        # step from the inputs held over it: no direct feedthrough of the current inputs
        SubElement(structure, "Output", {"valueReference": vr, "dependencies": ""})
    for vr in outputs:
        # initial outputs depend on the parameters and the initial inputs (the start solved)
        SubElement(structure, "InitialUnknown", {"valueReference": vr})
    return root
