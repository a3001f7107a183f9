"""The system in other FMI 2.0 masters, with the workarounds their own defects need.

Each ``run_*`` function runs the system (``dist/DriveRattle.ssp`` or the two FMUs) in one
master and returns a ``harness.Result`` holding the coupling signals (``"<Unit>.<output>"`` of
``drive_rattle.interface.CONNECTIONS``) at the communication points the master computed.
Each master places its points with its own arithmetic (``MASTER_GRIDS``,
``harness.time_grid``): the harness run on the same grid gives the same numbers bit for bit
(tests/cosim/test_masters.py), so these functions are also the reference for what each master
computes.  pathsim-fmi is the exception: it steps the units one after the other (Gauss-Seidel),
which the harness does not do; its run is the model library's units stepped in its order, bit
for bit (``pathsim_system``).  docs/tools.md explains each workaround for users of the
masters directly.

The SSP masters that ignore the SSD's parameter bindings (fmpy's SSP runner,
fmu-manipulation-toolbox's container) get them from their runners here (``ssp.read_bindings``);
ecos applies them only when the set is named, which ``run_ecos`` does; gemseo-fmu gets
parameters its own way (``gemseo_system(..., parameters)``).

Measured with fmpy 0.3.19 (the newest gemseo-fmu accepts), fmu-manipulation-toolbox 2.0,
gemseo-fmu 3.1.1, ecospy 0.7.2 and pathsim-fmi 0.1.1.  ``main`` writes the copies of the FMUs
that some masters need (``variants``).  Run one master per process where a master can abort at
exit (libcosim and fmpy in one process).
"""

from __future__ import annotations

import contextlib
import io
import logging
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

from drive_rattle.interface import CONNECTIONS, DRIVELINE, MESH

from . import variants
from .harness import Result
from .ssp import PARAMETER_SET, component_sources, read_bindings

#: The coupling signals every master exchanges, ``"<Unit>.<output>"``.
COUPLING = [f"{src}.{out}" for src, out, _, _ in CONNECTIONS]
#: ``harness.time_grid`` name of each master's communication points.
MASTER_GRIDS = {"libcosim": "nanoseconds", "fmpy.ssp": "accumulated",
                "container": "multiplied", "gemseo": "accumulated-clipped",
                "ecos": "accumulated", "cofmupy": "accumulated"}
#: Real inputs and outputs of each unit, for masters that read every variable as Real.
REAL_INPUTS = {MESH: [i for _, _, d, i in CONNECTIONS if d == MESH],
               DRIVELINE: [i for _, _, d, i in CONNECTIONS if d == DRIVELINE]}
REAL_OUTPUTS = {MESH: [o for s, o, _, _ in CONNECTIONS if s == MESH],
                DRIVELINE: [o for s, o, _, _ in CONNECTIONS if s == DRIVELINE]}


def _result(time, columns: dict) -> Result:
    return Result(time=[float(t) for t in time],
                  columns={k: [float(v) for v in vs] for k, vs in columns.items()},
                  units=dict.fromkeys(columns, ""))


