"""The mesh + driveline system as an SSP 1.0 system structure, and its run in libcosim.

``write_ssp`` writes a directory (``SystemStructure.ssd`` + ``resources/*.fmu``) or a zipped
``.ssp`` with both FMUs, the connections of ``interface.CONNECTIONS``, every input and output of
each unit as a connector, one parameter set per component (``PARAMETER_SET``: the parameter
bindings and the inputs' start values together) and the OSP fixed-step annotation libcosim
needs.  The FMI 2.0 FMUs it bundles declare the integer codes as Integers
(``variants.integer_codes``: libcosim and ecos ignore FMI 2.0 Enumeration variables, so they
would neither apply a code's binding nor load the SSD without a warning per code), and the
binding of each code names its codes (``description="codes: 0 = none, 1 = ..."``).  The input
starts are what each unit's partner outputs at the start time (``consistent_input_starts``),
so that masters which exchange no values during initialization still start the pair
consistent.  With ``system_outputs=True`` the system also declares every
output of both units as a system connector of kind output, connected to the unit's output, so
that a container built from the SSP exposes them (libcosim and ecos refuse such an SSD: see
``write_ssp``).  ``run_libcosim`` loads it with libcosimpy (a native C++ master: Jacobi
fixed-step, like the harness) and records outputs at every communication point.

What the masters read of the bindings (measured; docs/tools.md): libcosim applies the first
parameter set of each component unless another is named; ecos applies a set only when it is
named (``--parameterSet``), sets of the same name across components together; fmpy's SSP runner
and fmu-manipulation-toolbox's container read none of them.  So each component has exactly one
set, all of the same name, and ``read_bindings`` gives the bound values to the runners of the
masters that ignore them (``drive_rattle_cosim.masters``).  ``edit_bindings`` changes bound
values in an existing SSP, as a user editing the SSD would.

libcosim and ecos parse the SSD without namespace awareness: the prefixes must be literally
``ssd:``, ``ssc:`` and ``ssv:``.  libcosim only warns about a parameter binding naming an
unknown variable, so ``check_bindings`` compares every binding with the FMUs'
modelDescriptions first.
"""

from __future__ import annotations

import zipfile
from pathlib import Path
from xml.sax.saxutils import quoteattr

from fmpy import read_model_description

from drive_rattle.interface import CONNECTIONS, DRIVELINE, MESH

from . import variants
from .harness import Result
from .system import communication_points

SSD_NAME = "SystemStructure.ssd"
#: The name of the one parameter set of every component: ecos applies a set only when it is
#: named (``ecos simulate --parameterSet DriveRattle``, ``EcosSimulation.init(parameter_set=)``).
PARAMETER_SET = "DriveRattle"
NAMESPACES = (
    'xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" '
    'xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" '
    'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" '
    'xmlns:osp="http://opensimulationplatform.com/SSP/OSPAnnotations"'
)
_SSV_TYPE = {bool: "Boolean", int: "Integer", float: "Real", str: "String"}
_NS = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
       "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues"}
_FROM_SSV = {"Real": float, "Integer": int, "Boolean": lambda text: text in ("true", "1"),
             "String": str}


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    return repr(v) if isinstance(v, float) else str(v)


def check_bindings(fmus: dict[str, Path], parameters: dict, causality: str = "parameter") -> None:
    """Raise ValueError unless every ``"<Unit>.<name>"`` is a variable of that unit's FMU with
    the given ``causality`` ("parameter" or "input") and a matching type."""
    variables = {unit: {v.name: v for v in read_model_description(str(path)).modelVariables}
                 for unit, path in fmus.items()}
    what = "parameter" if causality == "parameter" else "input-start"
    for qualified, value in parameters.items():
        unit, _, name = qualified.partition(".")
        v = variables.get(unit, {}).get(name)
        if v is None or v.causality != causality:
            raise ValueError(f"SSP {what} binding '{qualified}': no such {causality}")
        expected = _SSV_TYPE.get(type(value))
        declared = "Integer" if v.type == "Enumeration" else v.type  # set as an Integer
        if declared != expected and not (v.type == "Real" and expected == "Integer"):
            raise ValueError(
                f"SSP {what} binding '{qualified}' = {value!r} is {expected or type(value)}; "
                f"the FMU declares {v.type}")


