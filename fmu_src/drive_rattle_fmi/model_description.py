"""The complete modelDescription.xml of a drive-rattle slave, rendered from its specs.

pythonfmu's own rendering lacks units, limits, dependencies and InitialUnknowns; this one emits
(FMI 2.0 schema order): CoSimulation, UnitDefinitions, LogCategories, DefaultExperiment,
ModelVariables and ModelStructure (Outputs without direct feedthrough, InitialUnknowns).
The hidden status-channel variables are left out; being registered last, they leave every
public value reference equal to its registration index (the model library's table index).  The
inputs' start values are the library's (``drive_rattle.units.input_starts``).  pythonfmu's
builder calls it (through ``RattleSlave.to_xml``) when the build packs an FMU; nothing calls
it at run time.
"""

from __future__ import annotations

import datetime
from xml.etree.ElementTree import Element, SubElement

from pythonfmu import __version__ as pythonfmu_version

from drive_rattle.parameters import ParameterSpec
from drive_rattle.units import input_starts

from .units import BASE_UNITS, DISPLAY_UNITS, check_display_unit

#: Capability flags written to <CoSimulation>.  The wrapper and the shim implement all of them.
CAPABILITIES = {
    "needsExecutionTool": "true",  # a Python interpreter with the FMU's dependencies
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


def _fmt(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    return str(value)


def model_description(slave, generation_time: str | None = None,
                      guid: str | None = None) -> Element:
    """The <fmiModelDescription> element of a RattleSlave instance, with ``guid`` ("{...}";
    default: the slave's own, pythonfmu's random one)."""
    cls = type(slave)
    if generation_time is None:
        generation_time = datetime.datetime.now(datetime.timezone.utc).isoformat(
            timespec="seconds")
    root = Element("fmiModelDescription", {
        "fmiVersion": "2.0",
        "modelName": cls.__name__,
        "guid": guid or f"{{{slave.guid!s}}}",
        "description": cls.description,
        "author": cls.author,
        "version": cls.version,
        "license": cls.license,
        "generationTool": f"drive-rattle-build (pythonfmu {pythonfmu_version})",
        "generationDateAndTime": generation_time,
        "variableNamingConvention": "structured",
        "numberOfEventIndicators": "0",
    })
    SubElement(root, "CoSimulation", {"modelIdentifier": cls.__name__, **CAPABILITIES})

    variables = slave.public_variables
    param_specs = slave._param_specs
    signal_specs = {s.name: s for s in (*cls.INPUTS, *cls.OUTPUTS)}
    starts = input_starts(cls.KIND)

    def unit_of(name):
        spec = param_specs.get(name) or signal_specs[name]
        return spec.unit, spec.display_unit

    used = sorted({unit_of(v.name)[0] for v in variables
                   if slave._fmi_types[v.name] == "Real"})
    units = SubElement(root, "UnitDefinitions")
    for unit in used:
        check_display_unit(unit, None)
        u = SubElement(units, "Unit", {"name": unit})
        SubElement(u, "BaseUnit", {k: str(e) for k, e in BASE_UNITS[unit].items()})
        for name, factor in DISPLAY_UNITS.get(unit, {}).items():
            SubElement(u, "DisplayUnit", {"name": name, "factor": repr(factor)})

    cats = SubElement(root, "LogCategories")
    for name, text in LOG_CATEGORIES.items():
        SubElement(cats, "Category", {"name": name, "description": text})

    SubElement(root, "DefaultExperiment",
               {k: repr(v) for k, v in cls.DEFAULT_EXPERIMENT.items()})

    mv = SubElement(root, "ModelVariables")
    index = {}
    for i, var in enumerate(variables, start=1):
        if var.value_reference != i - 1:
            raise RuntimeError(
                f"{var.name}: value reference {var.value_reference} != index {i - 1}")
        index[var.name] = i
        fmi_type = slave._fmi_types[var.name]
        attrs = {"name": var.name, "valueReference": str(var.value_reference),
                 "description": var.description, "causality": var.causality.name,
                 "variability": var.variability.name}
        type_attrs = {}
        if var.name in param_specs:
            spec: ParameterSpec = param_specs[var.name]
            attrs["initial"] = "exact"
            type_attrs["start"] = _fmt(spec.default)
            if fmi_type in ("Real", "Integer"):
                if spec.minimum is not None:
                    type_attrs["min"] = _fmt(spec.minimum)
                if spec.maximum is not None:
                    type_attrs["max"] = _fmt(spec.maximum)
        elif var.name in {s.name for s in cls.INPUTS}:
            spec = signal_specs[var.name]
            type_attrs["start"] = _fmt(starts[var.name])
            if spec.minimum is not None:
                type_attrs["min"], type_attrs["max"] = _fmt(spec.minimum), _fmt(spec.maximum)
        if fmi_type == "Real":
            unit, display = unit_of(var.name)
            check_display_unit(unit, display)
            type_attrs["unit"] = unit
            if display:
                type_attrs["displayUnit"] = display
            # Order of attributes in the schema does not matter, but keep unit first to read.
            type_attrs = {k: type_attrs[k] for k in
                          ("unit", "displayUnit", "min", "max", "start") if k in type_attrs}
        sv = SubElement(mv, "ScalarVariable", attrs)
        SubElement(sv, fmi_type, type_attrs)

    structure = SubElement(root, "ModelStructure")
    outputs = [index[s.name] for s in cls.OUTPUTS]
    out_el = SubElement(structure, "Outputs")
    for i in outputs:
        # Co-simulation outputs are values at the communication point, computed by the last
        # step from the inputs held over it: no direct feedthrough of the current inputs.
        SubElement(out_el, "Unknown", {"index": str(i), "dependencies": ""})
    init_el = SubElement(structure, "InitialUnknowns")
    for i in outputs:
        # Initial outputs depend on the parameters and the initial inputs (equilibrium).
        SubElement(init_el, "Unknown", {"index": str(i)})
    return root