# ---------------------------------------------------------------- fmpy's SSP runner
@contextlib.contextmanager
def fmpy_ssp_workarounds(first_step: bool = True):
    """Work around two defects of fmpy.ssp (fmpy 0.3.19 to 0.3.32) inside this context.

    * Its ``set_value`` sets Real, Integer and Boolean variables only and raises
      ``Unsupported type: String`` for any String parameter of a ``parameter_set`` (the
      Driveline's ``engine.speed_table``): here it sets Strings with ``fmi2SetString``.
    * ``first_step``: ``simulate_ssp`` exchanges nothing during initialization and starts
      every connector at 0.0, so the first ``doStep`` of each unit gets 0 on every input: a
      pinion at rest while the wheel turns at 44.6 rad/s.  Here the units exchange as a
      master that initializes them in the SSD's order does (the container does so): each
      unit, in initialization mode, gets the outputs of the units initialized before it
      (the Driveline, first, keeps its inputs' start values), and before the first step
      every connection carries what its start unit outputs after initialization.  So the
      first step of each unit gets its partner's outputs at the start time, whatever the
      SSP's bound input starts: a unit whose inputs then differ from those at the end of its
      initialization (the Driveline, when an edited parameter moved the mesh's start) settles
      at its first step (``init.settle_first_step``, fmi2Warning), as it would have done
      during initialization."""
    from fmpy.ssp import simulation
    from fmpy.ssp.ssd import Component

    original_do_step, original_set_value = simulation.do_step, simulation.set_value
    original_instantiate = simulation.instantiate_fmu
    started: set[int] = set()

    def feed(component, initialized) -> None:
        """Set ``component``'s connected inputs to the outputs of the ``initialized`` units."""
        sources = {e.name: e for e in initialized}
        for c in component.parent.connections:
            if c.endElement == component.name and c.startElement in sources:
                value = simulation.get_value(sources[c.startElement], c.startConnector)
                connector = next(k for k in component.connectors if k.name == c.endConnector)
                connector.value = value
                original_set_value(component, c.endConnector, value)

    def instantiate_fmu(component, ssp_unzipdir, start_time, stop_time=None,
                        parameter_set=None):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        filename = str(Path(ssp_unzipdir) / component.source)
        md = read_model_description(filename, validate=False)
        if md.fmiVersion != "2.0":
            return original_instantiate(component, ssp_unzipdir, start_time, stop_time,
                                        parameter_set)
        component.unzipdir = extract(filename)
        component.variables = {v.name: v for v in md.modelVariables}
        component.fmu = FMU2Slave(guid=md.guid, unzipDirectory=component.unzipdir,
                                  modelIdentifier=md.coSimulation.modelIdentifier,
                                  instanceName=component.name)
        component.fmu.instantiate()
        component.fmu.setupExperiment(startTime=start_time)
        if parameter_set is not None:
            simulation.set_parameters(component, parameter_set)
        component.fmu.enterInitializationMode()
        siblings = [e for e in component.parent.elements if isinstance(e, Component)]
        feed(component, [e for e in siblings[:siblings.index(component)]
                         if getattr(e, "fmu", None) is not None])
        component.fmu.exitInitializationMode()

    def do_step(component, time, step_size):
        system = component.parent
        if id(system) not in started:
            started.add(id(system))
            units = [e for e in system.elements if isinstance(e, Component)]
            for unit in units:
                feed(unit, units)
        original_do_step(component, time, step_size)

    def set_value(component, name, value):
        variable = component.variables[name]
        if variable.type == "String":
            component.fmu.setString([variable.valueReference], [str(value)])
        else:
            original_set_value(component, name, value)

    simulation.set_value = set_value
    if first_step:
        simulation.do_step, simulation.instantiate_fmu = do_step, instantiate_fmu
    try:
        yield
    finally:
        simulation.do_step, simulation.set_value = original_do_step, original_set_value
        simulation.instantiate_fmu = original_instantiate


def fmpy_ssp_keeps_start_values():
    """``fmpy_ssp_workarounds()`` (its former name)."""
    return fmpy_ssp_workarounds()


def fmpy_parameter_set(ssp: Path):
    """The SSD's bindings (``ssp.read_bindings``) as the ``parameter_set`` that
    ``fmpy.ssp.simulate_ssp`` applies (fmpy 0.3.19 to 0.3.32 reads the SSD's bindings but
    never applies them).  Names are ``<Component>.<name>``, as fmpy matches them; values keep
    their Python type, because fmpy sets a Boolean as ``value != 0.0``, which is True for the
    SSV text ``"false"``."""
    from fmpy.ssp.ssd import Parameter, ParameterSet

    kinds = {bool: "Boolean", int: "Integer", float: "Real", str: "String"}
    parameter_set = ParameterSet(name=PARAMETER_SET)
    parameter_set.parameters = [Parameter(name=name, type=kinds[type(value)], value=value)
                                for name, value in read_bindings(ssp).items()]
    return parameter_set


