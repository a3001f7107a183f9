"""A raw FMI 3.0 co-simulation host on ctypes, for driving the built FMI 3.0 FMUs call by call
the way a careless or unusual importer would: any bytes as strings, NULL pointers, wrong
tokens and paths, calls in any order.  fmpy's FMU3Slave checks and converts too much for that.

Every call returns the raw fmi3Status; the messages the FMU logs (FMI 3.0's logMessage has no
format string) are collected per instance (``Instance.log``: (status, category, message)),
routed by the instance environment pointer.
"""

from __future__ import annotations

import ctypes
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
    c_uint8,
    c_void_p,
)
from pathlib import Path
from xml.etree import ElementTree

OK, WARNING, DISCARD, ERROR, FATAL = range(5)

LOG = CFUNCTYPE(None, c_void_p, c_int, c_char_p, c_char_p)
#: FMI 3.0 element -> (ctypes type, name of the get/set functions' type)
CTYPES = {"Float64": (c_double, "Float64"), "Int32": (c_int32, "Int32"),
          "Enumeration": (c_int64, "Int64"), "Boolean": (c_bool, "Boolean"),
          "String": (c_char_p, "String")}
#: The functions of the FMI 3.0 headers (every one is exported by these FMUs).
VALUE_TYPES = ("Float32", "Float64", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32",
               "Int64", "UInt64", "Boolean", "String")


def _decode(b: bytes | None) -> str:
    return b.decode("utf-8", "replace") if b is not None else ""


def unpack(fmu: Path, folder: Path) -> Path:
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    for so in Path(folder).glob("binaries/*/*"):
        so.chmod(0o755)
    return Path(folder)


class Model:
    """An unpacked FMI 3.0 FMU: its x86_64-linux binary loaded with ctypes, its variables and
    instantiation token."""

    def __init__(self, unpacked: Path):
        self.root = Path(unpacked)
        md = ElementTree.parse(self.root / "modelDescription.xml").getroot()
        self.token = md.get("instantiationToken")
        self.identifier = md.find("CoSimulation").get("modelIdentifier")
        self.variables = {}  # name -> (vr, FMI 3.0 element, causality)
        self.starts = {}
        for v in md.find("ModelVariables"):
            self.variables[v.get("name")] = (int(v.get("valueReference")), v.tag,
                                             v.get("causality"))
        self.lib = ctypes.CDLL(str(self.root / "binaries" / "x86_64-linux"
                                   / f"{self.identifier}.so"))
        self._declare()
        self.pending_log: list = []
        self._instances: dict[int, Instance] = {}
        self._logger = LOG(self._log)
        self._env_counter = 0

    def _declare(self) -> None:
        L = self.lib
        inst, vrs, st = c_void_p, POINTER(c_uint), c_int
        sig = {
            "fmi3GetVersion": (c_char_p, []),
            "fmi3InstantiateCoSimulation": (c_void_p, [
                c_char_p, c_char_p, c_char_p, c_bool, c_bool, c_bool, c_bool, vrs, c_size_t,
                c_void_p, LOG, c_void_p]),
            "fmi3InstantiateModelExchange": (c_void_p, [c_char_p, c_char_p, c_char_p, c_bool,
                                                        c_bool, c_void_p, LOG]),
            "fmi3FreeInstance": (None, [inst]),
            "fmi3SetDebugLogging": (st, [inst, c_bool, c_size_t, c_void_p]),
            "fmi3EnterInitializationMode": (st, [inst, c_bool, c_double, c_double, c_bool,
                                                 c_double]),
            "fmi3ExitInitializationMode": (st, [inst]),
            "fmi3EnterEventMode": (st, [inst]),
            "fmi3EnterStepMode": (st, [inst]),
            "fmi3Terminate": (st, [inst]),
            "fmi3Reset": (st, [inst]),
            "fmi3DoStep": (st, [inst, c_double, c_double, c_bool, POINTER(c_bool),
                                POINTER(c_bool), POINTER(c_bool), POINTER(c_double)]),
            "fmi3GetFMUState": (st, [inst, POINTER(c_void_p)]),
            "fmi3SetFMUState": (st, [inst, c_void_p]),
            "fmi3FreeFMUState": (st, [inst, POINTER(c_void_p)]),
            "fmi3SerializedFMUStateSize": (st, [inst, c_void_p, POINTER(c_size_t)]),
            "fmi3SerializeFMUState": (st, [inst, c_void_p, POINTER(c_uint8), c_size_t]),
            "fmi3DeserializeFMUState": (st, [inst, POINTER(c_uint8), c_size_t,
                                             POINTER(c_void_p)]),
            "fmi3GetDirectionalDerivative": (st, [inst, vrs, c_size_t, vrs, c_size_t,
                                                  c_void_p, c_size_t, c_void_p, c_size_t]),
            "fmi3UpdateDiscreteStates": (st, [inst, *[c_void_p] * 6]),
            "fmi3GetClock": (st, [inst, vrs, c_size_t, c_void_p]),
            "fmi3SetTime": (st, [inst, c_double]),
        }
        for t in VALUE_TYPES:
            sig[f"fmi3Get{t}"] = (st, [inst, vrs, c_size_t, c_void_p, c_size_t])
            sig[f"fmi3Set{t}"] = (st, [inst, vrs, c_size_t, c_void_p, c_size_t])
        for name, (restype, argtypes) in sig.items():
            f = getattr(L, name)
            f.restype, f.argtypes = restype, argtypes

    def _log(self, env, status, category, message) -> None:
        entry = (status, _decode(category), _decode(message))
        target = self._instances.get(env or 0)
        (target.log if target is not None else self.pending_log).append(entry)

    def vr(self, name: str) -> int:
        return self.variables[name][0]

    def names(self, kind: str | None = None, causality: str | None = None) -> list[str]:
        return [n for n, (_, k, c) in self.variables.items()
                if (kind is None or k == kind) and (causality is None or c == causality)]

    def resources_path(self) -> bytes:
        return str(self.root / "resources").encode() + b"/"

    def instantiate(self, name: bytes | None = b"inst", token: bytes | None = None,
                    path: bytes | None = None, logging_on: bool = False,
                    event_mode: bool = False, early_return: bool = False,
                    required: list[int] | None = None, default_path: bool = True,
                    log: bool = True) -> Instance | None:
        """A new instance (None if fmi3InstantiateCoSimulation returned NULL: its messages
        are then in ``pending_log``)."""
        self._env_counter += 1
        env = self._env_counter
        self.pending_log = []
        if path is None and default_path:
            path = self.resources_path()
        req = (c_uint * max(1, len(required or [])))(*(required or []))
        c = self.lib.fmi3InstantiateCoSimulation(
            name, self.token.encode() if token is None else token, path, False, logging_on,
            event_mode, early_return, req if required else None, len(required or []), env,
            self._logger if log else LOG(), None)
        if not c:
            return None
        inst = Instance(self, c)
        inst.log.extend(self.pending_log)
        self._instances[env] = inst
        return inst


