"""The two units of the model library from Python: a :class:`Unit` is driven as an FMU is
(parameters and inputs by public name, initialize, step, outputs, save and restore), through
the same library calls the FMUs make, so it gives their numbers and their messages.

    from drive_rattle import MeshParameters, MeshUnit

    mesh = MeshUnit(MeshParameters(), phi_p=0.0, w_p=86.92, tau_load=0.15)
    report = mesh.step(1e-4, phi_p=0.0, w_p=86.92, a_p=0.0, tau_load=0.15)
    print(mesh.outputs()["wheel.w"], report.events)

A refused call raises :class:`library.ModelError` (a ValueError) with the library's message and
changes nothing; a warning (a first step that settled the wheel) is kept in
:attr:`Unit.warnings`.  Standard library only (the pythonfmu slaves use it too).
"""

from __future__ import annotations

import ctypes
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any, NamedTuple

from . import library
from .library import DRIVELINE, MESH, ModelError

_TYPE_CALLS = {"Real": ("rm_set_real", "rm_get_real", ctypes.c_double),
               "Integer": ("rm_set_integer", "rm_get_integer", ctypes.c_int32),
               "Boolean": ("rm_set_boolean", "rm_get_boolean", ctypes.c_int32),
               "String": ("rm_set_string", "rm_get_string", ctypes.c_char_p)}


class Variable(NamedTuple):
    vr: int
    type: str
    causality: str


_TABLES: dict[int, dict[str, Variable]] = {}


def table(kind: int) -> dict[str, Variable]:
    """Name -> (value reference, type, causality) of a unit kind's variables, from the
    library's tables (generated from the specs)."""
    t = _TABLES.get(kind)
    if t is None:
        t = {v["name"]: Variable(v["vr"], v["type"], v["causality"])
             for v in library.variables(kind)}
        _TABLES[kind] = t
    return t


class Event(NamedTuple):
    """A located contact event of a step."""

    time: float  # from the start of the step [s]
    kind: str  # "onset" (an impact), "release", "reversal" (a pair's friction turns), "pair" (a
    # crowned pair starts or stops carrying load) or "touch" (a contact begun by the inputs
    # on a receding flank at a communication point: not an impact, not counted)
    flank: int  # +1 drive, -1 coast
    speed: float  # normal approach speed d(delta)/dt at the event [m/s]


@dataclass
class StepReport:
    """The located events of the last step (at most ``library.MAX_EVENTS`` kept; ``total``
    counts all) and its cost counters."""

    events: list[Event]
    total: int
    rhs_evaluations: int
    contact_substeps: int

    @property
    def onsets(self) -> list[Event]:
        return [e for e in self.events if e.kind == "onset"]


def _values_of(values) -> dict[str, Any]:
    if values is None:
        return {}
    if hasattr(values, "to_public"):
        return values.to_public()
    return dict(values)


