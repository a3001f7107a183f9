"""Co-simulation of GearMeshRattle and Driveline on fmpy's low-level FMI 2.0 and FMI 3.0 APIs
(``FMU2Slave``, ``FMU3Slave``).

Fixed communication step, Jacobi coupling (both units step from the outputs of the last
communication point) along ``drive_rattle.interface.CONNECTIONS``, the same as libcosim's
fixed-step algorithm and as the in-process twin ``drive_rattle_cosim.system.simulate``.
Communication points are integer nanoseconds, ``t_k = (t0_ns + k step_ns) / 1e9``, and each
step is ``t_{k+1} - t_k``, as libcosim computes them, so the three agree bit for bit.

Each unit is driven through the adapter of its FMU's standard (``FMI2``, ``FMI3``: read from
the modelDescription's ``fmiVersion``), which is all that differs between them: the names of
the typed get/set calls (FMI 2.0 Real, Integer, an Enumeration as an Integer; FMI 3.0
Float64, Int32, an Enumeration as an Int64), the ``nValues`` argument of FMI 3.0's, the
initialization calls (``fmi2SetupExperiment`` + ``fmi2EnterInitializationMode``;
``fmi3EnterInitializationMode`` with the start time), ``fmi3DoStep``'s outputs (a request to
terminate or an early return ends the run with an error) and the logger.  One loop drives
both, so the FMI 3.0 FMUs give the FMI 2.0 FMUs' numbers bit for bit (tested).  Each FMU is
unpacked into a temporary folder of its own, removed on every way out (a failed load
included).

Python::

    from drive_rattle_cosim.harness import CoSimulation
    with CoSimulation("dist/GearMeshRattle.fmu", "dist/Driveline.fmu",
                      parameters={"GearMeshRattle.gear.backlash": 0.12e-3}) as sim:
        result = sim.run(stop_time=0.5, outputs=["GearMeshRattle.wheel.w"])
    result.to_csv("out/run.csv")

Command line: ``python -m drive_rattle_cosim.harness --help``.
"""

from __future__ import annotations

import contextlib
import csv
import functools
import itertools
import math
import os
import shutil
import sys
import tempfile
import threading
from ctypes import byref, c_bool, c_double, c_int, c_int32, c_int64, c_uint
from dataclasses import dataclass, field
from pathlib import Path
from typing import ClassVar

import fmpy
from fmpy import extract, read_model_description

from drive_rattle.interface import CONNECTIONS, DRIVELINE, MESH

from .paths import DIST
from .system import communication_points, step_nanoseconds

#: Rounds of output-to-input exchange in initialization mode (libcosim does one per unit).
INIT_ROUNDS = 2
#: Steps from which on a progress bar is shown when asked for.
PROGRESS_MIN_STEPS = 20_000

_STATUS = ["OK", "Warning", "Discard", "Error", "Fatal", "Pending"]


def _status_name(status: int) -> str:
    return _STATUS[status] if 0 <= status < len(_STATUS) else str(status)


#: Live FMI 2.0 units by FMI instance name: fmpy's native logger proxy keeps a single Python
#: logger per process, so one callback serves every FMI 2.0 instance and routes messages by
#: instance name (an FMI 3.0 instance gets a callback of its own).
_INSTANCES: dict[str, Unit] = {}
_CALLBACKS: list = []
#: Held while an instance name is chosen (units may load in several threads).
_NAMES_LOCK = threading.Lock()


def _register_instance(unit: Unit) -> str:
    with _NAMES_LOCK:
        n = 1
        while (name := unit.name if n == 1 else f"{unit.name}#{n}") in _INSTANCES:
            n += 1
        _INSTANCES[name] = unit
    return name


def _log(env, instance, status, category, message) -> None:
    unit = _INSTANCES.get(instance.decode("utf-8", "replace") if instance else "")
    if unit is not None:
        unit.messages.append((_status_name(status), message.decode("utf-8", "replace")))


def _callbacks():
    """The process-wide FMI 2.0 callback struct (logger formatted natively by fmpy's proxy)."""
    from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackLoggerTYPE

    if not _CALLBACKS:
        cb = fmi2CallbackFunctions()
        cb.logger = fmi2CallbackLoggerTYPE(_log)
        with contextlib.suppress(Exception):  # the proxy ships with fmpy on every platform
            from fmpy.logging import addLoggerProxy

            addLoggerProxy(byref(cb))
        _CALLBACKS.append(cb)
    return _CALLBACKS[0]