def default_parameters(fmus: dict[str, Path]) -> dict:
    """Every parameter of the FMUs at its start value, ``{"<Unit>.<name>": value}``."""
    convert = {"Real": float, "Integer": int, "Enumeration": int,
               "Boolean": lambda v: v == "true", "String": str}
    return {f"{unit}.{v.name}": convert[v.type](v.start)
            for unit, path in fmus.items()
            for v in read_model_description(str(path)).modelVariables
            if v.causality == "parameter"}


def consistent_input_starts(parameters: dict | None = None, start_time: float = 0.0) -> dict:
    """``{"<Unit>.<input>": value}``: each input at what its partner outputs at ``start_time``
    [s] once the system with these parameters is initialized
    (``drive_rattle.units.coupled_start_inputs``)."""
    from drive_rattle.parameters import DrivelineParameters, MeshParameters
    from drive_rattle.units import coupled_start_inputs

    per_unit = {MESH: {}, DRIVELINE: {}}
    for qualified, value in (parameters or {}).items():
        unit, _, name = qualified.partition(".")
        if unit not in per_unit:
            raise ValueError(f"parameter '{qualified}': unknown unit '{unit}'")
        per_unit[unit][name] = value
    physics = [cls.from_public(per_unit[unit])
               for unit, cls in ((MESH, MeshParameters), (DRIVELINE, DrivelineParameters))]
    mesh_inputs, driveline_inputs = coupled_start_inputs(*physics, start_time=start_time)
    return {**{f"{MESH}.{k}": v for k, v in mesh_inputs.items()},
            **{f"{DRIVELINE}.{k}": v for k, v in driveline_inputs.items()}}


def enumeration_codes(fmus: dict[str, Path]) -> dict[str, str]:
    """``{"<Unit>.<name>": "0 = none, 1 = ..."}``: the codes and item names of every
    Enumeration variable of the FMUs (``variants.code_list``)."""
    return {f"{unit}.{v.name}": variants.code_list((int(i.value), i.name)
                                                   for i in v.declaredType.items)
            for unit, path in fmus.items()
            for v in read_model_description(str(path)).modelVariables
            if v.type == "Enumeration"}


def unit_connectors(fmus: dict[str, Path]) -> dict[str, list[tuple[str, str, str]]]:
    """``{unit: [(name, kind, type), ...]}``: every input and output of each unit's FMU, in
    the modelDescription's order (type ``Real``, ``Integer``, ``Boolean`` or ``String``)."""
    return {unit: [(v.name, v.causality, v.type)
                   for v in read_model_description(str(path)).modelVariables
                   if v.causality in ("input", "output")]
            for unit, path in fmus.items()}


def system_output_names(connectors: dict[str, list[tuple[str, str, str]]]) -> dict[str, str]:
    """``{"<Unit>.<output>": system connector name}``: every output of both units under its
    own name (``mesh.W``, ``vehicle.w``).  Not ``<Unit>.<output>``: fmpy's SSP runner names its
    columns by connector path, and ``GearMeshRattle.mesh.W`` is already the component's."""
    names = {}
    for unit, variables in connectors.items():
        for name, kind, _ in variables:
            if kind == "output":
                if name in names.values():
                    raise ValueError(f"output '{name}' of {unit}: another unit has an output of "
                                     "that name; a system connector needs a unique one")
                names[f"{unit}.{name}"] = name
    return names