class Unit:
    """One unit of the model library (``library.MESH`` or ``library.DRIVELINE``).

    ``parameters`` (a parameter set or public names to values) and ``inputs`` (public names)
    are set, then, with ``initialize``, the unit is initialized at ``start_time`` [s] (the
    start solved as an FMU solves it at exitInitializationMode).  ``resources`` is the folder
    relative speed-table paths resolve against."""

    def __init__(self, kind: int, parameters=None, inputs: Mapping[str, float] | None = None,
                 *, start_time: float = 0.0, resources: str | None = None,
                 initialize: bool = True):
        self._lib = lib = library.load()
        self.kind = kind
        self.variables = table(kind)
        self.warnings: list[str] = []
        self._ptr = None
        ptr = lib.rm_new(kind, resources.encode() if resources else None)
        if not ptr:
            raise library.LibraryError(f"rm_new({kind}) failed: unknown kind or out of memory")
        self._ptr = ptr
        self._outputs = [n for n, v in self.variables.items() if v.causality == "output"]
        self._real_outputs = [n for n in self._outputs if self.variables[n].type == "Real"]
        self._int_outputs = [n for n in self._outputs if self.variables[n].type == "Integer"]
        self._real_out_vrs = _uints(self.variables[n].vr for n in self._real_outputs)
        self._int_out_vrs = _uints(self.variables[n].vr for n in self._int_outputs)
        self._real_out = (ctypes.c_double * len(self._real_outputs))()
        self._int_out = (ctypes.c_int32 * len(self._int_outputs))()
        self.set(_values_of(parameters))
        self.set(_values_of(inputs))
        if initialize:
            self.initialize(start_time)

    # ------------------------------------------------------------------ calls
    def call(self, name: str, *args) -> int:
        """Call ``name`` of the library on this unit; ModelError with its message on Error."""
        status = getattr(self._lib, name)(self._ptr, *args)
        if status == library.WARNING:
            self.warnings.append(library.message(self._lib, self._ptr))
        elif status != library.OK:
            raise ModelError(library.message(self._lib, self._ptr))
        return status

    def close(self) -> None:
        """Free the unit (also when it is garbage-collected)."""
        if self._ptr:
            self._lib.rm_free(self._ptr)
            self._ptr = None

    def __del__(self):
        if getattr(self, "_ptr", None):
            self.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # ------------------------------------------------------------------ values
    def set(self, values: Mapping[str, Any]) -> None:
        """Set parameters or inputs by public name (one call per type: a refused entry stores
        nothing of its type's call)."""
        by_type: dict[str, tuple[list[int], list]] = {}
        for name, value in values.items():
            v = self.variables.get(name)
            if v is None:
                raise ModelError(f"unknown variable {name!r} of {_unit_name(self.kind)}")
            vrs, vals = by_type.setdefault(v.type, ([], []))
            vrs.append(v.vr)
            if v.type == "String":
                vals.append(str(value).encode("utf-8"))
            elif v.type == "Real":
                vals.append(float(value))
            else:
                vals.append(int(value))
        for fmi_type, (vrs, vals) in by_type.items():
            setter, _, ctype = _TYPE_CALLS[fmi_type]
            self.call(setter, _uints(vrs), len(vrs), (ctype * len(vals))(*vals))

    def get(self, names: Iterable[str]) -> dict[str, Any]:
        """Values by public name (outputs computed as an FMU computes them when read)."""
        out = {}
        for name in names:
            v = self.variables[name]
            _, getter, ctype = _TYPE_CALLS[v.type]
            buf = (ctype * 1)()
            self.call(getter, _uints([v.vr]), 1, buf)
            value = buf[0]
            out[name] = (value.decode() if v.type == "String" else bool(value)
                         if v.type == "Boolean" else value)
        return out

    def outputs(self) -> dict[str, float]:
        """Every output, by public name (Integer outputs as int)."""
        self.call("rm_get_real", self._real_out_vrs, len(self._real_outputs), self._real_out)
        self.call("rm_get_integer", self._int_out_vrs, len(self._int_outputs), self._int_out)
        values = dict(zip(self._real_outputs, self._real_out, strict=True))
        values.update(zip(self._int_outputs, self._int_out, strict=True))
        return {name: values[name] for name in self._outputs}

    # ------------------------------------------------------------------ life cycle
    def initialize(self, start_time: float = 0.0) -> None:
        """setupExperiment, enter and exit initialization: the model built, the start solved."""
        self.call("rm_setup", float(start_time))
        self.call("rm_enter_initialization")
        self.call("rm_exit_initialization")

    @property
    def time(self) -> float:
        """The end of the last accepted step (the start time before the first)."""
        t = ctypes.c_double()
        self.call("rm_last_successful_time", ctypes.byref(t))
        return t.value

    @property
    def phase(self) -> str:
        return library.PHASES[self._lib.rm_phase(self._ptr)]

    def advance(self, h: float, inputs: Mapping[str, float] | None = None, *,
                at: float | None = None) -> None:
        """Set ``inputs`` (public names) and step by ``h`` [s] from the communication point
        ``at`` [s] (default: the current time).  A master's grid passes its own points, which
        can differ from the accumulated time by rounding; time-dependent loads (the engine's
        firing) see the point passed, as in an FMU."""
        if inputs:
            self.set(inputs)
        self.call("rm_do_step", self.time if at is None else float(at), float(h))

    def report(self) -> StepReport:
        """The events and cost of the last accepted step."""
        r = library.RmStepReport()
        self._lib.rm_step_report(self._ptr, ctypes.byref(r))
        events = [Event(r.events[k].time, library.EVENT_KINDS[r.events[k].kind],
                        r.events[k].flank, r.events[k].speed) for k in range(r.count)]
        return StepReport(events, int(r.total), int(r.rhs_evaluations), int(r.contact_substeps))

    def terminate(self) -> None:
        self.call("rm_terminate")

    def reset(self) -> None:
        self.call("rm_reset")

    # ------------------------------------------------------------------ state
    def save(self) -> bytes:
        """The complete unit as the library's versioned binary record."""
        size = ctypes.c_size_t()
        self.call("rm_save", None, 0, ctypes.byref(size))
        buf = ctypes.create_string_buffer(size.value)
        self.call("rm_save", buf, size.value, ctypes.byref(size))
        return buf.raw[:size.value]

    def restore(self, record: bytes) -> None:
        """The unit as ``save`` left it (checked whole; a refused record changes nothing)."""
        self.call("rm_restore", bytes(record), len(record))

    def describe(self) -> dict[str, float]:
        """Derived quantities of the parameters (geometry, contact law, masses; SI)."""
        n = 64
        names = (ctypes.c_char_p * n)()
        values = (ctypes.c_double * n)()
        count = ctypes.c_size_t()
        self.call("rm_describe", names, values, n, ctypes.byref(count))
        return {names[k].decode(): values[k] for k in range(min(count.value, n))}