def run_fmpy_ssp(ssp: Path, stop_time: float, step: float, workaround: bool = True,
                 bindings: bool = True, outputs: list[str] | None = None) -> Result:
    """``fmpy.ssp.simulate_ssp`` (accumulated time ``t += step``) with the SSD's bindings
    passed as its ``parameter_set`` (``fmpy_parameter_set``; ``bindings=False``: as fmpy
    runs the SSP by itself, on the FMUs' defaults), inside ``fmpy_ssp_workarounds``
    (``workaround=False``: without its first-step part).  Its rows carry the time at the start of
    each step and the values at its end; the result carries the end times.  ``outputs``:
    connector paths to record (default ``COUPLING``; system connectors by their name)."""
    from fmpy.ssp.simulation import simulate_ssp

    parameter_set = fmpy_parameter_set(ssp) if bindings else None
    with fmpy_ssp_workarounds(first_step=workaround):
        rows = simulate_ssp(str(ssp), stop_time=stop_time, step_size=step,
                            parameter_set=parameter_set)
    return _result([t + step for t in rows["time"]],
                   {name: rows[name] for name in outputs or COUPLING})


# ---------------------------------------------------------------- fmu-manipulation-toolbox
def build_container(ssp: Path, out_dir: Path, bindings: bool = True) -> Path:
    """A container FMU of the SSP's units built by fmu-manipulation-toolbox in ``out_dir``
    (as ``fmucontainer -container DriveRattle.ssp``), with the SSD's connections, and its
    system connectors as the container's outputs.

    fmucontainer reads no parameter binding of the SSD (2.0: only its components and
    connections), so with ``bindings`` every bound value (``ssp.read_bindings``) is added as
    a start value of its unit, the container's ``START`` rule, which the container sets on the
    unit before initializing it.  The links appear as local variables
    ``<unit in lower case>.<output>``."""
    from fmu_manipulation_toolbox.assembly import Assembly

    from .ssp import _value

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    shutil.copy2(ssp, out_dir / Path(ssp).name)
    assembly = Assembly(Path(ssp).name, fmu_directory=out_dir)
    if bindings:
        by_file = {Path(name).name: name for name in assembly.root.fmu_names_list}
        units = {unit: by_file[Path(source).name]
                 for unit, source in component_sources(ssp).items()}
        for qualified, value in read_bindings(ssp).items():
            unit, _, name = qualified.partition(".")
            assembly.root.add_start_value(units[unit], name, _value(value))
    assembly.make_fmu()
    container = out_dir / f"{Path(ssp).stem}.fmu"
    if not container.is_file():
        raise RuntimeError(f"fmu-manipulation-toolbox wrote no {container}")
    return container


