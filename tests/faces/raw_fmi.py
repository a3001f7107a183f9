"""A raw co-simulation host on ctypes, one driver for every face (the pythonfmu and native FMI
2.0 FMUs, the native FMI 3.0 FMUs), for driving them the way a sloppy or unusual importer
would: any bytes as strings, NULL pointers, wrong tokens and paths, any buffer sizes, states
reused, calls in any order.  fmpy's slaves check and convert too much for that.

What differs between the standards is the model's *dialect* (``FMI2``, ``FMI3``: chosen from
the modelDescription's fmiVersion): the function names, the C types of each variable type and
the type that gets and sets each of the model library's (``Model.kind``), the logger's
signature, instantiation's arguments and the interfaces these FMUs refuse, where the start
time is given and how the time reached is read, and where the binary lies.  ``Model`` and
``Instance`` are the same for both.

Every call returns the raw status; the messages the FMU logs are collected per instance
(``Instance.log``: (status, category, message)), routed by the instance environment pointer.
FMI 2.0's logger takes a printf format: the faces always log as ("%s", message), so a message
passed as the format itself (a printf format injection) is recorded with category "FORMAT".
FMI 3.0's logMessage has no format.
"""

from __future__ import annotations

import ctypes
import functools
import os
import zipfile
from ctypes import (
    CFUNCTYPE,
    POINTER,
    c_bool,
    c_char_p,
    c_double,
    c_int,
    c_int32,
    c_int64,
    c_size_t,
    c_uint,
    c_void_p,
)
from pathlib import Path
from typing import ClassVar
from urllib.parse import quote
from xml.etree import ElementTree

OK, WARNING, DISCARD, ERROR, FATAL, PENDING = range(6)  # fmi3Status stops at FATAL
CO_SIMULATION, MODEL_EXCHANGE = 1, 0  # fmi2Type
DO_STEP_STATUS, PENDING_STATUS, LAST_SUCCESSFUL_TIME, TERMINATED = range(4)  # fmi2StatusKind

LOGGER = CFUNCTYPE(None, c_void_p, c_char_p, c_int, c_char_p, c_char_p, c_char_p)
LOG = CFUNCTYPE(None, c_void_p, c_int, c_char_p, c_char_p)


class Callbacks(ctypes.Structure):
    """fmi2CallbackFunctions."""
    _fields_ = [("logger", LOGGER), ("allocateMemory", c_void_p), ("freeMemory", c_void_p),
                ("stepFinished", c_void_p), ("componentEnvironment", c_void_p)]


#: The FMI 3.0 value types (every one's get and set is exported by these FMUs).
VALUE_TYPES = ("Float32", "Float64", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32",
               "Int64", "UInt64", "Boolean", "String")


def _decode(b: bytes | None) -> str:
    return b.decode("utf-8", "replace") if b is not None else ""


class Dialect:
    """What one FMI standard names and passes differently; the functions common to both are
    named as FMI 3.0 spells them, without the prefix (``call``)."""

    standard: str
    prefix: str
    platform: str  # the folder of the x86-64 Linux binary
    token_attribute: str
    #: variable type -> (ctypes type, the name of its get/set functions' type)
    types: ClassVar[dict]
    #: FMI 3.0's spelling -> this standard's, where they differ
    spelling: ClassVar[dict] = {}
    #: the arguments every get/set takes after the values (FMI 3.0: nValues)
    counts_values: bool
    #: the model library's four types -> this standard's name of the type that gets and sets
    #: them (an Enumeration is FMI 3.0's own: ``library_type``)
    kinds: ClassVar[dict]
    #: the name of instantiation's resources argument, in the glue's refusals
    resources_argument: str
    #: FMI 3.0 lets an importer with no resources folder pass NULL; FMI 2.0 does not
    null_resources_accepted: bool
    #: what the glue's refusal of a debug-logging category that is not UTF-8 says
    bad_category: str
    #: the time reached, before the first step: refused (FMI 2.0's fmi2LastSuccessfulTime
    #: needs a step) or the start time (FMI 3.0's variable time)
    time_before_first_step_refused: bool
    #: a function (FMI 3.0's name without the prefix) every co-simulation FMU exports and
    #: these FMUs refuse, with the arguments of a call that asks for nothing
    not_provided: str
    derivative_arguments: ClassVar[tuple]

    def library_type(self, kind: str) -> str:
        """The model library's type ("Real", "Integer", "Boolean", "String") of a variable of
        this standard's type ``kind``."""
        return next(t for t, k in self.kinds.items() if k == kind) \
            if kind in self.kinds.values() else "Integer"  # an FMI 3.0 Enumeration

    def name(self, function: str) -> str:
        return self.prefix + self.spelling.get(function, function)

    def variable(self, sv) -> tuple[str, str | None]:
        """(variable type, start text) of a <ScalarVariable> or FMI 3.0 variable element."""
        raise NotImplementedError

    def resources(self, model: Model) -> bytes:
        raise NotImplementedError