def _uints(values) -> ctypes.Array:
    values = list(values)
    return (ctypes.c_uint * len(values))(*values)


def _unit_name(kind: int) -> str:
    return {MESH: "GearMeshRattle", DRIVELINE: "Driveline"}.get(kind, f"kind {kind}")


class MeshUnit(Unit):
    """The GearMeshRattle unit: the wheel started for the pinion at (``phi_p`` [rad], ``w_p``
    [rad/s]) under ``tau_load`` [N.m], then stepped with the pinion's Taylor inputs."""

    def __init__(self, parameters=None, phi_p: float = 0.0, w_p: float = 0.0,
                 tau_load: float = 0.0, a_p: float = 0.0, **options):
        super().__init__(MESH, parameters, {"pinion.phi": phi_p, "pinion.w": w_p,
                                            "pinion.a": a_p, "wheel.tau_load": tau_load},
                         **options)

    def step(self, h: float, phi_p: float, w_p: float, a_p: float = 0.0,
             tau_load: float = 0.0) -> StepReport:
        """Advance the wheel by ``h`` [s] under the pinion kinematics at the step start and
        the held load torque; the step's events."""
        self.advance(h, {"pinion.phi": phi_p, "pinion.w": w_p, "pinion.a": a_p,
                         "wheel.tau_load": tau_load})
        return self.report()

    def wheel(self) -> tuple[float, float]:
        """The wheel's angle [rad] and speed [rad/s] now."""
        v = self.get(("wheel.phi", "wheel.w"))
        return v["wheel.phi"], v["wheel.w"]


class DrivelineUnit(Unit):
    """The Driveline unit: its output shaft started in steady state behind the wheel at
    (``phi_w`` [rad], ``w_w`` [rad/s]) at ``start_time``."""

    def __init__(self, parameters=None, phi_w: float = 0.0, w_w: float = 0.0, **options):
        super().__init__(DRIVELINE, parameters, {"wheel.phi": phi_w, "wheel.w": w_w}, **options)

    def step(self, h: float, phi_w: float, w_w: float, at: float | None = None) -> None:
        """Advance by ``h`` [s] with the wheel's angle and speed at the step start (from the
        communication point ``at`` [s], default the current time)."""
        self.advance(h, {"wheel.phi": phi_w, "wheel.w": w_w}, at=at)


def check_parameters(kind: int, public_values: Mapping[str, Any]) -> None:
    """ModelError with the library's message unless the parameter values are valid for a
    unit of ``kind``: ranges, choices, and the combination checks (geometry, contact law)."""
    with Unit(kind, public_values, initialize=False) as unit:
        unit.call("rm_check_parameters")


def describe(kind: int, public_values: Mapping[str, Any]) -> dict[str, float]:
    """The derived quantities of the parameter values (``Unit.describe``)."""
    with Unit(kind, public_values, initialize=False) as unit:
        return unit.describe()


def input_starts(kind: int) -> dict[str, float]:
    """The inputs' start values of a unit kind: what its partner outputs at t = 0 in the
    default system (the FMUs' start values)."""
    with Unit(kind, initialize=False) as unit:
        names = [n for n, v in unit.variables.items() if v.causality == "input"]
        return unit.get(names)


def coupled_start_inputs(mesh_parameters=None, driveline_parameters=None,
                         start_time: float = 0.0) -> tuple[dict[str, float], dict[str, float]]:
    """``(mesh inputs, driveline inputs)`` at ``start_time`` [s] of the coupled system: what
    each unit's partner outputs there once both are initialized, the exchange run to its fixed
    point (``rm_coupled_start``).  A unit initialized with its inputs at these values outputs
    exactly its partner's values, so masters that exchange nothing during initialization start
    the pair consistent."""
    with Unit(MESH, mesh_parameters, initialize=False) as mesh, \
            Unit(DRIVELINE, driveline_parameters, initialize=False) as drive:
        m_in = (ctypes.c_double * 4)()
        d_in = (ctypes.c_double * 2)()
        status = mesh._lib.rm_coupled_start(mesh._ptr, drive._ptr, float(start_time), m_in, d_in)
        if status != library.OK:
            raise ModelError(library.message(mesh._lib, mesh._ptr))
        m_names = [n for n, v in mesh.variables.items() if v.causality == "input"]
        d_names = [n for n, v in drive.variables.items() if v.causality == "input"]
        return dict(zip(m_names, m_in, strict=True)), dict(zip(d_names, d_in, strict=True))