class CoSimulationError(RuntimeError):
    """A unit refused a call, or an FMU could not be loaded; the message holds the unit's
    logged reason."""


@dataclass
class Variable:
    name: str
    vr: int
    fmi_type: str  # the type of the calls that get and set it: Real, Integer, ... / Float64, ...
    causality: str
    unit: str


def raw_function(slave, name: str):
    """The ctypes function ``name`` of the FMU's library, argument types set by fmpy.

    fmpy >= 0.3.20 keeps them in ``slave._functions``; 0.3.19 (the newest that gemseo-fmu
    accepts) only in the library object, where both versions set them."""
    functions = getattr(slave, "_functions", None)
    return functions[name] if functions is not None else getattr(slave.dll, name)


class FMI2:
    """How the harness drives an FMI 2.0 co-simulation FMU (fmpy's ``FMU2Slave``)."""

    version: ClassVar[str] = "2.0"
    #: The type of the get/set calls of each modelDescription type (an Enumeration is got and
    #: set with fmi2GetInteger / fmi2SetInteger).
    ACCESS: ClassVar[dict] = {"Real": "Real", "Integer": "Integer", "Enumeration": "Integer",
                              "Boolean": "Boolean", "String": "String"}
    #: The C type of each numeric access type, in the order outputs are recorded.
    CTYPES: ClassVar[dict] = {"Real": c_double, "Integer": c_int, "Boolean": c_int}
    #: The access type of the coupling signals.
    FLOAT: ClassVar[str] = "Real"
    #: The folder of this machine's binary (FMI 2.0 section 2.3: binaries/<platform>).
    BINARIES: ClassVar[str] = f"binaries/{fmpy.platform}/"

    @staticmethod
    def load(unit: Unit, md, folder: str):
        from fmpy.fmi2 import FMU2Slave

        unit.instance_name = _register_instance(unit)
        slave = FMU2Slave(guid=md.guid, unzipDirectory=folder,
                          modelIdentifier=unit.model_name, instanceName=unit.instance_name)
        unit.slave = slave
        slave.instantiate(callbacks=_callbacks(), loggingOn=False)
        return slave

    @staticmethod
    def unload(unit: Unit) -> None:
        _INSTANCES.pop(unit.instance_name, None)

    @staticmethod
    def enter_initialization(unit: Unit, start_time: float) -> None:
        unit.call("setupExperiment", unit.slave.setupExperiment, None, start_time)
        unit.call("enterInitializationMode", unit.slave.enterInitializationMode)

    @staticmethod
    def bind(function, component, vrs, n: int, values):
        """The raw get or set of ``n`` values at ``vrs``, as a call of no arguments."""
        return functools.partial(function, component, vrs, n, values)

    @staticmethod
    def stepper(unit: Unit):
        """``(doStep, component, the arguments after the step size, flags)``: an FMI 2.0 step
        reports nothing beside its status."""
        return raw_function(unit.slave, "fmi2DoStep"), unit.slave.component, (1,), ()


class FMI3:
    """How the harness drives an FMI 3.0 co-simulation FMU (fmpy's ``FMU3Slave``): no event
    mode, no early return, no intermediate update."""

    version: ClassVar[str] = "3.0"
    ACCESS: ClassVar[dict] = {"Float64": "Float64", "Int32": "Int32", "Int64": "Int64",
                              "Enumeration": "Int64", "Boolean": "Boolean", "String": "String"}
    CTYPES: ClassVar[dict] = {"Float64": c_double, "Int32": c_int32, "Int64": c_int64,
                              "Boolean": c_bool}
    FLOAT: ClassVar[str] = "Float64"
    #: The folder of this machine's binary (FMI 3.0 section 2.5.1: the platform tuple).
    BINARIES: ClassVar[str] = f"binaries/{fmpy.platform_tuple}/"

    @staticmethod
    def load(unit: Unit, md, folder: str):
        from fmpy.fmi3 import FMU3Slave

        def log(env, status, category, message):
            unit.messages.append((_status_name(status),
                                  message.decode("utf-8", "replace") if message else ""))

        unit.instance_name = unit.name
        slave = FMU3Slave(guid=md.guid, unzipDirectory=folder, modelIdentifier=unit.model_name,
                          instanceName=unit.instance_name)
        unit.slave = slave
        slave.instantiate(loggingOn=False, logMessage=log)
        return slave

    @staticmethod
    def unload(unit: Unit) -> None:
        pass

    @staticmethod
    def enter_initialization(unit: Unit, start_time: float) -> None:
        unit.call("enterInitializationMode",
                  functools.partial(unit.slave.enterInitializationMode, startTime=start_time))

    @staticmethod
    def bind(function, component, vrs, n: int, values):
        return functools.partial(function, component, vrs, n, values, n)

    @staticmethod
    def stepper(unit: Unit):
        """fmi3DoStep's outputs: ``flags`` (a request to terminate, an early return) end the
        run; the event flag cannot be set without event mode."""
        event, terminate, early, last = c_bool(), c_bool(), c_bool(), c_double()
        return (raw_function(unit.slave, "fmi3DoStep"), unit.slave.component,
                (True, byref(event), byref(terminate), byref(early), byref(last)),
                (terminate, early))