def _common(comp) -> dict:
    """The signatures both standards share, by FMI 3.0's name without the prefix."""
    st = c_int
    return {
        "FreeInstance": (None, [comp]),
        "SetDebugLogging": (st, [comp, c_int, c_size_t, c_void_p]),
        "ExitInitializationMode": (st, [comp]),
        "Terminate": (st, [comp]),
        "Reset": (st, [comp]),
        "GetFMUState": (st, [comp, POINTER(c_void_p)]),
        "SetFMUState": (st, [comp, c_void_p]),
        "FreeFMUState": (st, [comp, POINTER(c_void_p)]),
        "SerializedFMUStateSize": (st, [comp, c_void_p, POINTER(c_size_t)]),
        "SerializeFMUState": (st, [comp, c_void_p, c_void_p, c_size_t]),
        "DeserializeFMUState": (st, [comp, c_void_p, c_size_t, POINTER(c_void_p)]),
    }


class Fmi2(Dialect):
    standard, prefix, platform, token_attribute = "2.0", "fmi2", "linux64", "guid"
    types: ClassVar[dict] = {"Real": (c_double, "Real"), "Integer": (c_int, "Integer"),
                             "Boolean": (c_int, "Boolean"), "String": (c_char_p, "String")}
    spelling: ClassVar[dict] = {"GetFMUState": "GetFMUstate", "SetFMUState": "SetFMUstate",
                                "FreeFMUState": "FreeFMUstate",
                                "SerializedFMUStateSize": "SerializedFMUstateSize",
                                "SerializeFMUState": "SerializeFMUstate",
                                "DeserializeFMUState": "DeSerializeFMUstate"}
    counts_values = False
    kinds: ClassVar[dict] = {"Real": "Real", "Integer": "Integer", "Boolean": "Boolean",
                             "String": "String"}
    resources_argument = "fmuResourceLocation"
    null_resources_accepted = False
    bad_category = "not valid UTF-8"
    time_before_first_step_refused = True
    not_provided = "CancelStep"  # no asynchronous steps
    derivative_arguments = (None, 0, None, 0, None, None)

    def signatures(self) -> dict:
        comp, vrs, st = c_void_p, POINTER(c_uint), c_int
        sig = _common(comp)
        sig.update({
            "Instantiate": (c_void_p, [c_char_p, c_int, c_char_p, c_char_p, POINTER(Callbacks),
                                       c_int, c_int]),
            "SetupExperiment": (st, [comp, c_int, c_double, c_double, c_int, c_double]),
            "EnterInitializationMode": (st, [comp]),
            "DoStep": (st, [comp, c_double, c_double, c_int]),
            "CancelStep": (st, [comp]),
            "GetStatus": (st, [comp, c_int, POINTER(c_int)]),
            "GetRealStatus": (st, [comp, c_int, POINTER(c_double)]),
            "GetIntegerStatus": (st, [comp, c_int, POINTER(c_int)]),
            "GetBooleanStatus": (st, [comp, c_int, POINTER(c_int)]),
            "GetStringStatus": (st, [comp, c_int, POINTER(c_char_p)]),
            "GetDirectionalDerivative": (st, [comp, vrs, c_size_t, vrs, c_size_t,
                                              POINTER(c_double), POINTER(c_double)]),
        })
        for kind, (ctype, _) in self.types.items():
            sig[f"Get{kind}"] = (st, [comp, vrs, c_size_t, POINTER(ctype)])
            sig[f"Set{kind}"] = (st, [comp, vrs, c_size_t, POINTER(ctype)])
        return sig

    def variable(self, sv):
        child = next(iter(sv))
        # an Enumeration is an Integer to the C API (fmi2Get/SetInteger)
        return ("Integer" if child.tag == "Enumeration" else child.tag), child.get("start")

    def resources(self, model):
        return model.resources_uri()

    def logger(self, model):
        return LOGGER(model._log2)

    def instantiate(self, model, env, name, token, resources, logging_on, *, kind=CO_SIMULATION,
                    log=True):
        callbacks = Callbacks(model._logger if log else LOGGER(), None, None, None, env)
        c = model.lib.fmi2Instantiate(name, kind, token, resources, ctypes.byref(callbacks), 0,
                                      int(logging_on))
        return c, callbacks

    def instantiate_other(self, model, interface, name):
        kind = {"model exchange": MODEL_EXCHANGE, "other": 7}[interface]
        callbacks = Callbacks(model._logger, None, None, None, 0)
        return model.lib.fmi2Instantiate(name, kind, model.token.encode(),
                                         model.resources_uri(), ctypes.byref(callbacks), 0, 0)

    def enter(self, inst, start, stop):
        assert start is None and stop is None, "FMI 2.0 takes the start time in setup()"
        return inst.L.fmi2EnterInitializationMode(inst.c)

    def begin(self, inst, start):
        status = inst.setup(start)
        return status if status != OK else inst.enter()

    def step_flags(self, inst, t, h, no_prior):
        return inst.L.fmi2DoStep(inst.c, t, h, no_prior), None

    def time(self, inst):
        v = c_double(float("nan"))
        return inst.L.fmi2GetRealStatus(inst.c, LAST_SUCCESSFUL_TIME, ctypes.byref(v)), v.value