class CoupledRun:
    """A coupled run of :func:`run_coupled`: the communication points [s], one column per
    recorded variable (``"<Unit>.<name>"``, Integer outputs as float) and the mesh's contact
    onsets (time [s], normal approach speed [m/s], flank).

    The library writes every column contiguously into one buffer; ``columns`` and ``time``
    become Python lists on first use, and :meth:`column_buffer` hands a column over without
    a copy (``numpy.asarray(run.column_buffer(name))``) for studies of long runs."""

    def __init__(self, start_ns: int, step_ns: int, steps: int, names: list[str], buffer,
                 onsets: list[float]):
        self._start_ns, self._step_ns, self.steps = start_ns, step_ns, steps
        self._index = {name: i for i, name in enumerate(names)}
        self._values = memoryview(buffer).cast("B").cast("d")
        self._columns: dict[str, list[float]] | None = None
        self._time: list[float] | None = None
        self.onset_times = onsets[0::3]
        self.onset_speeds = onsets[1::3]
        self.onset_flanks = [int(f) for f in onsets[2::3]]

    def column_buffer(self, name: str) -> memoryview:
        """The column of ``name`` as a read-only buffer of doubles (no copy)."""
        i, n = self._index[name], self.steps + 1
        return self._values[i * n:(i + 1) * n].toreadonly()

    @property
    def columns(self) -> dict[str, list[float]]:
        if self._columns is None:
            self._columns = {name: self.column_buffer(name).tolist() for name in self._index}
        return self._columns

    @property
    def time(self) -> list[float]:
        """The communication points t_k = (t0_ns + k step_ns) / 1e9 [s] (made once)."""
        if self._time is None:
            self._time = [(self._start_ns + k * self._step_ns) / 1e9
                          for k in range(self.steps + 1)]
        return self._time


def run_coupled(mesh: Unit, driveline: Unit, step_ns: int, steps: int,
                record: Iterable[str] | None = None, onset_capacity: int | None = None
                ) -> CoupledRun:
    """Couple two initialized units for ``steps`` steps of ``step_ns`` nanoseconds from their
    current time, in one call of the library (``rm_run_coupled``): the co-simulation's
    numbers, bit for bit, at the cost of the model alone.  ``record`` names the variables
    recorded at every point, ``"<Unit>.<name>"`` (default: every output of both units);
    ``onset_capacity`` the most onsets kept (default: four per step)."""
    units = {_unit_name(MESH): mesh, _unit_name(DRIVELINE): driveline}
    if record is None:
        record = [f"{name}.{n}" for name, u in units.items()
                  for n, v in u.variables.items() if v.causality == "output"]
    record = list(record)
    vrs, kinds = [], []
    for qualified in record:
        unit_name, _, name = qualified.partition(".")
        unit = units.get(unit_name)
        if unit is None or name not in unit.variables:
            raise ModelError(f"cannot record {qualified!r}: expected '<Unit>.<variable>' of "
                             f"{', '.join(units)}")
        vrs.append(unit.variables[name].vr)
        kinds.append(unit.kind)
    start = mesh.time
    start_ns = round(start * 1e9)
    n = len(record)
    buffer = (ctypes.c_double * (n * (steps + 1)))()
    if onset_capacity is None:  # chatter can put several onsets into a step; rarely more
        onset_capacity = 4 * int(steps) + 1024
    onsets = (ctypes.c_double * (3 * onset_capacity))()
    count = ctypes.c_size_t()
    status = mesh._lib.rm_run_coupled(
        mesh._ptr, driveline._ptr, start_ns, int(step_ns), int(steps), _uints(vrs),
        (ctypes.c_int * n)(*kinds), n, buffer, onsets, onset_capacity, ctypes.byref(count))
    if status != library.OK:
        raise ModelError(library.message(mesh._lib, mesh._ptr))
    if count.value > onset_capacity:
        raise ModelError(f"{count.value} onsets, more than the {onset_capacity} kept: raise "
                         "onset_capacity")
    return CoupledRun(start_ns, int(step_ns), int(steps), record, buffer,
                      onsets[:3 * count.value])