def system_structure(fmu_names: dict[str, str], parameters: dict, step: float,
                     start_time: float = 0.0, stop_time: float = 2.0,
                     input_starts: dict | None = None,
                     connectors: dict[str, list[tuple[str, str, str]]] | None = None,
                     system_outputs: bool = False, codes: dict[str, str] | None = None) -> str:
    """The SSD text; ``fmu_names`` maps unit to its file name under resources/.  Each
    component gets one parameter set named ``PARAMETER_SET`` holding its parameter bindings
    and then its input starts.  ``connectors`` (``unit_connectors``; default: the coupling
    signals only) are declared on the components; ``system_outputs`` also declares every
    output among them as a system connector, connected to the unit's output.  ``codes``
    (``enumeration_codes``) become the description of the bindings of those parameters, where
    an engineer editing the SSD reads them."""
    input_starts = input_starts or {}
    codes = codes or {}
    if connectors is None:
        connectors = {unit: [] for unit in fmu_names}
        for src, out, dst, inp in CONNECTIONS:
            connectors[dst].append((inp, "input", "Real"))
            connectors[src].append((out, "output", "Real"))
    lines = ['<?xml version="1.0" encoding="UTF-8"?>',
             f'<ssd:SystemStructureDescription name="DriveRattle" version="1.0" {NAMESPACES}>',
             '  <ssd:System name="drive_rattle">']
    exposed = system_output_names(connectors) if system_outputs else {}
    if exposed:
        types = {f"{unit}.{name}": fmi_type for unit, variables in connectors.items()
                 for name, _, fmi_type in variables}
        lines.append("    <ssd:Connectors>")
        for qualified, name in exposed.items():
            lines.append(f"      <ssd:Connector name={quoteattr(name)} kind=\"output\">"
                         f"<ssc:{types[qualified]}/></ssd:Connector>")
        lines.append("    </ssd:Connectors>")
    lines.append("    <ssd:Elements>")
    # The Driveline first: its outputs (prescribed engine kinematics, the shaft torque in
    # steady state) do not depend on its inputs at the start, so masters that initialize the
    # units in document order and cut the mesh-driveline loop before its first unit
    # (fmu-manipulation-toolbox's container) give the mesh the Driveline's true outputs.
    for unit in (DRIVELINE, MESH):
        lines.append(f'      <ssd:Component name="{unit}" source="resources/{fmu_names[unit]}" '
                     'type="application/x-fmu-sharedlibrary">')
        lines.append("        <ssd:Connectors>")
        for name, kind, fmi_type in connectors[unit]:
            lines.append(f"          <ssd:Connector name={quoteattr(name)} kind=\"{kind}\">"
                         f"<ssc:{fmi_type}/></ssd:Connector>")
        lines.append("        </ssd:Connectors>")
        bound = {k.partition(".")[2]: v for values in (parameters, input_starts)
                 for k, v in values.items() if k.partition(".")[0] == unit}
        if bound:
            lines += ["        <ssd:ParameterBindings>",
                      "          <ssd:ParameterBinding><ssd:ParameterValues>",
                      f'          <ssv:ParameterSet version="1.0" name="{PARAMETER_SET}">'
                      "<ssv:Parameters>"]
            for name, value in bound.items():
                kind = _SSV_TYPE[type(value)]
                described = codes.get(f"{unit}.{name}")
                described = f" description={quoteattr(f'codes: {described}')}" if described else ""
                lines.append(f"            <ssv:Parameter name={quoteattr(name)}{described}>"
                             f"<ssv:{kind} value={quoteattr(_value(value))}/></ssv:Parameter>")
            lines += ["          </ssv:Parameters></ssv:ParameterSet>",
                      "          </ssd:ParameterValues></ssd:ParameterBinding>",
                      "        </ssd:ParameterBindings>"]
        lines.append("      </ssd:Component>")
    lines += ["    </ssd:Elements>", "    <ssd:Connections>"]
    for src, out, dst, inp in CONNECTIONS:
        lines.append(f'      <ssd:Connection startElement="{src}" startConnector="{out}" '
                     f'endElement="{dst}" endConnector="{inp}"/>')
    for qualified, name in exposed.items():
        unit, _, output = qualified.partition(".")
        lines.append(f"      <ssd:Connection startElement=\"{unit}\" "
                     f"startConnector={quoteattr(output)} endConnector={quoteattr(name)}/>")
    lines += ["    </ssd:Connections>", "  </ssd:System>",
              f'  <ssd:DefaultExperiment startTime="{start_time!r}" stopTime="{stop_time!r}">',
              "    <ssd:Annotations>",
              '      <ssc:Annotation type="com.opensimulationplatform">',
              f'        <osp:Algorithm><osp:FixedStepAlgorithm baseStepSize="{step!r}"/>'
              "</osp:Algorithm>",
              "      </ssc:Annotation>", "    </ssd:Annotations>",
              "  </ssd:DefaultExperiment>", "</ssd:SystemStructureDescription>", ""]
    return "\n".join(lines)