class Fmi3(Dialect):
    standard, prefix, platform, token_attribute = "3.0", "fmi3", "x86_64-linux", \
        "instantiationToken"
    types: ClassVar[dict] = {"Float64": (c_double, "Float64"), "Int32": (c_int32, "Int32"),
                             "Enumeration": (c_int64, "Int64"), "Boolean": (c_bool, "Boolean"),
                             "String": (c_char_p, "String")}
    counts_values = True
    kinds: ClassVar[dict] = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean",
                             "String": "String"}
    resources_argument = "resourcePath"
    null_resources_accepted = True
    # its categories are a fixed list of ASCII names: a byte string that is not UTF-8 is none
    bad_category = "is not one of this FMU's"
    time_before_first_step_refused = False
    not_provided = "EnterEventMode"  # hasEventMode = false
    derivative_arguments = (None, 0, None, 0, None, 0, None, 0)

    def signatures(self) -> dict:
        inst, vrs, st = c_void_p, POINTER(c_uint), c_int
        sig = _common(inst)
        sig.update({
            "GetVersion": (c_char_p, []),
            "InstantiateCoSimulation": (c_void_p, [
                c_char_p, c_char_p, c_char_p, c_bool, c_bool, c_bool, c_bool, vrs, c_size_t,
                c_void_p, LOG, c_void_p]),
            "InstantiateModelExchange": (c_void_p, [c_char_p, c_char_p, c_char_p, c_bool,
                                                    c_bool, c_void_p, LOG]),
            "SetDebugLogging": (st, [inst, c_bool, c_size_t, c_void_p]),
            "EnterInitializationMode": (st, [inst, c_bool, c_double, c_double, c_bool,
                                             c_double]),
            "EnterEventMode": (st, [inst]),
            "EnterStepMode": (st, [inst]),
            "DoStep": (st, [inst, c_double, c_double, c_bool, POINTER(c_bool),
                            POINTER(c_bool), POINTER(c_bool), POINTER(c_double)]),
            "GetDirectionalDerivative": (st, [inst, vrs, c_size_t, vrs, c_size_t, c_void_p,
                                              c_size_t, c_void_p, c_size_t]),
            "UpdateDiscreteStates": (st, [inst, *[c_void_p] * 6]),
            "GetClock": (st, [inst, vrs, c_size_t, c_void_p]),
            "SetTime": (st, [inst, c_double]),
        })
        for t in VALUE_TYPES:
            sig[f"Get{t}"] = (st, [inst, vrs, c_size_t, c_void_p, c_size_t])
            sig[f"Set{t}"] = (st, [inst, vrs, c_size_t, c_void_p, c_size_t])
        return sig

    def variable(self, v):
        start = v.find("Start")
        return v.tag, (start.get("value") if start is not None else v.get("start"))

    def resources(self, model):
        return model.resources_path()

    def logger(self, model):
        return LOG(model._log3)

    def instantiate(self, model, env, name, token, resources, logging_on, *, event_mode=False,
                    early_return=False, required=None, log=True):
        req = (c_uint * max(1, len(required or [])))(*(required or []))
        c = model.lib.fmi3InstantiateCoSimulation(
            name, token, resources, False, bool(logging_on), event_mode, early_return,
            req if required else None, len(required or []), env,
            model._logger if log else LOG(), None)
        return c, None

    def instantiate_other(self, model, interface, name):
        token, path = model.token.encode(), model.resources_path()
        if interface == "model exchange":
            return model.lib.fmi3InstantiateModelExchange(name, token, path, False, False, None,
                                                          model._logger)
        f = model.lib.fmi3InstantiateScheduledExecution
        f.restype = c_void_p
        return f(c_char_p(name), c_char_p(token), c_char_p(path), c_bool(False), c_bool(False),
                 None, model._logger, None, None, None)

    def enter(self, inst, start, stop):
        return inst.L.fmi3EnterInitializationMode(inst.c, False, 0.0, start or 0.0,
                                                  stop is not None, stop or 0.0)

    def begin(self, inst, start):
        return self.enter(inst, start, None)

    def step_flags(self, inst, t, h, no_prior):
        event, terminate, early = c_bool(True), c_bool(True), c_bool(True)
        last = c_double(float("nan"))
        status = inst.L.fmi3DoStep(inst.c, t, h, bool(no_prior), ctypes.byref(event),
                                   ctypes.byref(terminate), ctypes.byref(early),
                                   ctypes.byref(last))
        return status, (event.value, terminate.value, early.value, last.value)

    def time(self, inst):
        st, (t,) = inst.get("Float64", [inst.m.vr("time")])
        return st, t