#: The adapters by the major version of ``fmiVersion``.
STANDARDS = {"2": FMI2, "3": FMI3}


def loaded_member(binaries: str, name: str) -> bool:
    """Whether the FMU's member ``name`` is one an instance loads: the modelDescription, the
    resources, and the binary in the folder ``binaries`` (this machine's)."""
    return (name == "modelDescription.xml" or name.startswith("resources/")
            or name.startswith(binaries))


def standard_of(md, fmu: Path):
    """The adapter of a modelDescription's FMI version (CoSimulationError for another
    version or an FMU that is not for co-simulation)."""
    standard = STANDARDS.get(str(md.fmiVersion).split(".")[0])
    if standard is None:
        raise CoSimulationError(f"{fmu} is an FMI {md.fmiVersion} FMU; allowed: FMI 2.0 or "
                                "3.0 co-simulation FMUs")
    if md.coSimulation is None:
        raise CoSimulationError(f"{fmu} has no co-simulation interface; allowed: FMI 2.0 or "
                                "3.0 co-simulation FMUs")
    return standard


class _Raw:
    """The prepared get or set of a fixed list of value references: the raw function bound to
    the component, the reference array and a preallocated value array, called with no
    arguments (``get()``, ``put()``); ``values``: an array to share (a coupling's set takes
    the values its get wrote)."""

    def __init__(self, unit: Unit, fmi_type: str, vrs: list[int], values=None):
        n = len(vrs)
        standard = unit.standard
        self.unit, self.fmi_type, self.n = unit, fmi_type, n
        self.vrs = (c_uint * n)(*vrs)
        self.values = (standard.CTYPES[fmi_type] * n)() if values is None else values
        prefix = f"fmi{standard.version[0]}"
        component = unit.slave.component
        self.get = standard.bind(raw_function(unit.slave, f"{prefix}Get{fmi_type}"), component,
                                 self.vrs, n, self.values)
        self.put = standard.bind(raw_function(unit.slave, f"{prefix}Set{fmi_type}"), component,
                                 self.vrs, n, self.values)


