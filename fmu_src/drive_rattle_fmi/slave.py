"""The pythonfmu face of the model library: a slave class per unit (``slave_class``) whose every
FMI call is one call of the library (``fmu_src/rattle_model``, through ``drive_rattle.library``).

The slave holds one library unit (``rm_new``) and forwards to it: values by value reference
(the library's table index), setupExperiment, the initialization mode, doStep, terminate,
reset and the FMU state (the library's binary record, ``rm_save`` / ``rm_restore``).  It holds no
model rule, check or message of its own: what the library refuses or warns about reaches the
host with the library's message (``rm_message``) verbatim, through the status channel of the
status shim (``drive_rattle_build.shim``): a C ``int`` whose address the shim reads at
instantiation, and the message variable.  Without the shim (a platform it was not built for),
the message goes to pythonfmu's logger and doStep returns False (fmi2Discard), so that a
failure is never silent.

pythonfmu turns an exception raised in a slave method into fmi2Fatal (after which freeing the
instance corrupts the host): no method lets one out.  The few refusals written here are the
binding's (a Python value that a C argument cannot carry, when the slave is driven from Python
directly); pythonfmu's wrapper never passes such values.

Registration follows the specs (``drive_rattle.parameters`` for the parameters,
``drive_rattle.interface`` for the inputs and outputs), in the order of the library's tables,
which are generated from the same specs: a value reference is the library's index.  The three
hidden variables of the status channel are registered last.

The slave classes are made once per process, here (``slave_class``), and the slave modules
(``fmu_src/slaves/GearMeshRattle.py``, ``fmu_src/slaves/Driveline.py``) only name them:
pythonfmu 0.7.0's wrapper executes the slave module's source anew at every fmi2Instantiate and
keeps a reference to every class that source creates, so a class defined in the slave module
stayed alive once per instantiation (about 17 kiB each; tests/adversarial/test_endurance.py).
What the wrapper still leaks per call (about 1 kiB) the status shim avoids by keeping freed
instances idle for reuse; and the wrapper's release of a reference to the module's namespace
that it never took is made good by ``hold_namespace``.
"""

from __future__ import annotations

import ctypes
import hashlib
import math
import os
import sys
import weakref
from pathlib import Path
from typing import ClassVar

from pythonfmu import Fmi2Slave
from pythonfmu.enums import Fmi2Causality, Fmi2Status, Fmi2Variability
from pythonfmu.variables import Boolean, Integer, Real, String

from drive_rattle import interface, library
from drive_rattle.catalog import UNITS
from drive_rattle.parameters import specs

#: Names of the hidden variables of the status shim: the two String variables of the status
#: channel and the Real the shim answers fmi2GetRealStatus(fmi2LastSuccessfulTime) from.
#: Registered last, so that the public value references are the library's indexes; left out
#: of the modelDescription, and refused by the shim when a host names them.
STATUS_ADDRESS_VARIABLE = "_fmi.status_address"
MESSAGE_VARIABLE = "_fmi.message"
LAST_SUCCESSFUL_TIME_VARIABLE = "_fmi.last_successful_time"

_VARIABLE_TYPES = {"Real": Real, "Integer": Integer, "Boolean": Boolean, "String": String}
_C_TYPES = {"Real": ctypes.c_double, "Integer": ctypes.c_int32, "Boolean": ctypes.c_int32,
            "String": ctypes.c_char_p}
#: fmi2ValueReference is unsigned; pythonfmu hands it to Python as a signed C int (2^31 arrives
#: as -2^31): both ranges are accepted and taken modulo 2^32, as C does.
_VR_MIN, _VR_END = -(2**31), 2**32
_INT32_MIN, _INT32_END = -(2**31), 2**31
#: Instance name pythonfmu's builder instantiates the slave with to render the description.
_BUILDER_INSTANCE = "dummyInstance"


def _no_getter():
    """The getter of every registered variable: pythonfmu calls getters only from the methods
    this face overrides.  (Without one, pythonfmu would bind a closure on the slave: a
    reference cycle that keeps a freed slave, and its unit, until the garbage collector runs.)"""
    return None


def _forget_resources_path(resources) -> None:
    """Take this FMU's resources folder back out of ``sys.path``.

    pythonfmu inserts it at the front of the host's ``sys.path`` on every instantiation, to
    import the slave module.  Left there, it grows the path by one entry per instance and makes
    the host import *this FMU's* copy of ``drive_rattle`` -- also in processes the host starts
    later, which inherit the path.  Every module the FMU needs is imported by now (the packages
    import their modules eagerly)."""
    if not resources:
        return
    target = os.path.normcase(os.path.abspath(str(resources)))
    sys.path[:] = [p for p in sys.path
                   if not p or os.path.normcase(os.path.abspath(p)) != target]