FMI2, FMI3 = Fmi2(), Fmi3()
DIALECTS = {d.standard: d for d in (FMI2, FMI3)}

#: Every model loaded in this process (free_all).
_MODELS: list = []


def free_all() -> None:
    """Free every instance still alive, of every model loaded (before a leak check: what the
    host did not free is the host's leak, not the FMU's)."""
    for model in _MODELS:
        for inst in list(model._instances.values()):
            if inst.c:
                inst.free()


class Model:
    """An unpacked FMU: its x86-64 Linux binary loaded with ctypes, its variables and token
    (FMI 2.0's GUID, FMI 3.0's instantiation token), driven in its standard's dialect."""

    def __init__(self, unpacked: Path):
        self.root = Path(unpacked)
        md = ElementTree.parse(self.root / "modelDescription.xml").getroot()
        self.dialect = d = DIALECTS[md.get("fmiVersion")]
        self.token = md.get(d.token_attribute)
        self.guid = self.token  # FMI 2.0's name for it
        self.identifier = md.find("CoSimulation").get("modelIdentifier")
        #: the C-only faces: no Python needed where they run
        self.native = d is FMI3 or \
            md.find("CoSimulation").get("needsExecutionTool") == "false"
        self.variables = {}  # name -> (vr, variable type, causality)
        self.starts = {}  # start values, as the setters take them
        for sv in md.find("ModelVariables"):
            kind, start = d.variable(sv)
            self.variables[sv.get("name")] = (int(sv.get("valueReference")), kind,
                                              sv.get("causality"))
            if start is not None and sv.get("causality") != "independent":
                self.starts[sv.get("name")] = {
                    "Real": float, "Integer": int, "Boolean": lambda x: int(x == "true"),
                    "String": str.encode}[d.library_type(kind)](start)
        self.lib = ctypes.CDLL(str(self.root / "binaries" / d.platform / f"{self.identifier}.so"))
        for name, (restype, argtypes) in d.signatures().items():
            f = getattr(self.lib, d.name(name))
            f.restype, f.argtypes = restype, argtypes
        # Messages of the instance being created, then routed by the environment pointer.
        self.pending_log: list = []
        self._instances: dict[int, Instance] = {}
        self._logger = d.logger(self)
        self._env_counter = 0
        _MODELS.append(self)

    def _route(self, env, entry) -> None:
        target = self._instances.get(env or 0)
        (target.log if target is not None else self.pending_log).append(entry)

    def _log2(self, env, instance, status, category, fmt, arg) -> None:
        self._route(env, (status, _decode(category), _decode(arg)) if fmt == b"%s"
                    else (status, "FORMAT", _decode(fmt)))

    def _log3(self, env, status, category, message) -> None:
        self._route(env, (status, _decode(category), _decode(message)))

    def call(self, function: str):
        """The C function of this dialect for FMI 3.0's ``function`` (without the prefix)."""
        return getattr(self.lib, self.dialect.name(function))

    def vr(self, name: str) -> int:
        return self.variables[name][0]

    @functools.cached_property
    def unit_variables(self) -> dict:
        """The unit's variables as the model library types them: name -> (vr, "Real" |
        "Integer" | "Boolean" | "String", causality), without FMI 3.0's independent variable
        (the glue's, not the library's; ``records.Record`` and the shadow read these)."""
        return {n: (vr, self.dialect.library_type(k), c)
                for n, (vr, k, c) in self.variables.items() if c != "independent"}

    def kind(self, library_type: str) -> str:
        """This standard's name of the type that gets and sets the library's ``library_type``
        ("Real" -> "Float64" in FMI 3.0)."""
        return self.dialect.kinds[library_type]

    def instantiate_other(self, interface: str, name: bytes = b"inst"):
        """Instantiation as ``interface`` ("model exchange"; "other": FMI 2.0's fmi2Type 7,
        FMI 3.0's Scheduled Execution), which these co-simulation FMUs refuse: the returned
        pointer (NULL expected), the messages in ``pending_log``."""
        self.pending_log = []
        return self.dialect.instantiate_other(self, interface, name)

    def names(self, kind: str | None = None, causality: str | None = None) -> list[str]:
        return [n for n, (_, k, c) in self.variables.items()
                if (kind is None or k == kind) and (causality is None or c == causality)]

    def resources_uri(self) -> bytes:
        """The resources folder as FMI 2.0 gives it: a file URI."""
        return ("file://" + quote(os.fsencode(self.root / "resources"))).encode()

    def resources_path(self) -> bytes:
        """The resources folder as FMI 3.0 gives it: a path with its trailing separator."""
        return os.fsencode(self.root / "resources") + b"/"

    def instantiate(self, name: bytes | None = b"inst", token: bytes | None = None,
                    resources: bytes | None = None, logging_on: bool = False,
                    default_resources: bool = True, *, guid: bytes | None = None,
                    location: bytes | None = None, path: bytes | None = None,
                    default_location: bool = True, default_path: bool = True,
                    **extras) -> Instance | None:
        """A new instance (None if instantiation returned NULL: its messages are then in
        ``pending_log``).  ``resources`` defaults to the unpacked folder's, in the dialect's
        form (``default_resources=False``: NULL); ``guid``/``location``/``path`` are the
        standards' names of ``token`` and ``resources``; ``extras`` are the dialect's own
        (FMI 2.0: kind; FMI 3.0: event_mode, early_return, required; both: log=False for no
        logger)."""
        token = token if token is not None else guid
        resources = next((r for r in (resources, location, path) if r is not None), None)
        default = default_resources and default_location and default_path
        self._env_counter += 1
        env = self._env_counter
        self.pending_log = []
        if resources is None and default:
            resources = self.dialect.resources(self)
        c, keep = self.dialect.instantiate(
            self, env, name, self.token.encode() if token is None else token, resources,
            logging_on, **extras)
        if not c:
            return None
        inst = Instance(self, c, keep)
        inst.log.extend(self.pending_log)
        self._instances[env] = inst
        return inst


