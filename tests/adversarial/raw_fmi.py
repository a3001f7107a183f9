"""A raw FMI 2.0 co-simulation host on ctypes, for driving the built FMUs the way a sloppy or
unusual master would: any bytes as strings, any buffer sizes, states reused, calls in any
order.  fmpy's FMU2Slave checks and converts too much for that.

Every call returns the raw fmi2Status; the messages the FMU logs are collected per instance
(``Instance.log``: (status, category, message)).  The shim always logs as ("%s", message), so
the logger callback takes the message as the argument after the format; a message passed as
the format itself (a printf format injection) is recorded with category "FORMAT".
"""

from __future__ import annotations

import ctypes
import os
import zipfile
from ctypes import (
    CFUNCTYPE,
    POINTER,
    c_char,
    c_char_p,
    c_double,
    c_int,
    c_size_t,
    c_uint,
    c_void_p,
)
from pathlib import Path
from urllib.parse import quote
from xml.etree import ElementTree

OK, WARNING, DISCARD, ERROR, FATAL, PENDING = range(6)
CO_SIMULATION, MODEL_EXCHANGE = 1, 0
DO_STEP_STATUS, PENDING_STATUS, LAST_SUCCESSFUL_TIME, TERMINATED = range(4)

LOGGER = CFUNCTYPE(None, c_void_p, c_char_p, c_int, c_char_p, c_char_p, c_char_p)


class Callbacks(ctypes.Structure):
    _fields_ = [("logger", LOGGER), ("allocateMemory", c_void_p), ("freeMemory", c_void_p),
                ("stepFinished", c_void_p), ("componentEnvironment", c_void_p)]


#: Every model loaded in this process (free_all).
_MODELS: list = []


def free_all() -> None:
    """Free every instance still alive, of every model loaded (before a leak check: what the
    host did not free is the host's leak, not the FMU's)."""
    for model in _MODELS:
        for inst in list(model._instances.values()):
            if inst.c:
                inst.free()


def _decode(b: bytes | None) -> str:
    return b.decode("utf-8", "replace") if b is not None else ""