_BY_CONTENT: dict[bytes, ctypes.CDLL] = {}


def _library_of(resources) -> ctypes.CDLL:
    """The model library of this FMU: its own copy in ``resources/drive_rattle/`` (all
    pythonfmu FMUs of a process share one interpreter, so the ``drive_rattle`` package in
    ``sys.modules`` may be another FMU's, whose folder the host may have deleted), else the
    binding's default (a slave class driven from a source checkout).  A copy with the same
    bytes as one loaded already is that one: a host that unpacks the FMU anew for every run
    (fmpy's simulate_fmu) does not map one more library each time."""
    if resources:
        own = Path(resources) / "drive_rattle" / library.LIBRARY_NAME
        try:
            key = hashlib.sha256(own.read_bytes()).digest()
        except OSError:
            key = None
        if key is not None:
            lib = _BY_CONTENT.get(key)
            if lib is None:
                lib = _BY_CONTENT[key] = library.load(own)
            return lib
    return library.load()


class _FaceError(Exception):
    """A Python value the library's C interface cannot carry (the binding's refusal)."""


class RattleSlave(Fmi2Slave):
    """Base of the drive-rattle slaves: one library unit of kind ``KIND`` behind the FMI
    calls (see the module docstring).  Subclasses are made by :func:`slave_class`."""

    KIND: ClassVar[int] = -1  # library.MESH or library.DRIVELINE
    PARAMETERS: ClassVar[type] = None  # the parameter dataclass of the unit (its specs)
    INPUTS: ClassVar[tuple] = ()
    OUTPUTS: ClassVar[tuple] = ()
    DEFAULT_EXPERIMENT: ClassVar[dict] = interface.DEFAULT_EXPERIMENT
    #: The FMU's modelDescription, rendered from the specs by the build
    #: (``drive_rattle_build.model_description``) and handed to pythonfmu's builder here.
    MODEL_DESCRIPTION: ClassVar = None
    description: ClassVar[str] = ""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        if self.instance_name != _BUILDER_INSTANCE:  # the builder removes its path itself
            _forget_resources_path(self.resources)
        self._fmi_status = ctypes.c_int(Fmi2Status.ok)
        self._fmi_message = ""
        self._shim_attached = False  # set when the status shim reads the status address
        self._lib = lib = _library_of(self.resources)
        self._register_variables(lib)
        n = self._n_public
        self._vr_status_address, self._vr_message, self._vr_last_time = n, n + 1, n + 2
        self._hidden = frozenset((n, n + 1, n + 2))
        resources = os.fsencode(self.resources) if self.resources else None
        unit = lib.rm_new(self.KIND, resources)
        if not unit:
            raise library.LibraryError(f"rm_new({self.KIND}) failed: out of memory")
        # held as a raw pointer, not a Python int, so that a leak checker scanning the
        # process's memory finds the unit (LeakSanitizer: tests/sanitize)
        self._unit = ctypes.c_void_p(unit)
        # Freed with the slave (pythonfmu has no free hook: fmi2FreeInstance and fmi2Reset
        # drop the slave object); not at interpreter exit, where the library may be gone.
        self._free = weakref.finalize(self, lib.rm_free, unit)
        self._free.atexit = False
        self._state_buffer = None  # made by the first getFMUstate

    # ------------------------------------------------------------------ registration
    def _register_variables(self, lib) -> None:
        """Register the variables from the specs and check them against the library's table:
        the same names, types and causalities in the same order.  Once per class and library:
        the variables hold nothing of an instance (no getter or setter is used), so every
        instance shares them."""
        cls = type(self)
        shared = cls.__dict__.get("_registered")
        if shared is not None and shared[0] is lib:
            self.vars, self._n_public = shared[1], shared[2]
            return
        for _attr, spec in specs(self.PARAMETERS):
            self._register(spec.name, spec.fmi_type, Fmi2Causality.parameter,
                           Fmi2Variability.fixed, spec.description)
        for spec in self.INPUTS:
            self._register(spec.name, spec.fmi_type, Fmi2Causality.input,
                           Fmi2Variability.continuous, spec.description)
        for spec in self.OUTPUTS:
            variability = (Fmi2Variability.continuous if spec.fmi_type == "Real"
                           else Fmi2Variability.discrete)
            self._register(spec.name, spec.fmi_type, Fmi2Causality.output, variability,
                           spec.description)
        _check_table(cls, lib, [(v.name, type(v).__name__, v.causality.name)
                                for v in self.vars.values()])
        self._n_public = len(self.vars)
        for name, var_type, variability in (
                (STATUS_ADDRESS_VARIABLE, String, Fmi2Variability.constant),
                (MESSAGE_VARIABLE, String, Fmi2Variability.discrete),
                (LAST_SUCCESSFUL_TIME_VARIABLE, Real, Fmi2Variability.continuous)):
            self.register_variable(var_type(name, causality=Fmi2Causality.local,
                                            variability=variability, getter=_no_getter),
                                   nested=False)
        cls._registered = (lib, self.vars, self._n_public)

    def _register(self, name, fmi_type, causality, variability, description) -> None:
        self.register_variable(_VARIABLE_TYPES[fmi_type](
            name, causality=causality, variability=variability, description=description,
            getter=_no_getter), nested=False)

    @property
    def public_variables(self) -> list:
        """Registered variables of the interface, in value-reference order (no hidden ones)."""
        return list(self.vars.values())[:self._n_public]

    @property
    def _param_specs(self) -> dict:
        """Public name -> ParameterSpec of the unit's parameters."""
        return {spec.name: spec for _attr, spec in specs(self.PARAMETERS)}

    @property
    def _fmi_types(self) -> dict:
        """Public name -> FMI type of every public variable."""
        return {v.name: type(v).__name__ for v in self.public_variables}

    # ------------------------------------------------------------------ status channel
    def _attach_shim(self) -> str:
        """Address of the status int, read by the status shim once at instantiation."""
        self._shim_attached = True
        return hex(ctypes.addressof(self._fmi_status))

    def _report(self, status: int, message: str) -> None:
        """Make the current FMI call return ``status`` with ``message`` logged to the host."""
        if status >= self._fmi_status.value:
            self._fmi_message = message
            self._fmi_status.value = status
        if not self._shim_attached:
            # pythonfmu hands messages to the host as a printf format: escape '%'.
            self.log(message.replace("%", "%%"), Fmi2Status(status))

    def _answer(self, status: int) -> int:
        """Pass a library status with its message to the host; returns it."""
        if status != library.OK:
            msg = self._lib.rm_message(self._unit)
            self._report(status if status in (library.WARNING, library.ERROR) else
                         library.ERROR, msg.decode("utf-8", "replace") if msg else "")
        return status

    def _failed(self, action: str, err: Exception) -> int:
        """A call the face could not make: an Error with the reason (never an exception)."""
        reason = str(err) if isinstance(err, _FaceError) else f"unexpected {err!r}"
        self._report(library.ERROR, f"{action}: {reason}")
        return library.ERROR

    def _last_successful_time(self) -> float:
        t = ctypes.c_double(math.nan)
        self._answer(self._lib.rm_last_successful_time(self._unit, ctypes.byref(t)))
        return t.value

    # ------------------------------------------------------------------ values
    def _get(self, fmi_type: str, vrs, default) -> list:
        action = f"get{fmi_type}"
        try:
            if self._hidden.isdisjoint(vrs):
                return self._get_values(fmi_type, vrs, action)
            return self._get_hidden(fmi_type, vrs, action)
        except Exception as err:
            self._failed(action, err)
            return [default] * _length(vrs)

    def _get_values(self, fmi_type: str, vrs, action: str) -> list:
        """One library call: the values of ``vrs`` (the library's refusals for bad ones)."""
        n = len(vrs)
        out = (_C_TYPES[fmi_type] * n)()
        self._answer(getattr(self._lib, f"rm_get_{fmi_type.lower()}")(
            self._unit, _vr_array(vrs, action), n, out))
        return out[:]

    def _get_hidden(self, fmi_type: str, vrs, action: str) -> list:
        """A get that names hidden variables (the status shim's reads): those of the right
        type are answered here, the others by the library (which refuses them)."""
        hidden = {(self._vr_status_address, "String"): self._attach_shim,
                  (self._vr_message, "String"): lambda: self._fmi_message,
                  (self._vr_last_time, "Real"): self._last_successful_time}
        ours = [(vr, fmi_type) in hidden for vr in vrs]
        rest = [vr for vr, own in zip(vrs, ours, strict=True) if not own]
        values = iter(self._get_values(fmi_type, rest, action) if rest else ())
        return [hidden[vr, fmi_type]() if own else next(values)
                for vr, own in zip(vrs, ours, strict=True)]

    def get_real(self, vrs):
        return self._get("Real", vrs, math.nan)

    def get_integer(self, vrs):
        return self._get("Integer", vrs, 0)

    def get_boolean(self, vrs):
        return [bool(v) for v in self._get("Boolean", vrs, False)]

    def get_string(self, vrs):
        values = self._get("String", vrs, "")
        return [v.decode("utf-8", "replace") if isinstance(v, bytes) else v or ""
                for v in values]

    def _set(self, fmi_type: str, vrs, values) -> None:
        action = f"set{fmi_type}"
        try:
            n = len(vrs)
            if len(values) != n:
                raise _FaceError(f"{n} value references but {len(values)} values; nothing of "
                                 "this call was stored")
            array = (_C_TYPES[fmi_type] * n)(*_c_values(fmi_type, values))
            self._answer(getattr(self._lib, f"rm_set_{fmi_type.lower()}")(
                self._unit, _vr_array(vrs, action), n, array))
        except Exception as err:
            self._failed(action, err)

    def set_real(self, vrs, values):
        self._set("Real", vrs, values)

    def set_integer(self, vrs, values):
        self._set("Integer", vrs, values)

    def set_boolean(self, vrs, values):
        self._set("Boolean", vrs, values)

    def set_string(self, vrs, values):
        self._set("String", vrs, values)

    # ------------------------------------------------------------------ FMI life cycle
    def _call(self, action: str, name: str, *args) -> int:
        try:
            return self._answer(getattr(self._lib, name)(self._unit, *args))
        except Exception as err:
            return self._failed(action, err)

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        self._call("setupExperiment", "rm_setup", start_time)

    def enter_initialization_mode(self):
        self._call("enterInitializationMode", "rm_enter_initialization")

    def exit_initialization_mode(self):
        self._call("exitInitializationMode", "rm_exit_initialization")

    def do_step(self, current_time, step_size, no_set_fmu_state_prior=False):
        status = self._call("doStep", "rm_do_step", current_time, step_size)
        # With the shim the status channel carries the failure (and True keeps pythonfmu from
        # flagging the instance as terminated); without it, Discard is the only non-OK status.
        return self._shim_attached or status in (library.OK, library.WARNING)

    def terminate(self):
        self._call("terminate", "rm_terminate")

    def reset(self):
        """The unit as new (pythonfmu's fmi2Reset makes a new slave instead)."""
        self._call("reset", "rm_reset")

    # ------------------------------------------------------------------ FMU state
    def _get_fmu_state(self) -> bytes:
        """The unit as the library's binary record (``rm_save``); b"" when it failed."""
        try:
            size = ctypes.c_size_t()
            buf = self._state_buffer
            if buf is None:
                self._state_buffer = buf = ctypes.create_string_buffer(1024)
            if self._answer(self._lib.rm_save(self._unit, buf, len(buf),
                                              ctypes.byref(size))) == library.ERROR:
                return b""
            if size.value > len(buf):  # grown: save again into a buffer that fits
                self._state_buffer = buf = ctypes.create_string_buffer(size.value)
                if self._answer(self._lib.rm_save(self._unit, buf, len(buf),
                                                  ctypes.byref(size))) == library.ERROR:
                    return b""
            return buf.raw[:size.value]
        except Exception as err:
            self._failed("getFMUstate", err)
            return b""

    def _set_fmu_state(self, state) -> None:
        """The unit as the record ``state`` left it (``rm_restore``: checked whole by the
        library; a refused record changes nothing)."""
        try:
            record = state if isinstance(state, bytes) else bytes(state)
        except Exception:
            self._failed("setFMUstate", _FaceError(
                f"the FMU state is a {type(state).__name__}, not a record of this FMU; "
                "nothing changed"))
            return
        self._call("setFMUstate", "rm_restore", record, len(record))

    @staticmethod
    def _fmu_state_to_bytes(state) -> bytes:
        return state if isinstance(state, bytes) else b""

    @staticmethod
    def _fmu_state_from_bytes(state) -> bytes:
        try:
            return state if isinstance(state, bytes) else bytes(state)
        except Exception:  # refused by _set_fmu_state
            return b""

    # ------------------------------------------------------------------ model description
    def to_xml(self, model_options=None):
        """The modelDescription the build rendered (pythonfmu's builder writes it)."""
        if self.MODEL_DESCRIPTION is None:
            raise RuntimeError(f"{type(self).__name__}: the modelDescription is rendered by "
                               "the build (drive-rattle-build), not by the slave")
        return self.MODEL_DESCRIPTION