def _array(ctype, values):
    return (ctype * max(1, len(values)))(*values)


class Instance:
    """One FMU instance: thin wrappers that return the raw status."""

    def __init__(self, model: Model, c, callbacks=None):
        self.m, self.c, self.callbacks = model, c, callbacks
        self.d, self.L = model.dialect, model.lib
        self.log: list = []

    def call(self, function: str, *args):
        """``function`` (FMI 3.0's name without the prefix) on this instance."""
        return self.m.call(function)(self.c, *args)

    # -- life cycle
    def setup(self, start=0.0, tol=None, stop=None) -> int:
        """fmi2SetupExperiment (FMI 2.0 only)."""
        return self.L.fmi2SetupExperiment(self.c, tol is not None, tol or 0.0, start,
                                          stop is not None, stop or 0.0)

    def enter(self, start: float | None = None, stop: float | None = None) -> int:
        """Enter initialization mode (FMI 3.0 with its start time; FMI 2.0 after setup)."""
        return self.d.enter(self, start, stop)

    def begin(self, start: float = 0.0) -> int:
        """Into initialization mode at ``start``, as the standard does it (FMI 2.0: setup,
        enter)."""
        return self.d.begin(self, start)

    def exit(self) -> int:
        return self.call("ExitInitializationMode")

    def terminate(self) -> int:
        return self.call("Terminate")

    def reset(self) -> int:
        return self.call("Reset")

    def free(self) -> None:
        self.call("FreeInstance")
        self.c = None

    def step(self, t: float, h: float, no_prior: int = 1) -> int:
        return self.d.step_flags(self, t, h, no_prior)[0]

    def step_flags(self, t: float, h: float) -> tuple[int, tuple | None]:
        """The step's status and (FMI 3.0) its outputs (eventHandlingNeeded,
        terminateSimulation, earlyReturn, lastSuccessfulTime)."""
        return self.d.step_flags(self, t, h, 1)

    def time(self) -> tuple[int, float]:
        """The time reached (FMI 2.0: fmi2LastSuccessfulTime; FMI 3.0: the variable time)."""
        return self.d.time(self)

    def logging(self, on, categories) -> int:
        if categories is None:
            return self.call("SetDebugLogging", on, 0, None)
        arr = (c_char_p * max(1, len(categories)))(*categories)
        return self.call("SetDebugLogging", on, len(categories), arr)

    # -- values
    def set(self, kind: str, vrs, values, n_values: int | None = None) -> int:
        ctype, fn = self.d.types[kind]
        values = [v.encode() if isinstance(v, str) else v for v in values]
        counts = (len(vrs) if n_values is None else n_values,) if self.d.counts_values else ()
        return self.call(f"Set{fn}", _array(c_uint, vrs), len(vrs), _array(ctype, values),
                         *counts)

    def get(self, kind: str, vrs) -> tuple[int, list]:
        ctype, fn = self.d.types[kind]
        out = (ctype * max(1, len(vrs)))()
        counts = (len(vrs),) if self.d.counts_values else ()
        st = self.call(f"Get{fn}", _array(c_uint, vrs), len(vrs), out, *counts)
        values = list(out)[:len(vrs)]
        if kind == "String":
            values = [_decode(v) for v in values]
        return st, values

    def set_named(self, values: dict) -> int:
        worst = OK
        for name, value in values.items():
            vr, kind, _ = self.m.variables[name]
            worst = max(worst, self.set(kind, [vr], [value]))
        return worst

    def get_named(self, name: str):
        vr, kind, _ = self.m.variables[name]
        st, values = self.get(kind, [vr])
        assert st == OK, (name, st, self.log[-3:])
        return values[0]

    def snapshot(self) -> dict:
        """Every variable of the modelDescription, by type (the observable values)."""
        out = {}
        for kind in self.d.types:
            names = self.m.names(kind)
            st, values = self.get(kind, [self.m.vr(n) for n in names])
            out[kind] = (st, [v.hex() if isinstance(v, float) else v for v in values])
        return out

    # -- FMU state
    def get_state(self, into: c_void_p | None = None) -> tuple[int, c_void_p]:
        state = into if into is not None else c_void_p()
        return self.call("GetFMUState", ctypes.byref(state)), state

    def set_state(self, state) -> int:
        return self.call("SetFMUState", state)

    def free_state(self, state: c_void_p) -> int:
        return self.call("FreeFMUState", ctypes.byref(state))

    def state_size(self, state) -> tuple[int, int]:
        n = c_size_t(0)
        st = self.call("SerializedFMUStateSize", state, ctypes.byref(n))
        return st, n.value

    def serialize(self, state, extra: int = 0, fill: int = 0xA5) -> tuple[int, bytes]:
        """Serialize into a buffer ``extra`` bytes larger than the reported size (negative:
        smaller), pre-filled with ``fill``; returns the status and the whole buffer."""
        st, n = self.state_size(state)
        if st != OK:
            return st, b""
        size = max(0, n + extra)
        buf = ctypes.create_string_buffer(bytes([fill]) * size, size)
        st = self.call("SerializeFMUState", state, buf, size)
        return st, buf.raw

    def deserialize(self, data: bytes, into: c_void_p | None = None) -> tuple[int, c_void_p]:
        state = into if into is not None else c_void_p()
        buf = ctypes.create_string_buffer(data, max(1, len(data)))
        return self.call("DeserializeFMUState", buf, len(data), ctypes.byref(state)), state

    def serialized(self) -> bytes:
        """The current state, serialized (exact buffer)."""
        st, state = self.get_state()
        assert st == OK, self.log[-3:]
        st, data = self.serialize(state)
        assert st == OK, self.log[-3:]
        self.free_state(state)
        return data

    # -- status (FMI 2.0)
    def real_status(self, kind: int) -> tuple[int, float]:
        v = c_double(float("nan"))
        return self.L.fmi2GetRealStatus(self.c, kind, ctypes.byref(v)), v.value

    def messages(self, since: int = 0, status: int | None = None) -> list[str]:
        return [m for s, _, m in self.log[since:] if status is None or s == status]


