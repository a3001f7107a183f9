"""The system in other FMI 2.0 masters, with the workarounds their own defects need.

Each ``run_*`` function runs the system (``dist/DriveRattle.ssp`` or the two FMUs) in one
master and returns a ``harness.Result`` holding the coupling signals (``"<Unit>.<output>"`` of
``drive_rattle.interface.CONNECTIONS``) at the communication points the master computed.
Each master places its points with its own arithmetic (``MASTER_GRIDS``,
``harness.time_grid``): the harness run on the same grid gives the same numbers bit for bit
(tests/cosim/test_masters.py), so these functions are also the reference for what each master
computes.  docs/tools.md explains each workaround for users of the masters directly.

Measured with fmpy 0.3.19 (the newest gemseo-fmu accepts), fmu-manipulation-toolbox 2.0 and
gemseo-fmu 3.1.1.  Run one master per process where a master can abort at exit (libcosim and
fmpy in one process).
"""

from __future__ import annotations

import contextlib
import logging
import shutil
import subprocess
import sys
from pathlib import Path

from drive_rattle.interface import CONNECTIONS, DRIVELINE, MESH

from .harness import Result

#: The coupling signals every master exchanges, ``"<Unit>.<output>"``.
COUPLING = [f"{src}.{out}" for src, out, _, _ in CONNECTIONS]
#: ``harness.time_grid`` name of each master's communication points.
MASTER_GRIDS = {"libcosim": "nanoseconds", "fmpy.ssp": "accumulated",
                "container": "multiplied", "gemseo": "accumulated-clipped"}
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
def fmpy_ssp_keeps_start_values():
    """Work around fmpy.ssp's first step (fmpy 0.3.19 to 0.3.32).

    ``fmpy.ssp.simulate_ssp`` exchanges nothing during initialization and starts every
    connector at 0.0, so the first ``doStep`` of each unit gets 0 on every input: a pinion at
    rest while the wheel turns at 44.6 rad/s.  Inside this context each unit's first step
    gets the values its inputs already hold (their start values, which are the partner's
    start outputs), as a master that exchanged during initialization would send."""
    from fmpy.ssp import simulation

    original = simulation.do_step
    started: set[int] = set()

    def do_step(component, time, step_size):
        if id(component) not in started:
            started.add(id(component))
            for connector in component.connectors:
                if connector.kind == "input":
                    connector.value = simulation.get_value(component, connector.name)
        original(component, time, step_size)

    simulation.do_step = do_step
    try:
        yield
    finally:
        simulation.do_step = original


def run_fmpy_ssp(ssp: Path, stop_time: float, step: float, workaround: bool = True) -> Result:
    """``fmpy.ssp.simulate_ssp`` (accumulated time ``t += step``).  Its rows carry the time at
    the start of each step and the values at its end; the result carries the end times."""
    from fmpy.ssp.simulation import simulate_ssp

    context = fmpy_ssp_keeps_start_values() if workaround else contextlib.nullcontext()
    with context:
        rows = simulate_ssp(str(ssp), stop_time=stop_time, step_size=step)
    return _result([t + step for t in rows["time"]], {name: rows[name] for name in COUPLING})


# ---------------------------------------------------------------- fmu-manipulation-toolbox
def build_container(ssp: Path, out_dir: Path) -> Path:
    """``fmucontainer -container DriveRattle.ssp`` in ``out_dir``: a container FMU of both
    units with the SSD's connections (its parameter and input-start bindings are not read).
    The links appear as local variables ``<unit in lower case>.<output>``."""
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


def run_container(container: Path, stop_time: float, step: float, log=None) -> Result:
    """The container FMU in fmpy's ``simulate_fmu`` (``t_k = k step``), recording the links;
    ``log(message)`` receives the messages of the container and its units."""
    from fmpy import simulate_fmu

    names = {name: name.split(".", 1)[0].lower() + "." + name.split(".", 1)[1]
             for name in COUPLING}

    def logger(*args):
        if log is not None:
            log(args[-1].decode("utf-8", "replace"))

    rows = simulate_fmu(str(container), stop_time=stop_time, output_interval=step,
                        output=list(names.values()), logger=logger)
    return _result(rows["time"], {name: rows[local] for name, local in names.items()})


# ---------------------------------------------------------------- gemseo-fmu
def gemseo_system(mesh_fmu: Path, driveline_fmu: Path, stop_time: float, step: float):
    """gemseo-fmu's ``TimeSteppingSystem`` of both units (Jacobi, no exchange during
    initialization: the first step gets the inputs' start values).

    Work around two defects of gemseo-fmu 3.1.1: without ``input_names`` it applies
    ``float()`` to every input's and parameter's start value and cannot even construct a unit
    with a Boolean parameter (``could not convert string to float: 'true'``); without
    ``output_names`` it reads every output with ``fmi2GetReal`` and fails on the Integer
    outputs (the impact counters).  So each unit gets its Real coupling inputs and outputs
    explicitly; parameters stay at their defaults (set them with the FMU's start values or
    through ``input_names`` of Real parameters)."""
    from gemseo_fmu.disciplines.do_step_fmu_discipline import DoStepFMUDiscipline
    from gemseo_fmu.disciplines.time_stepping_system import TimeSteppingSystem

    logging.getLogger("gemseo").setLevel(logging.ERROR)  # one MDA warning per step
    units = [DoStepFMUDiscipline(str(path), input_names=REAL_INPUTS[name],
                                 output_names=REAL_OUTPUTS[name], name=name)
             for name, path in ((DRIVELINE, driveline_fmu), (MESH, mesh_fmu))]
    return TimeSteppingSystem(units, final_time=stop_time, time_step=step)


def run_gemseo(mesh_fmu: Path, driveline_fmu: Path, stop_time: float, step: float) -> Result:
    """Run ``gemseo_system``; the result holds the values after every step."""
    system = gemseo_system(mesh_fmu, driveline_fmu, stop_time, step)
    system.execute()
    data = system.io.data
    columns = {f"{unit}.{name}": data[name] for unit, names in REAL_OUTPUTS.items()
               for name in names}
    return _result(data[f"{DRIVELINE}_time"], columns)


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