def build_container_cli(ssp: Path, out_dir: Path) -> Path:
    """``fmucontainer -container DriveRattle.ssp`` as a user runs it (no bindings applied)."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    shutil.copy2(ssp, out_dir / Path(ssp).name)
    tool = shutil.which("fmucontainer") or str(Path(sys.executable).parent / "fmucontainer")
    run = subprocess.run([tool, "-container", Path(ssp).name, "-fmu-directory", str(out_dir)],
                         cwd=out_dir, capture_output=True, text=True, timeout=300)
    container = out_dir / f"{Path(ssp).stem}.fmu"
    if run.returncode != 0 or not container.is_file():
        raise RuntimeError(f"fmucontainer failed (exit {run.returncode}):\n{run.stdout}"
                           f"{run.stderr}")
    return container


def run_container(container: Path, stop_time: float, step: float, log=None,
                  outputs: list[str] | None = None) -> Result:
    """The container FMU in fmpy's ``simulate_fmu`` (``t_k = k step``), recording the links
    (``COUPLING``, as ``<unit in lower case>.<output>``) and the container's ``outputs``
    (its variables by name); ``log(message)`` receives the messages of the container and its
    units."""
    from fmpy import simulate_fmu

    names = {name: name.split(".", 1)[0].lower() + "." + name.split(".", 1)[1]
             for name in COUPLING}
    names.update({name: name for name in outputs or []})

    def logger(*args):
        if log is not None:
            log(args[-1].decode("utf-8", "replace"))

    rows = simulate_fmu(str(container), stop_time=stop_time, output_interval=step,
                        output=list(names.values()), logger=logger)
    return _result(rows["time"], {name: rows[local] for name, local in names.items()})


# ---------------------------------------------------------------- ecos
def run_ecos(ssp: Path, stop_time: float, step: float, outputs: list[str] | None = None,
             parameter_set: str | None = PARAMETER_SET, log_level: str = "warn") -> Result:
    """Vico's ecos (pip ``ecospy``; Debian's ``libtbb12``) on the SSP: Jacobi fixed step,
    accumulated time ``t += step``, exchanges during initialization (one round per unit).

    ecos applies an SSP parameter set only when it is named (``parameter_set``, the command
    line's ``--parameterSet``): without a name every unit runs on its FMU's defaults, with no
    warning (``parameter_set=None`` does that).  Records ``outputs`` (``"<Unit>.<name>"``,
    default ``COUPLING``; Integer outputs through ``get_integer``) from the start time, after
    initialization."""
    from ecospy import EcosLib, EcosSimulation
    from fmpy import read_model_description

    EcosLib.set_log_level(log_level)
    outputs = outputs or COUPLING
    types = {}
    for unit, source in component_sources(ssp).items():
        with zipfile.ZipFile(ssp) as z:
            data = z.read(source)
        md = read_model_description(io.BytesIO(data))
        types.update({f"{unit}.{v.name}": v.type for v in md.modelVariables})
    sim = EcosSimulation(ssp_path=str(ssp), step_size=step)
    try:
        if not sim.init(parameter_set=parameter_set):
            raise RuntimeError(f"ecos: init failed: {EcosLib.get_last_error()}")
        getters = {name: (sim.get_integer if types[name] in ("Integer", "Enumeration")
                          else sim.get_real,
                          name.replace(".", "::", 1)) for name in outputs}
        result = Result(units=dict.fromkeys(outputs, ""))
        result.columns = {name: [] for name in outputs}
        time = sim.get_time()
        while True:
            result.time.append(time)
            for name, (get, identifier) in getters.items():
                result.columns[name].append(get(identifier))
            if time >= stop_time:
                break
            time = sim.step(1)
        sim.terminate()
        return result
    finally:
        sim.free()


# ---------------------------------------------------------------- gemseo-fmu
def _set_once(variable) -> None:
    """Make a gemseo-fmu variable set its FMU value only when it changes (the first time)."""
    set_value, last = variable.set_value, []

    def set_when_changed(value):
        if not last or not (last[0] == value).all():
            set_value(value)
            last[:] = [value]

    variable.set_value = set_when_changed


def gemseo_system(mesh_fmu: Path, driveline_fmu: Path, stop_time: float, step: float,
                  parameters: dict | None = None):
    """gemseo-fmu's ``TimeSteppingSystem`` of both units (Jacobi, no exchange during
    initialization: the first step gets the inputs' start values).

    Work around two defects of gemseo-fmu 3.1.1: without ``input_names`` it applies
    ``float()`` to every input's and parameter's start value and cannot even construct a unit
    with a Boolean parameter (``could not convert string to float: 'true'``); without
    ``output_names`` it reads every output with ``fmi2GetReal`` and fails on the Integer
    outputs (the impact counters).  So each unit gets its Real coupling inputs and outputs
    explicitly.

    ``parameters`` (``"<Unit>.<name>"``: Real parameters only, gemseo-fmu sets FMI 2
    variables with ``fmi2SetReal``) are set gemseo's way, as inputs of the unit's discipline
    with these values as their defaults.  gemseo-fmu sets every input of a discipline before
    every step, parameters too, and FMI 2.0 allows a fixed parameter to be set only until
    initialization ends: the units refuse the second setting (``fmi2SetReal failed with
    status 3``, ``parameter 'gear.backlash' is fixed``).  So each parameter is set only when
    its value changes, i.e. once, before initialization (``_set_once``).  And since gemseo
    exchanges nothing during initialization, the coupling inputs' defaults are the partner's
    start outputs for these parameters (``ssp.consistent_input_starts``), as the FMUs' start
    values are for the defaults."""
    from gemseo_fmu.disciplines.do_step_fmu_discipline import DoStepFMUDiscipline
    from gemseo_fmu.disciplines.time_stepping_system import TimeSteppingSystem
    from numpy import array

    from .ssp import consistent_input_starts

    logging.getLogger("gemseo").setLevel(logging.ERROR)  # one MDA warning per step
    parameters = parameters or {}
    for qualified, value in parameters.items():
        if type(value) is not float:
            raise ValueError(f"gemseo-fmu sets FMI 2 variables as Real: '{qualified}' = "
                             f"{value!r} cannot be set")
    starts = consistent_input_starts(parameters) if parameters else {}
    units = []
    for unit, path in ((DRIVELINE, driveline_fmu), (MESH, mesh_fmu)):
        own = {k.partition(".")[2]: v for k, v in parameters.items()
               if k.partition(".")[0] == unit}
        discipline = DoStepFMUDiscipline(str(path), input_names=REAL_INPUTS[unit] + list(own),
                                         output_names=REAL_OUTPUTS[unit], name=unit)
        defaults = discipline.io.input_grammar.defaults
        for name, value in own.items():
            defaults[name] = array([value])
            _set_once(discipline._to_fmu_variables[name])
        for name in REAL_INPUTS[unit]:
            if f"{unit}.{name}" in starts:
                defaults[name] = array([starts[f"{unit}.{name}"]])
        units.append(discipline)
    return TimeSteppingSystem(units, final_time=stop_time, time_step=step)


def run_gemseo(mesh_fmu: Path, driveline_fmu: Path, stop_time: float, step: float,
               parameters: dict | None = None) -> Result:
    """Run ``gemseo_system``; the result holds the values after every step."""
    system = gemseo_system(mesh_fmu, driveline_fmu, stop_time, step, parameters)
    system.execute()
    data = system.io.data
    columns = {f"{unit}.{name}": data[name] for unit, names in REAL_OUTPUTS.items()
               for name in names}
    return _result(data[f"{DRIVELINE}_time"], columns)


# ---------------------------------------------------------------- cofmupy
@contextlib.contextmanager
def cofmupy_real_outputs():
    """Inside this context cofmupy (1.0.0) reads only the Real outputs of an FMI 2.0 unit: it
    reads every output with ``fmi2GetReal`` after every step, with no setting to leave some
    out, and the Integer outputs (the impact counters, ``mesh.n_contact``) fail
    (``getReal: no Real variable with value reference ...``)."""
    from cofmupy.wrappers import Fmu2Handler

    original = Fmu2Handler.get_output_names

    def real_outputs(self):
        return [n for n in original(self) if self.var_name2attr[n].type == "Real"]

    Fmu2Handler.get_output_names = real_outputs
    try:
        yield
    finally:
        Fmu2Handler.get_output_names = original


def cofmupy_config(mesh_fmu: Path, driveline_fmu: Path, parameters: dict | None = None) -> dict:
    """cofmupy's configuration of the pair (Jacobi), each unit's ``"initialization"`` holding
    its Real ``parameters`` (``"<Unit>.<name>"``; cofmupy sets every variable with
    ``fmi2SetReal``) and every coupling input at the partner's output at the start for these
    parameters (``ssp.consistent_input_starts``): cofmupy writes 0 to every input that is not in
    ``"initialization"`` before it initializes the units, and exchanges nothing then."""
    from .ssp import consistent_input_starts

    parameters = parameters or {}
    for qualified, value in parameters.items():
        if type(value) is not float:
            raise ValueError(f"cofmupy sets FMI 2 variables as Real: '{qualified}' = "
                             f"{value!r} cannot be set")
    values = {**parameters, **consistent_input_starts(parameters)}
    paths = {MESH: str(mesh_fmu), DRIVELINE: str(driveline_fmu)}
    return {
        "fmus": [{"id": unit, "path": paths[unit],
                  "initialization": {k.partition(".")[2]: v for k, v in values.items()
                                     if k.partition(".")[0] == unit}}
                 for unit in (DRIVELINE, MESH)],
        "connections": [{"source": {"id": src, "variable": out},
                         "target": [{"id": dst, "variable": inp}]}
                        for src, out, dst, inp in CONNECTIONS],
        "cosim_method": "jacobi",
    }


def run_cofmupy(mesh_fmu: Path, driveline_fmu: Path, stop_time: float, step: float,
                parameters: dict | None = None, workarounds: bool = True,
                fixed_point: bool = False) -> Result:
    """cofmupy's ``Coordinator`` on ``cofmupy_config`` inside ``cofmupy_real_outputs``, its
    fixed-point initialization off (``fixed_point``: on; it calls ``fmi2SetupExperiment`` on
    running units, which they refuse: ``setupExperiment is not allowed in mode
    'stepping'``).  ``workarounds=False``: the configuration without the input starts, and
    every output read.  Accumulated time ``t += step``; the result holds the values after
    every step, at the step's end."""
    from cofmupy.coordinator import Coordinator

    config = cofmupy_config(mesh_fmu, driveline_fmu, parameters)
    if not workarounds:
        for unit in config["fmus"]:
            unit["initialization"] = {k: v for k, v in unit["initialization"].items()
                                      if k not in REAL_INPUTS[unit["id"]]}
    outputs = cofmupy_real_outputs() if workarounds else contextlib.nullcontext()
    with outputs:
        coordinator = Coordinator()
        coordinator.start(config, fixed_point_init=fixed_point)
        while coordinator.master.current_time < stop_time:
            coordinator.do_step(step)
        rows = coordinator.get_results()
    return _result([t + step for t in rows["time"]],
                   {name: rows[tuple(name.split(".", 1))] for name in COUPLING})


# ---------------------------------------------------------------- pathsim-fmi
def pathsim_system(mesh_fmu: Path, driveline_fmu: Path, step: float,
                   parameters: dict | None = None):
    """``(simulation, scope)``: pathsim-fmi's ``CoSimulationFMU`` blocks of both units, the
    mesh first, connected as ``CONNECTIONS``, and a ``Scope`` recording ``COUPLING``.

    pathsim-fmi 0.1.1 (on pathsim 0.27) reads every output with fmi2GetReal/fmi3GetFloat64 and
    fails at construction on an FMU with an Integer output (give it ``variants.real_outputs``
    copies); it takes the default experiment's step as the string fmpy reads (``TypeError``
    in its schedule), so ``step`` is passed as ``dt``; it sets ``parameters``
    (``"<Unit>.<name>"``: Real, Integer, Boolean) during initialization and exchanges nothing
    then.  At each communication point it steps the blocks one after the other, each from the
    outputs of the blocks before it (Gauss-Seidel in the order of the blocks): the mesh steps
    from the Driveline's outputs at the point, the Driveline from the mesh's at the step's end,
    and at its first step settles behind them (``init.settle_first_step``, fmi2Warning)."""
    from pathsim import Connection, Simulation
    from pathsim.blocks import Scope
    from pathsim_fmi import CoSimulationFMU

    parameters = parameters or {}
    blocks = {}
    for unit, path in ((MESH, mesh_fmu), (DRIVELINE, driveline_fmu)):
        own = {k.partition(".")[2]: v for k, v in parameters.items()
               if k.partition(".")[0] == unit}
        blocks[unit] = CoSimulationFMU(str(path), instance_name=unit, start_values=own or None,
                                       dt=step)
    scope = Scope(labels=COUPLING)
    links = [Connection(blocks[src][out], blocks[dst][inp]) for src, out, dst, inp in CONNECTIONS]
    links += [Connection(blocks[src][out], scope[k])
              for k, (src, out, _, _) in enumerate(CONNECTIONS)]
    return Simulation([*blocks.values(), scope], links, dt=step, log=False), scope


def run_pathsim(mesh_fmu: Path, driveline_fmu: Path, stop_time: float, step: float,
                parameters: dict | None = None, copy_to: Path | None = None) -> Result:
    """``pathsim_system`` run to ``stop_time``; ``copy_to``: the ``variants.real_outputs``
    copies of the FMUs written into this folder and run (None: the FMUs as given).  pathsim's
    ``Scope`` records at its time ``t`` the outputs of the step taken at ``t``: the result
    holds, per communication point ``t_k = k step`` from 0, the coupling signals at the end of
    that step, under pathsim's own clock (``t`` accumulated)."""
    if copy_to is not None:
        mesh_fmu, driveline_fmu = (variants.real_outputs(path, Path(copy_to) / Path(path).name)
                                   for path in (mesh_fmu, driveline_fmu))
    simulation, scope = pathsim_system(mesh_fmu, driveline_fmu, step, parameters)
    simulation.run(stop_time)
    time, data = scope.read()
    return _result(time, dict(zip(COUPLING, data, strict=True)))


# ---------------------------------------------------------------- fmpy alone
def run_alone(fmu: Path, stop_time: float | None = None) -> tuple[Result, float]:
    """One FMU in fmpy's ``simulate_fmu`` with its defaults (as ``fmpy simulate X.fmu``): no
    input set, the default experiment's step doubled until at most 1000 steps.  Returns the
    recorded outputs and the step fmpy chose."""
    from fmpy import read_model_description, simulate_fmu

    md = read_model_description(str(fmu))
    rows = simulate_fmu(str(fmu), stop_time=stop_time)
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    return (_result(rows["time"], {name: rows[name] for name in outputs}),
            float(rows["time"][1] - rows["time"][0]))


#: The copies of ``python -m drive_rattle_cosim.masters COMMAND SOURCE TARGET``.
COPIES = {
    "integer-codes": (variants.integer_codes,
                      "a copy of an FMU or SSP whose integer codes (FMI enumerations) are "
                      "declared integers: for libcosim and ecos, which ignore FMI 2.0 "
                      "enumerations (the SSPs of the build are such copies already)"),
    "real-outputs": (variants.real_outputs,
                     "a copy of an FMU whose outputs are all floats (the integer counters "
                     "local variables) and whose integer codes are integers: for masters "
                     "that read every output as a float (pathsim-fmi)"),
}


def main(argv=None) -> int:
    import argparse

    ap = argparse.ArgumentParser(prog="python -m drive_rattle_cosim.masters",
                                 description="Copies of the FMUs for masters with defects of "
                                             "their own (docs/tools.md).")
    sub = ap.add_subparsers(dest="command", required=True)
    for command, (_, text) in COPIES.items():
        copy = sub.add_parser(command, help=text, description=text)
        copy.add_argument("source", type=Path, help="an .fmu or .ssp file")
        copy.add_argument("target", type=Path, help="the copy to write")
    args = ap.parse_args(argv)
    try:
        target = COPIES[args.command][0](args.source, args.target)
    except ValueError as err:
        ap.exit(2, f"{ap.prog} {args.command}: {err}\n")
    print(f"wrote {target}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