# ------------------------------------------------------------------ serialized states
#: The envelope's header: magic, version, payload size, checksum, the token (both standards).
HEADER = 96


def fnv1a64(data: bytes) -> int:
    """FNV-1a, 64 bits (the checksum of the faces' state envelope), written independently."""
    h = 0xCBF29CE484222325
    for b in data:
        h = ((h ^ b) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return h


def state_payload(blob: bytes) -> bytes:
    """The unit's record (the model library's ``rm_save``; ``records.Record``) inside a
    serialized state."""
    n = int.from_bytes(blob[16:24], "little")
    return blob[HEADER:HEADER + n]


def with_payload(blob: bytes, payload, fix_checksum: bool = True) -> bytes:
    """``blob`` with its payload replaced (bytes, or a ``records.Record``), and by default a
    matching checksum: re-sealed, so that the content reaches the library's checks."""
    data = payload if isinstance(payload, bytes) else payload.encode()
    checksum = fnv1a64(data) if fix_checksum else int.from_bytes(blob[24:32], "little")
    return (blob[:16] + len(data).to_bytes(8, "little") + checksum.to_bytes(8, "little")
            + blob[32:HEADER] + data)


def unpack(fmu: Path, folder: Path | bytes) -> Path:
    """Extract ``fmu`` into ``folder`` (a bytes path may hold any bytes); returns the folder.
    The binaries are made executable where the archive gives them no mode."""
    os.makedirs(folder, exist_ok=True)
    with zipfile.ZipFile(fmu) as z:
        for info in z.infolist():
            target = os.path.join(folder, info.filename.encode()) if isinstance(folder, bytes) \
                else os.path.join(folder, info.filename)
            if info.is_dir():
                os.makedirs(target, exist_ok=True)
                continue
            os.makedirs(os.path.dirname(target), exist_ok=True)
            with open(target, "wb") as f:
                f.write(z.read(info))
            mode = (info.external_attr >> 16) & 0o777
            if mode or info.filename.startswith("binaries/"):
                os.chmod(target, mode or 0o755)
    return Path(os.fsdecode(folder))