def _write(target: Path, ssd: str, fmus: dict[str, bytes]) -> Path:
    """The SSD and the FMUs (``{file name: bytes}``) under resources/ as a directory, or zipped
    if ``target`` ends in ``.ssp``."""
    target = Path(target)
    if target.suffix == ".ssp":
        target.parent.mkdir(parents=True, exist_ok=True)
        with zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr(SSD_NAME, ssd)
            for name, data in fmus.items():
                z.writestr(f"resources/{name}", data)
        return target
    (target / "resources").mkdir(parents=True, exist_ok=True)
    (target / SSD_NAME).write_text(ssd, encoding="utf-8")
    for name, data in fmus.items():
        (target / "resources" / name).write_bytes(data)
    return target


def bundled_fmu(fmu: Path, integer_codes: bool = True) -> bytes:
    """The bytes of ``fmu`` as an SSP bundles it: with ``integer_codes``, an FMI 2.0 FMU's
    integer codes declared Integers (``variants.integer_codes``; libcosim and ecos ignore FMI
    2.0 Enumeration variables), any other FMU as it is."""
    data = Path(fmu).read_bytes()
    if integer_codes and read_model_description(str(fmu)).fmiVersion == "2.0":
        return variants.fmu_copy(data, variants.integer_coded_model_description)
    return data


def write_ssp(target: Path, mesh_fmu: Path, driveline_fmu: Path, parameters: dict | None = None,
              step: float = 1e-4, start_time: float = 0.0, stop_time: float = 2.0,
              input_starts: dict | str | None = None, system_outputs: bool = False,
              integer_codes: bool = True) -> Path:
    """Write the system as a directory, or as a zipped SSP when ``target`` ends in ``.ssp``.

    ``parameters`` and ``input_starts`` map ``"<Unit>.<name>"`` to values bound in the SSD
    (one parameter set per component, ``PARAMETER_SET``); ``input_starts="consistent"`` binds
    every input at what its partner outputs at the start time for these parameters
    (``consistent_input_starts``).  Every input and output of both units is a connector of
    its component.  ``system_outputs=True`` also connects every output to a system connector
    of the same name, which a container built from the SSP (fmu-manipulation-toolbox) exposes
    and fmpy's SSP runner records; libcosim (0.0.6: ``No such node
    (<xmlattr>.endElement)``) and ecos (0.7.2: ``No element named: GearMeshRattle``) refuse an
    SSD with a connection to a system connector, so the build writes that system to a file
    of its own.  The SSP bundles the FMUs as ``bundled_fmu`` gives them: by default the
    FMI 2.0 ones with their integer codes declared Integers (``integer_codes=False``: as they
    are), and each code's binding says its codes (``enumeration_codes``)."""
    parameters = parameters or {}
    if input_starts == "consistent":
        input_starts = consistent_input_starts(parameters, start_time)
    elif isinstance(input_starts, str):
        raise ValueError(f"input_starts = {input_starts!r}; allowed: a dict, 'consistent' or None")
    input_starts = input_starts or {}
    fmus = {MESH: Path(mesh_fmu), DRIVELINE: Path(driveline_fmu)}
    check_bindings(fmus, parameters)
    check_bindings(fmus, input_starts, causality="input")
    ssd = system_structure({u: p.name for u, p in fmus.items()}, parameters, step, start_time,
                           stop_time, input_starts, unit_connectors(fmus), system_outputs,
                           enumeration_codes(fmus))
    return _write(target, ssd, {p.name: bundled_fmu(p, integer_codes) for p in fmus.values()})