class Model:
    """An unpacked FMU: its binary loaded with ctypes, its variables and GUID."""

    def __init__(self, unpacked: Path):
        self.root = Path(unpacked)
        md = ElementTree.parse(self.root / "modelDescription.xml").getroot()
        self.guid = md.get("guid")
        self.identifier = md.find("CoSimulation").get("modelIdentifier")
        #: the native (C only) flavour: no Python needed where it runs
        self.native = md.find("CoSimulation").get("needsExecutionTool") == "false"
        self.variables = {}
        self.starts = {}  # start values, as the setters take them
        for sv in md.find("ModelVariables"):
            child = next(iter(sv))
            # an Enumeration is an Integer to the C API (fmi2Get/SetInteger)
            kind = "Integer" if child.tag == "Enumeration" else child.tag
            self.variables[sv.get("name")] = (int(sv.get("valueReference")), kind,
                                              sv.get("causality"))
            start = child.get("start")
            if start is not None:
                self.starts[sv.get("name")] = {
                    "Real": float, "Integer": int, "Boolean": lambda x: int(x == "true"),
                    "String": str.encode}[kind](start)
        self.lib = ctypes.CDLL(str(self.root / "binaries" / "linux64" / f"{self.identifier}.so"))
        self._declare()
        # Messages of the instance being created, then routed by the environment pointer.
        self.pending_log: list = []
        self._instances: dict[int, Instance] = {}
        self._logger = LOGGER(self._log)
        self._env_counter = 0
        _MODELS.append(self)

    def _declare(self) -> None:
        L = self.lib
        comp, vrs, st = c_void_p, POINTER(c_uint), c_int
        sig = {
            "fmi2Instantiate": (c_void_p, [c_char_p, c_int, c_char_p, c_char_p,
                                           POINTER(Callbacks), c_int, c_int]),
            "fmi2FreeInstance": (None, [comp]),
            "fmi2SetDebugLogging": (st, [comp, c_int, c_size_t, c_void_p]),
            "fmi2SetupExperiment": (st, [comp, c_int, c_double, c_double, c_int, c_double]),
            "fmi2EnterInitializationMode": (st, [comp]),
            "fmi2ExitInitializationMode": (st, [comp]),
            "fmi2Terminate": (st, [comp]),
            "fmi2Reset": (st, [comp]),
            "fmi2GetReal": (st, [comp, vrs, c_size_t, POINTER(c_double)]),
            "fmi2GetInteger": (st, [comp, vrs, c_size_t, POINTER(c_int)]),
            "fmi2GetBoolean": (st, [comp, vrs, c_size_t, POINTER(c_int)]),
            "fmi2GetString": (st, [comp, vrs, c_size_t, POINTER(c_char_p)]),
            "fmi2SetReal": (st, [comp, vrs, c_size_t, POINTER(c_double)]),
            "fmi2SetInteger": (st, [comp, vrs, c_size_t, POINTER(c_int)]),
            "fmi2SetBoolean": (st, [comp, vrs, c_size_t, POINTER(c_int)]),
            "fmi2SetString": (st, [comp, vrs, c_size_t, POINTER(c_char_p)]),
            "fmi2GetFMUstate": (st, [comp, POINTER(c_void_p)]),
            "fmi2SetFMUstate": (st, [comp, c_void_p]),
            "fmi2FreeFMUstate": (st, [comp, POINTER(c_void_p)]),
            "fmi2SerializedFMUstateSize": (st, [comp, c_void_p, POINTER(c_size_t)]),
            "fmi2SerializeFMUstate": (st, [comp, c_void_p, POINTER(c_char), c_size_t]),
            "fmi2DeSerializeFMUstate": (st, [comp, POINTER(c_char), c_size_t,
                                             POINTER(c_void_p)]),
            "fmi2DoStep": (st, [comp, c_double, c_double, c_int]),
            "fmi2CancelStep": (st, [comp]),
            "fmi2GetStatus": (st, [comp, c_int, POINTER(c_int)]),
            "fmi2GetRealStatus": (st, [comp, c_int, POINTER(c_double)]),
            "fmi2GetIntegerStatus": (st, [comp, c_int, POINTER(c_int)]),
            "fmi2GetBooleanStatus": (st, [comp, c_int, POINTER(c_int)]),
            "fmi2GetStringStatus": (st, [comp, c_int, POINTER(c_char_p)]),
            "fmi2GetDirectionalDerivative": (st, [comp, vrs, c_size_t, vrs, c_size_t,
                                                  POINTER(c_double), POINTER(c_double)]),
        }
        for name, (restype, argtypes) in sig.items():
            f = getattr(L, name)
            f.restype, f.argtypes = restype, argtypes

    def _log(self, env, instance, status, category, fmt, arg) -> None:
        if fmt == b"%s":
            entry = (status, _decode(category), _decode(arg))
        else:
            entry = (status, "FORMAT", _decode(fmt))
        target = self._instances.get(env or 0)
        (target.log if target is not None else self.pending_log).append(entry)

    def vr(self, name: str) -> int:
        return self.variables[name][0]

    def names(self, kind: str | None = None, causality: str | None = None) -> list[str]:
        return [n for n, (_, k, c) in self.variables.items()
                if (kind is None or k == kind) and (causality is None or c == causality)]

    def resources_uri(self) -> bytes:
        return ("file://" + quote(os.fsencode(self.root / "resources"))).encode()

    def instantiate(self, name=b"inst", kind: int = CO_SIMULATION, guid: bytes | None = None,
                    location: bytes | None = None, logging_on: int = 0,
                    default_location: bool = True) -> Instance | None:
        """A new instance (None if fmi2Instantiate returned NULL; its messages are then in
        ``pending_log``)."""
        self._env_counter += 1
        env = self._env_counter
        callbacks = Callbacks(self._logger, None, None, None, env)
        self.pending_log = []
        if location is None and default_location:
            location = self.resources_uri()
        c = self.lib.fmi2Instantiate(name, kind, self.guid.encode() if guid is None else guid,
                                     location, ctypes.byref(callbacks), 0, logging_on)
        if not c:
            return None
        inst = Instance(self, c, callbacks)
        inst.log.extend(self.pending_log)
        self._instances[env] = inst
        return inst


def _array(ctype, values):
    return (ctype * max(1, len(values)))(*values)


