"""The mesh + driveline system as an SSP 1.0 system structure, and its run in libcosim.

``write_ssp`` writes a directory (``SystemStructure.ssd`` + ``resources/*.fmu``) or a zipped
``.ssp`` with both FMUs, the connections of ``interface.CONNECTIONS``, parameter bindings, bindings
of the inputs' start values and the OSP fixed-step annotation libcosim needs.  The input starts
are what each unit's partner outputs at the start time (``consistent_input_starts``), so that
masters which exchange no values during initialization still start the pair consistent.
``run_libcosim`` loads it with libcosimpy (a native C++ master: Jacobi fixed-step, like the
harness) and records outputs at every communication point.

libcosim parses the SSD without namespace awareness: the prefixes must be literally ``ssd:``,
``ssc:`` and ``ssv:``.  It only warns about a parameter binding naming an unknown variable, so
``check_bindings`` compares every binding with the FMUs' modelDescriptions first.
"""

from __future__ import annotations

import shutil
import zipfile
from pathlib import Path
from xml.sax.saxutils import quoteattr

from fmpy import read_model_description

from drive_rattle.interface import CONNECTIONS, DRIVELINE, MESH

from .harness import Result
from .system import communication_points

SSD_NAME = "SystemStructure.ssd"
NAMESPACES = (
    'xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" '
    'xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" '
    'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" '
    'xmlns:osp="http://opensimulationplatform.com/SSP/OSPAnnotations"'
)
_SSV_TYPE = {bool: "Boolean", int: "Integer", float: "Real", str: "String"}


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
        if v.type != expected and not (v.type == "Real" and expected == "Integer"):
            raise ValueError(
                f"SSP {what} binding '{qualified}' = {value!r} is {expected or type(value)}; "
                f"the FMU declares {v.type}")


def default_parameters(fmus: dict[str, Path]) -> dict:
    """Every parameter of the FMUs at its start value, ``{"<Unit>.<name>": value}``."""
    convert = {"Real": float, "Integer": int, "Boolean": lambda v: v == "true", "String": str}
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


def system_structure(fmu_names: dict[str, str], parameters: dict, step: float,
                     start_time: float = 0.0, stop_time: float = 2.0,
                     input_starts: dict | None = None) -> str:
    """The SSD text; ``fmu_names`` maps unit to its file name under resources/.  The input
    starts are bound like parameters (in a second parameter set of the component)."""
    input_starts = input_starts or {}
    fmus_md = {}
    lines = ['<?xml version="1.0" encoding="UTF-8"?>',
             f'<ssd:SystemStructureDescription name="DriveRattle" version="1.0" {NAMESPACES}>',
             '  <ssd:System name="drive_rattle">', "    <ssd:Elements>"]
    # The Driveline first: its outputs (prescribed engine kinematics, the shaft torque in
    # steady state) do not depend on its inputs at the start, so masters that initialize the
    # units in document order and cut the mesh-driveline loop before its first unit
    # (fmu-manipulation-toolbox's container) give the mesh the Driveline's true outputs.
    for unit in (DRIVELINE, MESH):
        fmus_md[unit] = unit
        lines.append(f'      <ssd:Component name="{unit}" source="resources/{fmu_names[unit]}" '
                     'type="application/x-fmu-sharedlibrary">')
        lines.append("        <ssd:Connectors>")
        for src, out, dst, inp in CONNECTIONS:
            if dst == unit:
                lines.append(f'          <ssd:Connector name="{inp}" kind="input"><ssc:Real/>'
                             "</ssd:Connector>")
            if src == unit:
                lines.append(f'          <ssd:Connector name="{out}" kind="output"><ssc:Real/>'
                             "</ssd:Connector>")
        lines.append("        </ssd:Connectors>")
        sets = [(f"{unit}_{label}", {k.partition(".")[2]: v for k, v in values.items()
                                     if k.partition(".")[0] == unit})
                for label, values in (("parameters", parameters), ("input_starts", input_starts))]
        sets = [(name, bound) for name, bound in sets if bound]
        if sets:
            lines.append("        <ssd:ParameterBindings>")
        for set_name, bound in sets:
            lines += ["          <ssd:ParameterBinding><ssd:ParameterValues>",
                      f'          <ssv:ParameterSet version="1.0" name="{set_name}">'
                      "<ssv:Parameters>"]
            for name, value in bound.items():
                kind = _SSV_TYPE[type(value)]
                lines.append(f"            <ssv:Parameter name={quoteattr(name)}><ssv:{kind} "
                             f"value={quoteattr(_value(value))}/></ssv:Parameter>")
            lines += ["          </ssv:Parameters></ssv:ParameterSet>",
                      "          </ssd:ParameterValues></ssd:ParameterBinding>"]
        if sets:
            lines.append("        </ssd:ParameterBindings>")
        lines.append("      </ssd:Component>")
    lines += ["    </ssd:Elements>", "    <ssd:Connections>"]
    for src, out, dst, inp in CONNECTIONS:
        lines.append(f'      <ssd:Connection startElement="{src}" startConnector="{out}" '
                     f'endElement="{dst}" endConnector="{inp}"/>')
    lines += ["    </ssd:Connections>", "  </ssd:System>",
              f'  <ssd:DefaultExperiment startTime="{start_time!r}" stopTime="{stop_time!r}">',
              "    <ssd:Annotations>",
              '      <ssc:Annotation type="com.opensimulationplatform">',
              f'        <osp:Algorithm><osp:FixedStepAlgorithm baseStepSize="{step!r}"/>'
              "</osp:Algorithm>",
              "      </ssc:Annotation>", "    </ssd:Annotations>",
              "  </ssd:DefaultExperiment>", "</ssd:SystemStructureDescription>", ""]
    return "\n".join(lines)


def write_ssp(target: Path, mesh_fmu: Path, driveline_fmu: Path, parameters: dict | None = None,
              step: float = 1e-4, start_time: float = 0.0, stop_time: float = 2.0,
              input_starts: dict | str | None = None) -> Path:
    """Write the system as a directory, or as a zipped SSP when ``target`` ends in ``.ssp``.

    ``parameters`` and ``input_starts`` map ``"<Unit>.<name>"`` to values bound in the SSD;
    ``input_starts="consistent"`` binds every input at what its partner outputs at the start
    time for these parameters (``consistent_input_starts``)."""
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
                           stop_time, input_starts)
    target = Path(target)
    if target.suffix == ".ssp":
        target.parent.mkdir(parents=True, exist_ok=True)
        with zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr(SSD_NAME, ssd)
            for p in fmus.values():
                z.write(p, f"resources/{p.name}")
        return target
    (target / "resources").mkdir(parents=True, exist_ok=True)
    (target / SSD_NAME).write_text(ssd, encoding="utf-8")
    for p in fmus.values():
        shutil.copy2(p, target / "resources" / p.name)
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
    ex = CosimExecution.from_ssp_file(str(ssp), step_ns)
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