def _read_member(ssp: Path, name: str) -> bytes:
    """A file of an SSP directory or archive (``name`` relative to its root)."""
    ssp = Path(ssp)
    if ssp.is_dir():
        return (ssp / name).read_bytes()
    with zipfile.ZipFile(ssp) as z:
        return z.read(name)


def _components(root):
    return root.findall("ssd:System/ssd:Elements/ssd:Component", _NS)


def component_sources(ssp: Path) -> dict[str, str]:
    """``{component name: source}`` of the SSD's components (``resources/<unit>.fmu``)."""
    from lxml import etree

    root = etree.fromstring(_read_member(ssp, SSD_NAME))
    return {c.get("name"): c.get("source") for c in _components(root)}


def read_bindings(ssp: Path) -> dict:
    """``{"<Component>.<name>": value}``: every value the SSD's components bind, typed by
    its SSV element (Real -> float, Integer -> int, Boolean -> bool, String -> str), from
    inline parameter sets and from ``.ssv`` files (``source``, relative to the SSP's root), in
    document order (a later binding of a name replaces an earlier one).  For the masters that
    ignore the bindings (fmpy's SSP runner, fmu-manipulation-toolbox's container): their
    runners in ``drive_rattle_cosim.masters`` apply these values."""
    from lxml import etree

    root = etree.fromstring(_read_member(ssp, SSD_NAME))
    values = {}
    for component in _components(root):
        unit = component.get("name")
        for binding in component.findall("ssd:ParameterBindings/ssd:ParameterBinding", _NS):
            if binding.get("source"):
                sets = [etree.fromstring(_read_member(ssp, binding.get("source")))]
            else:
                sets = binding.findall("ssd:ParameterValues/ssv:ParameterSet", _NS)
            for parameter_set in sets:
                for parameter in parameter_set.findall("ssv:Parameters/ssv:Parameter", _NS):
                    typed = next(iter(parameter))
                    kind = etree.QName(typed).localname
                    if kind not in _FROM_SSV:
                        raise ValueError(f"SSP binding '{unit}.{parameter.get('name')}': "
                                         f"type {kind} is not supported")
                    values[f"{unit}.{parameter.get('name')}"] = _FROM_SSV[kind](typed.get("value"))
    return values