class Unit:
    """One FMU instance (FMI 2.0 or 3.0) with name-based, typed access.  Its FMU is unpacked
    into a temporary folder of its own, removed by :meth:`close` and on a failed load."""

    def __init__(self, fmu: Path, instance_name: str):
        self.name = instance_name
        self.instance_name = instance_name
        self.fmu = Path(fmu)
        self.slave = None
        self.messages: list[tuple[str, str]] = []  # (status, message) from the logger
        self._freed = False
        self._stepper = None
        if not self.fmu.is_file():
            raise FileNotFoundError(f"FMU {self.fmu} does not exist (build it with build_fmu.py)")
        try:
            md = read_model_description(str(self.fmu))
        except Exception as err:
            raise CoSimulationError(f"{self.name}: {self.fmu} is not a readable FMU ({err}); "
                                    "allowed: an FMI 2.0 or 3.0 co-simulation FMU") from None
        self.standard = standard_of(md, self.fmu)
        self.fmi_version = md.fmiVersion
        self.model_name = md.coSimulation.modelIdentifier
        access = self.standard.ACCESS
        self.variables = {v.name: Variable(v.name, v.valueReference, access.get(v.type, v.type),
                                           v.causality, v.unit or "")
                          for v in md.modelVariables}
        self._dir = tempfile.mkdtemp(prefix=f"drive_rattle_{self.model_name}_")
        cwd = os.getcwd()
        try:
            # what an instance loads alone: this machine's binary and the resources (the
            # other platforms' binaries and the sources would double the unpacking's cost)
            extract(str(self.fmu), self._dir,
                    include=functools.partial(loaded_member, self.standard.BINARIES))
            self.standard.load(self, md, self._dir)
        except BaseException as err:
            # fmpy changes into the binaries' folder to load them and stays there when the
            # load fails: back to where we were before that folder goes
            with contextlib.suppress(OSError):
                os.chdir(cwd)
            self._release()
            if isinstance(err, Exception):
                reason = f"; the FMU logged: {self.messages[-1][1]}" if self.messages else ""
                raise CoSimulationError(f"{self.name}: cannot load {self.fmu}: {err}{reason}"
                                        ) from None
            raise

    def _release(self) -> None:
        """Everything the load took: the library, the instance registry, the folder."""
        if self.slave is not None:
            with contextlib.suppress(Exception):
                self.slave.freeLibrary()
        self.standard.unload(self)
        self._freed = True
        shutil.rmtree(self._dir, ignore_errors=True)

    def call(self, what: str, fn, *args):
        """Call an fmpy method; an FMI error becomes CoSimulationError with the logged reason."""
        from fmpy.fmi1 import FMICallException

        try:
            return fn(*args)
        except FMICallException as err:
            self.fail(what, err.status)

    def fail(self, what: str, status: int):
        """Raise CoSimulationError for a call that returned ``status``, with the logged reason."""
        reason = self.messages[-1][1] if self.messages else "no message logged"
        raise CoSimulationError(f"{self.name}: {what} returned {_status_name(status)}: {reason}")

    def var(self, name: str) -> Variable:
        try:
            return self.variables[name]
        except KeyError:
            raise KeyError(f"{self.name} has no variable '{name}'") from None

    def set(self, values: dict) -> None:
        """Set variables by name, grouped by type."""
        groups: dict[str, tuple[list, list]] = {}
        for name, value in values.items():
            v = self.var(name)
            vrs, vals = groups.setdefault(v.fmi_type, ([], []))
            vrs.append(v.vr)
            vals.append(value)
        for fmi_type, (vrs, vals) in groups.items():
            self.call(f"set{fmi_type}", getattr(self.slave, f"set{fmi_type}"), vrs, vals)

    def get(self, names) -> list:
        """The values of the variables ``names``, in order."""
        out = []
        for name in names:
            v = self.var(name)
            out += self.call(f"get{v.fmi_type}", getattr(self.slave, f"get{v.fmi_type}"), [v.vr])
        return out

    def enter_initialization(self, start_time: float) -> None:
        self.standard.enter_initialization(self, start_time)

    def exit_initialization(self) -> None:
        self.call("exitInitializationMode", self.slave.exitInitializationMode)

    def stepper(self):
        """``(doStep, component, the arguments after the step size, flags)``: the raw step
        of this unit's standard (:meth:`FMI2.stepper`, :meth:`FMI3.stepper`), made once."""
        if self._stepper is None:
            self._stepper = self.standard.stepper(self)
        return self._stepper

    def do_step(self, t: float, h: float) -> None:
        """One communication step from ``t`` [s] of ``h`` [s] (CoSimulationError when it is
        refused, the unit asks to terminate or returns early)."""
        do_step, component, tail, flags = self.stepper()
        self.check_step(t, do_step(component, t, h, *tail), flags)

    def check_step(self, t: float, status: int, flags) -> None:
        """CoSimulationError for a step from ``t`` that returned ``status > 1`` or raised a
        flag (FMI 3.0: a request to terminate, an early return)."""
        if status > 1:
            self.fail(f"doStep at t = {t!r} s", status)
        if flags and (flags[0].value or flags[1].value):
            what = "asked to terminate" if flags[0].value else "returned early"
            raise CoSimulationError(f"{self.name}: doStep at t = {t!r} s {what}; allowed: "
                                    "every step to its end")

    def close(self) -> None:
        if not self._freed:
            self._freed = True
            try:
                # terminate after a failed call may be refused; free the instance anyway
                with contextlib.suppress(Exception):
                    self.slave.terminate()
                self.slave.freeInstance()
            finally:
                self.standard.unload(self)
                shutil.rmtree(self._dir, ignore_errors=True)