class Instance:
    """One FMU instance: thin wrappers that return the raw status."""

    def __init__(self, model: Model, c, callbacks):
        self.m, self.c, self.callbacks = model, c, callbacks
        self.L = model.lib
        self.log: list = []

    # -- life cycle
    def setup(self, start=0.0, tol=None, stop=None) -> int:
        return self.L.fmi2SetupExperiment(self.c, tol is not None, tol or 0.0, start,
                                          stop is not None, stop or 0.0)

    def enter(self) -> int:
        return self.L.fmi2EnterInitializationMode(self.c)

    def exit(self) -> int:
        return self.L.fmi2ExitInitializationMode(self.c)

    def terminate(self) -> int:
        return self.L.fmi2Terminate(self.c)

    def reset(self) -> int:
        return self.L.fmi2Reset(self.c)

    def free(self) -> None:
        self.L.fmi2FreeInstance(self.c)
        self.c = None

    def step(self, t: float, h: float, no_prior: int = 1) -> int:
        return self.L.fmi2DoStep(self.c, t, h, no_prior)

    def logging(self, on: int, categories) -> int:
        if categories is None:
            return self.L.fmi2SetDebugLogging(self.c, on, 0, None)
        arr = (c_char_p * max(1, len(categories)))(*categories)
        return self.L.fmi2SetDebugLogging(self.c, on, len(categories), arr)

    # -- values
    def set(self, kind: str, vrs, values) -> int:
        ctype = {"Real": c_double, "Integer": c_int, "Boolean": c_int, "String": c_char_p}[kind]
        values = [v.encode() if isinstance(v, str) else v for v in values]
        return getattr(self.L, f"fmi2Set{kind}")(self.c, _array(c_uint, vrs), len(vrs),
                                                  _array(ctype, values))

    def get(self, kind: str, vrs) -> tuple[int, list]:
        ctype = {"Real": c_double, "Integer": c_int, "Boolean": c_int, "String": c_char_p}[kind]
        out = (ctype * max(1, len(vrs)))()
        st = getattr(self.L, f"fmi2Get{kind}")(self.c, _array(c_uint, vrs), len(vrs), out)
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
        """Every variable of the modelDescription, by FMI type (the observable values)."""
        out = {}
        for kind in ("Real", "Integer", "Boolean", "String"):
            names = self.m.names(kind)
            st, values = self.get(kind, [self.m.vr(n) for n in names])
            out[kind] = (st, [v.hex() if isinstance(v, float) else v for v in values])
        return out

    # -- FMU state
    def get_state(self, into: c_void_p | None = None) -> tuple[int, c_void_p]:
        state = into if into is not None else c_void_p()
        return self.L.fmi2GetFMUstate(self.c, ctypes.byref(state)), state

    def set_state(self, state) -> int:
        return self.L.fmi2SetFMUstate(self.c, state)

    def free_state(self, state: c_void_p) -> int:
        return self.L.fmi2FreeFMUstate(self.c, ctypes.byref(state))

    def state_size(self, state) -> tuple[int, int]:
        n = c_size_t(0)
        st = self.L.fmi2SerializedFMUstateSize(self.c, state, ctypes.byref(n))
        return st, n.value

    def serialize(self, state, extra: int = 0, fill: int = 0xA5) -> tuple[int, bytes]:
        """Serialize into a buffer ``extra`` bytes larger than the reported size (negative:
        smaller), pre-filled with ``fill``; returns the status and the whole buffer."""
        st, n = self.state_size(state)
        if st != OK:
            return st, b""
        size = max(0, n + extra)
        buf = ctypes.create_string_buffer(bytes([fill]) * size, size)
        st = self.L.fmi2SerializeFMUstate(self.c, state, buf, size)
        return st, buf.raw

    def deserialize(self, data: bytes, into: c_void_p | None = None) -> tuple[int, c_void_p]:
        state = into if into is not None else c_void_p()
        buf = ctypes.create_string_buffer(data, len(data))
        return self.L.fmi2DeSerializeFMUstate(self.c, buf, len(data), ctypes.byref(state)), state

    def serialized(self) -> bytes:
        """The current state, serialized (exact buffer)."""
        st, state = self.get_state()
        assert st == OK, self.log[-3:]
        st, data = self.serialize(state)
        assert st == OK, self.log[-3:]
        self.free_state(state)
        return data

    # -- status
    def real_status(self, kind: int) -> tuple[int, float]:
        v = c_double(float("nan"))
        return self.L.fmi2GetRealStatus(self.c, kind, ctypes.byref(v)), v.value

    def messages(self, since: int = 0, status: int | None = None) -> list[str]:
        return [m for s, _, m in self.log[since:] if status is None or s == status]


# ------------------------------------------------------------------ serialized states
HEADER = 96


def fnv1a64(data: bytes) -> int:
    """FNV-1a, 64 bits (the checksum of the shim's state envelope), written independently."""
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
    """Extract ``fmu`` into ``folder`` (a bytes path may hold any bytes); returns the folder."""
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
            if mode:
                os.chmod(target, mode)
    return Path(os.fsdecode(folder))