def _array(ctype, values):
    return (ctype * max(1, len(values)))(*values)


class Instance:
    """One FMU instance: thin wrappers that return the raw status."""

    def __init__(self, model: Model, c):
        self.m, self.c, self.L = model, c, model.lib
        self.log: list = []

    # -- life cycle
    def enter(self, start: float = 0.0, stop: float | None = None) -> int:
        return self.L.fmi3EnterInitializationMode(self.c, False, 0.0, start, stop is not None,
                                                  stop or 0.0)

    def exit(self) -> int:
        return self.L.fmi3ExitInitializationMode(self.c)

    def terminate(self) -> int:
        return self.L.fmi3Terminate(self.c)

    def reset(self) -> int:
        return self.L.fmi3Reset(self.c)

    def free(self) -> None:
        self.L.fmi3FreeInstance(self.c)
        self.c = None

    def step(self, t: float, h: float) -> int:
        return self.step_flags(t, h)[0]

    def step_flags(self, t: float, h: float) -> tuple[int, tuple]:
        """fmi3DoStep: (status, (eventHandlingNeeded, terminateSimulation, earlyReturn,
        lastSuccessfulTime))."""
        event, terminate, early = c_bool(True), c_bool(True), c_bool(True)
        last = c_double(float("nan"))
        status = self.L.fmi3DoStep(self.c, t, h, True, ctypes.byref(event),
                                   ctypes.byref(terminate), ctypes.byref(early),
                                   ctypes.byref(last))
        return status, (event.value, terminate.value, early.value, last.value)

    def logging(self, on: bool, categories) -> int:
        if categories is None:
            return self.L.fmi3SetDebugLogging(self.c, on, 0, None)
        arr = (c_char_p * max(1, len(categories)))(*categories)
        return self.L.fmi3SetDebugLogging(self.c, on, len(categories), arr)

    # -- values
    def set(self, kind: str, vrs, values, n_values: int | None = None) -> int:
        ctype, fn = CTYPES[kind]
        values = [v.encode() if isinstance(v, str) else v for v in values]
        return getattr(self.L, f"fmi3Set{fn}")(self.c, _array(c_uint, vrs), len(vrs),
                                                _array(ctype, values),
                                                len(vrs) if n_values is None else n_values)

    def get(self, kind: str, vrs) -> tuple[int, list]:
        ctype, fn = CTYPES[kind]
        out = (ctype * max(1, len(vrs)))()
        st = getattr(self.L, f"fmi3Get{fn}")(self.c, _array(c_uint, vrs), len(vrs), out,
                                              len(vrs))
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
        """Every variable, by FMI 3.0 type (the observable values)."""
        out = {}
        for kind in CTYPES:
            names = self.m.names(kind)
            st, values = self.get(kind, [self.m.vr(n) for n in names])
            out[kind] = (st, [v.hex() if isinstance(v, float) else v for v in values])
        return out

    # -- FMU state
    def get_state(self, into: c_void_p | None = None) -> tuple[int, c_void_p]:
        state = into if into is not None else c_void_p()
        return self.L.fmi3GetFMUState(self.c, ctypes.byref(state)), state

    def set_state(self, state) -> int:
        return self.L.fmi3SetFMUState(self.c, state)

    def free_state(self, state: c_void_p) -> int:
        return self.L.fmi3FreeFMUState(self.c, ctypes.byref(state))

    def state_size(self, state) -> tuple[int, int]:
        n = c_size_t(0)
        return self.L.fmi3SerializedFMUStateSize(self.c, state, ctypes.byref(n)), n.value

    def serialize(self, state, extra: int = 0) -> tuple[int, bytes]:
        st, n = self.state_size(state)
        if st != OK:
            return st, b""
        size = max(0, n + extra)
        buf = (c_uint8 * max(1, size))(*([0xA5] * size))
        st = self.L.fmi3SerializeFMUState(self.c, state, buf, size)
        return st, bytes(buf)[:size]

    def deserialize(self, data: bytes, into: c_void_p | None = None) -> tuple[int, c_void_p]:
        state = into if into is not None else c_void_p()
        buf = (c_uint8 * max(1, len(data))).from_buffer_copy(data or b"\0")
        return self.L.fmi3DeserializeFMUState(self.c, buf, len(data),
                                              ctypes.byref(state)), state

    def serialized(self) -> bytes:
        st, state = self.get_state()
        assert st == OK, self.log[-3:]
        st, data = self.serialize(state)
        assert st == OK, self.log[-3:]
        self.free_state(state)
        return data