@dataclass
class Result:
    """Recorded communication points: ``time`` [s] and one column per recorded variable."""

    time: list[float] = field(default_factory=list)
    columns: dict[str, list] = field(default_factory=dict)
    units: dict[str, str] = field(default_factory=dict)

    def __getitem__(self, name: str) -> list:
        return self.columns[name]

    def to_csv(self, path) -> Path:
        """Write ``time [s]`` and every column with its unit in the header."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        names = list(self.columns)
        with path.open("w", newline="", encoding="utf-8") as f:
            w = csv.writer(f)
            w.writerow(["time [s]"] + [f"{n} [{self.units[n]}]" for n in names])
            for k, t in enumerate(self.time):
                w.writerow([repr(t)] + [repr(self.columns[n][k]) for n in names])
        return path


class CoSimulation:
    """The mesh and the driveline FMUs, coupled by ``CONNECTIONS``.

    ``parameters`` maps ``"<Unit>.<variable>"`` to values; they are set before initialization.
    """

    def __init__(self, mesh_fmu, driveline_fmu, parameters: dict | None = None,
                 start_time: float = 0.0, step: float = 1e-4):
        self.start_time, self.step = start_time, step
        self.units: dict[str, Unit] = {}
        try:
            self.units[MESH] = Unit(mesh_fmu, MESH)
            self.units[DRIVELINE] = Unit(driveline_fmu, DRIVELINE)
            self._initialize(parameters or {})
        except BaseException:
            self.close()
            raise

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self) -> None:
        for u in self.units.values():
            u.close()

    def _split(self, qualified: str) -> tuple[Unit, str]:
        unit, _, name = qualified.partition(".")
        if unit not in self.units or not name:
            raise KeyError(f"'{qualified}' must be '<unit>.<variable>' with unit one of "
                           f"{', '.join(self.units)}")
        return self.units[unit], name

    def _initialize(self, parameters: dict) -> None:
        per_unit: dict[str, dict] = {u: {} for u in self.units}
        for qualified, value in parameters.items():
            unit, name = self._split(qualified)
            if unit.var(name).causality != "parameter":
                raise KeyError(f"'{qualified}' is not a parameter")
            per_unit[unit.name][name] = value
        for u in self.units.values():
            u.set(per_unit[u.name])
            u.enter_initialization(self.start_time)
        self._plan = self._transfer_plan()
        for _ in range(INIT_ROUNDS):
            self._transfer()
        for u in self.units.values():
            u.exit_initialization()
        self.time = self.start_time
        self._k = 0

    def _transfer_plan(self) -> list[tuple[Unit, list[int], Unit, list[int]]]:
        """Per (source, destination) pair, sources in unit order: output and input value
        references, in order."""
        pairs: dict[tuple[str, str], tuple[list[int], list[int]]] = {}
        for unit in self.units:
            for src, out, dst, inp in CONNECTIONS:
                if src == unit:
                    outs, ins = pairs.setdefault((src, dst), ([], []))
                    outs.append(self.units[src].var(out).vr)
                    ins.append(self.units[dst].var(inp).vr)
        return [(self.units[s], outs, self.units[d], ins) for (s, d), (outs, ins) in pairs.items()]

    def _transfer(self) -> None:
        """One output-to-input exchange along the plan (initialization mode)."""
        for src, outs, dst, ins in self._plan:
            get, put = f"get{src.standard.FLOAT}", f"set{dst.standard.FLOAT}"
            dst.call(put, getattr(dst.slave, put), ins,
                     src.call(get, getattr(src.slave, get), outs))

    def run(self, stop_time: float, outputs=None, progress: bool = False,
            grid: str | tuple[list[float], list[float]] = "nanoseconds") -> Result:
        """Step to ``stop_time`` [s], recording ``outputs`` (``"<Unit>.<output>"``; default:
        every output of both units) at every communication point, the current one first.

        ``grid`` places the communication points as a master does: a name of ``time_grid``
        (the default integer nanoseconds of libcosim, or the time sums of other masters) or
        explicit ``(points, step sizes)`` from the current time, so that a master's run can be
        compared with this one bit for bit."""
        if outputs is None:
            outputs = [f"{u.name}.{v.name}" for u in self.units.values()
                       for v in u.variables.values() if v.causality == "output"]
        rec = []  # (unit, FMI type, [vrs], [qualified names])
        for u in self.units.values():
            for fmi_type in u.standard.CTYPES:
                names = [o for o in outputs if self._split(o)[0] is u
                         and u.var(self._split(o)[1]).fmi_type == fmi_type]
                if names:
                    rec.append((u, fmi_type, [u.var(self._split(o)[1]).vr for o in names],
                                names))
        result = Result(units={o: self._split(o)[0].var(self._split(o)[1]).unit or "1"
                               for o in outputs})
        result.columns = {o: [] for o in outputs}
        if isinstance(grid, str):
            points, sizes = time_grid(self.time, self.step, stop_time, grid)
        else:
            points, sizes = (list(x) for x in grid)
            if not (points and points[0] == self.time and len(sizes) == len(points) - 1):
                raise ValueError("grid: expected (points from the current time, one step size "
                                 "fewer)")
        steps = range(len(points))
        if progress and len(points) > PROGRESS_MIN_STEPS:
            from tqdm import tqdm

            steps = tqdm(steps, unit="step", desc="co-simulation", mininterval=0.5,
                         disable=None)  # no bar where stderr is not a terminal
        # Hot loop on the FMUs' raw ctypes functions with preallocated arrays (fmpy's
        # convenience wrappers cost several microseconds per call), the arguments bound
        # once, a row per recorded type and point (turned into columns at the end).
        raw_rec = [_Raw(u, fmi_type, vrs) for u, fmi_type, vrs, _ in rec]
        recorders = [(r.get, r.values, r) for r in raw_rec]
        rows: list[list] = [[] for _ in raw_rec]
        exchanges = []
        for src, outs, dst, ins in self._plan:
            a = _Raw(src, src.standard.FLOAT, outs)
            b = _Raw(dst, dst.standard.FLOAT, ins, values=a.values)  # both C doubles
            exchanges.append((a.get, a, b.put, b))
        steppers = [(*u.stepper(), u) for u in self.units.values()]
        last = len(points) - 1
        done = 0
        try:
            for k in steps:
                for (get, values, raw), out in zip(recorders, rows, strict=True):
                    status = get()
                    if status > 1:
                        raw.unit.fail(f"get{raw.fmi_type}", status)
                    out.append(values[:])
                if k == last:
                    break
                for get, a, put, b in exchanges:
                    status = get()
                    if status > 1:
                        a.unit.fail(f"get{a.fmi_type}", status)
                    status = put()
                    if status > 1:
                        b.unit.fail(f"set{b.fmi_type}", status)
                t, h = points[k], sizes[k]
                for do_step, component, tail, flags, u in steppers:
                    status = do_step(component, t, h, *tail)
                    if status > 1 or flags:
                        u.check_step(t, status, flags)
                done = k + 1
        finally:
            self.time = points[done]
        result.time = list(points[:done + 1])
        for (_, fmi_type, _, names), out in zip(rec, rows, strict=True):
            for name, column in zip(names, zip(*out, strict=True), strict=True):
                result.columns[name] = ([bool(v) for v in column] if fmi_type == "Boolean"
                                        else list(column))
        return result


#: How masters place communication points (``time_grid``).
GRIDS = ("nanoseconds", "accumulated", "accumulated-clipped", "multiplied", "fmpy")


def steps_between(points: list[float]) -> list[float]:
    """The step sizes of a master that steps from each point to the next: ``t_{k+1} - t_k``
    in floating point (what libcosim and fmpy's ``simulate_fmu`` pass; read a master's points
    from its own result and get its steps from them)."""
    return [b - a for a, b in itertools.pairwise(points)]


def time_grid(start: float, step: float, stop: float,
              grid: str = "nanoseconds") -> tuple[list[float], list[float]]:
    """``(points, sizes)``: the communication points from ``start`` to ``stop`` [s] and the
    step size passed at each (one fewer), as a master computes them:

    * ``"nanoseconds"``: ``t_k = (t0_ns + k step_ns)/1e9``, each step ``t_{k+1} - t_k``
      (libcosim, this harness, ``drive_rattle_cosim.system.simulate``);
    * ``"accumulated"``: ``t_{k+1} = t_k + step`` while ``t_k < stop``, every step ``step``
      (fmpy's SSP runner);
    * ``"accumulated-clipped"``: ``t_{k+1} = t_k + min(step, stop - t_k)`` while
      ``t_k < stop``, each step ``min(step, t_{k+1} - t_k)`` (gemseo-fmu's
      ``TimeSteppingSystem``; its last step can be a rounding residue of 1e-14 s);
    * ``"multiplied"``: ``t_k = start + k step``, every step ``step`` but a last one that
      ends at ``stop`` (fmu-manipulation-toolbox's container inside);
    * ``"fmpy"``: ``t_k = start + k step``, each step ``t_{k+1} - t_k`` (fmpy 0.3.32's
      ``simulate_fmu``: ``steps_between`` its points).

    The sums end at the first point at or past ``stop``."""
    if grid == "nanoseconds":
        points = communication_points(start, step, stop)
        return points, steps_between(points)
    if grid not in GRIDS:
        raise ValueError(f"grid = {grid!r}; allowed: {', '.join(GRIDS)}")
    if not (step > 0.0 and stop - start < 1e9 * step):
        raise ValueError(f"communication step {step!r} s is invalid for {start!r}..{stop!r} s")
    if grid == "fmpy":
        points = time_grid(start, step, stop, "multiplied")[0]
        return points, steps_between(points)
    points, sizes = [start], []
    while (t := points[-1]) < stop:
        if grid == "accumulated":
            points.append(t + step)
            sizes.append(step)
        elif grid == "multiplied":
            if t + step <= stop:
                points.append(start + len(points) * step)
                sizes.append(step)
            else:  # the last step ends at stop
                points.append(stop)
                sizes.append(stop - t)
        else:
            points.append(t + min(step, stop - t))
            sizes.append(min(step, points[-1] - t))
    return points, sizes


def main(argv=None) -> int:
    """The command line: exit status 0 on success, 1 when a unit refused a call during the
    run, 2 for a request refused before any work (one line on stderr)."""
    from drive_rattle.catalog import check_settings, parse_settings

    from .cli import Parser

    ap = Parser(
        prog="python -m drive_rattle_cosim.harness",
        description="Co-simulate GearMeshRattle with Driveline (fmpy, fixed step, Jacobi).")
    ap.add_argument("--mesh", type=Path, default=DIST / f"{MESH}.fmu")
    ap.add_argument("--driveline", type=Path, default=DIST / f"{DRIVELINE}.fmu")
    ap.add_argument("--start-time", type=float, default=0.0, help="[s]")
    ap.add_argument("--stop-time", type=float, default=0.1, help="[s]")
    ap.add_argument("--step", type=float, default=1e-4, help="communication step [s]")
    ap.add_argument("--set", action="append", default=[], metavar="UNIT.NAME=VALUE",
                    help="parameter value by its declared type (SI units), e.g. "
                         "GearMeshRattle.gear.backlash=1.2e-4; an enumeration by its code or "
                         "item name (GearMeshRattle.contact.dissipation=none), a Boolean "
                         "true/false; checked with the model library before the run")
    ap.add_argument("--record", action="append", default=None, metavar="UNIT.OUTPUT",
                    help="output to record (repeatable; default: all outputs)")
    ap.add_argument("--out", type=Path, default=Path("out") / "cosim.csv", help="result CSV")
    ap.add_argument("--no-progress", action="store_true")
    args = ap.parse_args(argv)
    try:
        params = parse_settings(args.set)
        check_settings(params)
        step_nanoseconds(args.step)
        if not (math.isfinite(args.start_time) and math.isfinite(args.stop_time)
                and args.stop_time > args.start_time):
            raise ValueError(f"--stop-time {args.stop_time!r} s after --start-time "
                             f"{args.start_time!r} s; allowed: finite times, stop after start")
    except ValueError as err:
        ap.error(str(err))
    try:
        with CoSimulation(args.mesh, args.driveline, params, args.start_time, args.step) as sim:
            result = sim.run(args.stop_time, args.record, progress=not args.no_progress)
    except (CoSimulationError, KeyError, ValueError, FileNotFoundError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 1
    path = result.to_csv(args.out)
    print(f"wrote {len(result.time)} points x {len(result.columns)} outputs to {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