def _length(values) -> int:
    try:
        return len(values)
    except Exception:
        return 0


def _vr_array(vrs, action: str) -> ctypes.Array:
    """The value references as fmi2ValueReference (unsigned 32 bits)."""
    for vr in vrs:
        if isinstance(vr, bool) or not isinstance(vr, int) or not _VR_MIN <= vr < _VR_END:
            raise _FaceError(f"value reference {vr!r} is not an fmi2ValueReference (an "
                             f"integer in [0, {_VR_END - 1}]); nothing of this call was done")
    return (ctypes.c_uint * len(vrs))(*vrs)


def _c_values(fmi_type: str, values) -> list:
    """``values`` as the C arguments of the library's setter; _FaceError for a value a C
    argument of the FMI type cannot carry."""
    def refuse(k, value, what):
        return _FaceError(f"value {k} ({value!r}) {what}; nothing of this call was stored")

    out = []
    for k, value in enumerate(values):
        if fmi_type == "Real":
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise refuse(k, value, "is not a real number")
            try:
                out.append(float(value))
            except OverflowError:
                raise refuse(k, value, "is beyond the range of a double") from None
        elif fmi_type == "Integer":
            if isinstance(value, bool) or not isinstance(value, int):
                raise refuse(k, value, "is not an integer")
            if not _INT32_MIN <= value < _INT32_END:
                raise refuse(k, value, "is beyond the 32 bits of an fmi2Integer")
            out.append(value)
        elif fmi_type == "Boolean":
            out.append(1 if value else 0)
        else:
            if not isinstance(value, str):
                raise refuse(k, value, "is not a string")
            if "\0" in value:
                raise refuse(k, value, "holds a NUL character, which an fmi2String cannot")
            # lone surrogates pass as the bytes they would be, for the library's UTF-8 check
            out.append(value.encode("utf-8", "surrogatepass"))
    return out