def edit_bindings(ssp: Path, values: dict, target: Path | None = None) -> Path:
    """Change bound values of an SSP, as a user editing its SSD would: ``values`` maps
    ``"<Component>.<name>"`` to the new value of an inline binding that the SSD already has
    (each one must exist: a misspelt name raises KeyError instead of being ignored).  Writes
    ``target`` (a directory or a ``.ssp``; default: ``ssp`` itself) and returns it."""
    from lxml import etree

    ssp, target = Path(ssp), Path(target or ssp)
    root = etree.fromstring(_read_member(ssp, SSD_NAME))
    found = dict.fromkeys(values, False)
    for component in _components(root):
        unit = component.get("name")
        for parameter in component.findall(
                "ssd:ParameterBindings/ssd:ParameterBinding/ssd:ParameterValues/"
                "ssv:ParameterSet/ssv:Parameters/ssv:Parameter", _NS):
            qualified = f"{unit}.{parameter.get('name')}"
            if qualified in values:
                typed = next(iter(parameter))
                kind = etree.QName(typed).localname
                value = values[qualified]
                if _SSV_TYPE.get(type(value)) != kind and not (
                        kind == "Real" and type(value) is int):
                    raise ValueError(f"'{qualified}' = {value!r}: the SSD binds an {kind}")
                typed.set("value", _value(float(value) if kind == "Real" else value))
                found[qualified] = True
    missing = [k for k, ok in found.items() if not ok]
    if missing:
        raise KeyError(f"{ssp}: no inline binding of {', '.join(missing)}")
    ssd = etree.tostring(root, xml_declaration=True, encoding="UTF-8")
    members = {}
    if ssp.is_dir():
        members = {str(p.relative_to(ssp)): p.read_bytes() for p in ssp.rglob("*")
                   if p.is_file() and p.name != SSD_NAME}
    else:
        with zipfile.ZipFile(ssp) as z:
            members = {n: z.read(n) for n in z.namelist() if n != SSD_NAME}
    if target.suffix == ".ssp":
        target.parent.mkdir(parents=True, exist_ok=True)
        with zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr(SSD_NAME, ssd)
            for name, data in members.items():
                z.writestr(name, data)
    else:
        for name, data in members.items():
            (target / name).parent.mkdir(parents=True, exist_ok=True)
            (target / name).write_bytes(data)
        (target / SSD_NAME).write_bytes(ssd)
    return target


def validate_ssd(path: Path) -> None:
    """Validate an SSD file against the SSP 1.0 schema shipped with fmpy (raises on errors)."""
    from fmpy.ssp.ssd import validate_tree
    from lxml import etree

    validate_tree(etree.parse(str(path)).getroot(), "SystemStructureDescription.xsd")


def run_libcosim(ssp: Path, stop_time: float, outputs: list[str],
                 step: float | None = None) -> Result:
    """Run an SSP directory or .ssp file in libcosim; record ``outputs`` (``"<Unit>.<name>"``,
    Real) at every communication point after the start, up to ``stop_time`` [s].

    libcosim initializes the units inside its first step, so the values at the start time
    are not observable here: the result begins at the first communication point after it."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.WARNING)
    step_ns = None if step is None else round(step * 1e9)
    if step_ns is None:  # libcosim crashes without a step (annotation or argument): read it
        import re

        ssd = Path(ssp) / SSD_NAME if Path(ssp).is_dir() else None
        text = ssd.read_text() if ssd else zipfile.ZipFile(ssp).read(SSD_NAME).decode()
        step = float(re.search(r'baseStepSize="([^"]+)"', text).group(1))
        step_ns = round(step * 1e9)
    try:
        ex = CosimExecution.from_ssp_file(str(ssp), step_ns)
    except AssertionError:  # libcosimpy asserts; the reason is libcosim's last error
        from libcosimpy._internal import get_last_error_message

        raise RuntimeError(f"libcosim cannot load {ssp}: {get_last_error_message()}") from None
    try:
        observer = CosimObserver.create_last_value()
        ex.add_observer(observer)
        index = {}
        for qualified in outputs:
            unit, _, name = qualified.partition(".")
            slave = ex.slave_index_from_instance_name(unit)
            refs = {v.name.decode(): v.reference for v in ex.slave_variables(slave)}
            if name not in refs:
                raise KeyError(f"libcosim: {unit} has no variable '{name}'")
            index[qualified] = (slave, refs[name])
        start = ex.status().current_time / 1e9
        points = communication_points(start, step, stop_time)
        result = Result(units={o: "" for o in outputs})
        result.columns = {o: [] for o in outputs}
        for t in points[1:]:
            if not ex.step(1):
                raise RuntimeError(f"libcosim failed to step to t = {t!r} s")
            result.time.append(ex.status().current_time / 1e9)
            for qualified, (slave, vr) in index.items():
                result.columns[qualified].append(observer.last_real_values(slave, [vr])[0])
        return result
    finally:
        del ex