def hold_namespace(namespace: dict) -> None:
    """Give pythonfmu the reference to a slave module's namespace that it releases at every
    fmi2Instantiate: pythonfmu 0.7.0 executes the slave module's source anew in it to find the
    slave class and then releases it (``Py_DECREF`` of ``PyModule_GetDict``'s borrowed
    reference).  A slave module that defines no class of its own (see the module docstring)
    leaves nothing else holding its namespace, which would then be freed after a few
    instantiations (a crash).  The slave modules call it once per execution: one reference
    each, no memory; with a wrapper that does not release it, the namespace just lives on
    (as it does anyway, in ``sys.modules``)."""
    ctypes.pythonapi.Py_IncRef(ctypes.py_object(namespace))


def _check_table(cls, lib, registered: list[tuple[str, str, str]]) -> None:
    """LibraryError unless the registration (name, FMI type, causality per value reference)
    is the library's table (both come from the specs; a stale or foreign library differs)."""
    table = [(v["name"], v["type"], v["causality"])
             for v in library.variables(cls.KIND, lib)]
    if table != registered:
        first = next((k for k, (a, b) in enumerate(zip(table, registered, strict=False))
                      if a != b), min(len(table), len(registered)))
        raise library.LibraryError(
            f"{cls.__name__}: the model library's variable table does not match the specs "
            f"(value reference {first}: library {table[first:first + 1]}, specs "
            f"{registered[first:first + 1]}; {len(table)} and {len(registered)} variables): "
            "rebuild the FMU")


_CLASSES: dict[str, type] = {}


def slave_class(model: str) -> type:
    """The slave class of ``model`` (``interface.MODELS``), made once per process: a
    :class:`RattleSlave` of the unit's kind, parameters and signals (``catalog.UNITS``), named
    ``model`` (the FMU's model identifier)."""
    cls = _CLASSES.get(model)
    if cls is None:
        unit = UNITS[model]
        cls = type(model, (RattleSlave,), {
            "__doc__": unit.summary, "__module__": __name__, "KIND": unit.kind,
            "PARAMETERS": unit.parameters, "INPUTS": unit.inputs, "OUTPUTS": unit.outputs,
            "description": unit.description})
        _CLASSES[model] = cls
    return cls
