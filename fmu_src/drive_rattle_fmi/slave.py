"""FMI glue shared by the drive-rattle slaves: registration from the physics specs, parameter
application at the end of initialization, checked stepping, full state save/restore, and
error reporting that never lets an exception escape.

pythonfmu turns any exception raised in a slave method into fmi2Fatal (after which freeing the
instance corrupts the host), and ignores every return value but do_step's.  So every entry
point here catches everything, and reports failures through the status channel of the native
shim (``native.py``): a C ``int`` whose address the shim reads at instantiation, plus the message
variable.  The shim returns that status from the FMI call and logs the message to the host.
A rejected call changes nothing: new values are computed into temporaries and committed last;
a multi-value set is checked whole before any value is stored.

Subclasses declare ``PARAMETERS`` (a parameter dataclass), ``INPUTS`` and ``OUTPUTS`` (signal
specs), and implement ``_build``, ``_step``, ``_outputs`` and the model-state pair.
"""

from __future__ import annotations

import copy
import ctypes
import json
import math
import os
import sys
import traceback
from typing import Any, ClassVar

from pythonfmu import Fmi2Slave
from pythonfmu.enums import Fmi2Causality, Fmi2Status, Fmi2Variability
from pythonfmu.variables import Boolean, Integer, Real, String

from drive_rattle.parameters import ParameterSpec, specs
from drive_rattle.snapshots import MAX_STATE_INTEGER, is_finite_float, short_repr

#: Names of the hidden variables of the native shim: the two String variables of the status
#: channel and the Real the shim answers fmi2GetRealStatus(fmi2LastSuccessfulTime) from.
#: Registered last, so their value references follow the public ones; left out of the
#: modelDescription, and refused by the shim when a host names them.
STATUS_ADDRESS_VARIABLE = "_fmi.status_address"
MESSAGE_VARIABLE = "_fmi.message"
LAST_SUCCESSFUL_TIME_VARIABLE = "_fmi.last_successful_time"

#: Version of the content of an FMU state (the dict of ``_get_fmu_state``).  The native shim
#: wraps serialized states in an envelope with the FMU's GUID, its own version and a checksum.
STATE_FORMAT = 3
#: The modes of the slave's life cycle (FMI 2.0 co-simulation states, condensed).
MODES = ("instantiated", "initialization", "stepping", "terminated")
#: fmi2Integer is a 32-bit int: larger values (the cumulative impact counters) saturate.
INT32_MIN, INT32_MAX = -(2**31), 2**31 - 1


def vr_text(vr: int) -> str:
    """A value reference as the host passed it: fmi2ValueReference is unsigned, pythonfmu hands
    it to Python as a signed C int (so 2^31 arrives as -2^31)."""
    return str(vr % 2**32) if isinstance(vr, int) else repr(vr)

#: Tolerance of the communication-point continuity check, in units of the last step size;
#: masters that compute t = t0 + k h differ from t_prev + h_prev by a few ulps of t.
COMMUNICATION_POINT_TOLERANCE = 1e-9

_VARIABLE_TYPES = {"Real": Real, "Integer": Integer, "Boolean": Boolean, "String": String}


#: Instance name pythonfmu's builder instantiates the slave with to render the description.
_BUILDER_INSTANCE = "dummyInstance"


def _forget_resources_path(resources) -> None:
    """Take this FMU's resources folder back out of ``sys.path``.

    pythonfmu inserts it at the front of the host's ``sys.path`` on every instantiation, to
    import the slave module.  Left there, it grows the path by one entry per instance and makes
    the host import *this FMU's* partial copy of ``drive_rattle`` (without its tooling
    modules) -- also in processes the host starts later, which inherit the path.  Every module
    the FMU needs is imported by now (the packages import their modules eagerly)."""
    if not resources:
        return
    target = os.path.normcase(os.path.abspath(str(resources)))
    sys.path[:] = [p for p in sys.path
                   if not p or os.path.normcase(os.path.abspath(p)) != target]


#: Returned by RattleSlave._guard when the guarded call failed.
_FAILED = object()


class ModelError(Exception):
    """A rejected request; its message is reported to the host as the status' message."""


class RattleSlave(Fmi2Slave):
    """Base of the drive-rattle FMU slaves (see the module docstring)."""

    PARAMETERS: type = None  # a drive_rattle.parameters.ParameterSet subclass
    INPUTS: tuple = ()
    OUTPUTS: tuple = ()
    DEFAULT_EXPERIMENT: ClassVar[dict] = {"startTime": 0.0, "stopTime": 2.0, "stepSize": 1e-4}
    author = "drive-rattle developers"
    license = "MIT"
    version = "0.1.0"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        if self.instance_name != _BUILDER_INSTANCE:  # the builder removes its path itself
            _forget_resources_path(self.resources)
        self._fmi_status = ctypes.c_int(Fmi2Status.ok)
        self._fmi_message = ""
        self._shim_attached = False  # set when the native shim reads the status address
        self._param_specs: dict[str, ParameterSpec] = {}
        self._values: dict[str, Any] = {}
        self._fmi_types: dict[str, str] = {}  # variable name -> FMI type
        self._mode = "instantiated"  # -> initialization -> stepping -> terminated
        self._start_time = 0.0
        self._time = 0.0  # communication point the next step must start from
        self._model = None
        self._provisional = None  # outputs computed in initialization mode
        # Outputs are computed when first read after a step (``_stale``); the quick ones
        # (``_quick_outputs``, e.g. the wheel's angle and speed) right after the step.
        self._stale = False
        self._output_set = frozenset(s.name for s in self.OUTPUTS)
        for _attr, spec in specs(self.PARAMETERS):
            self._param_specs[spec.name] = spec
            self._register(spec.name, spec.fmi_type, Fmi2Causality.parameter,
                           Fmi2Variability.fixed, spec.default, spec.description)
        for spec in self.INPUTS:
            self._register(spec.name, spec.fmi_type, Fmi2Causality.input,
                           Fmi2Variability.continuous, spec.start, spec.description)
        for spec in self.OUTPUTS:
            variability = (Fmi2Variability.continuous if spec.fmi_type == "Real"
                           else Fmi2Variability.discrete)
            zero = 0.0 if spec.fmi_type == "Real" else 0
            self._register(spec.name, spec.fmi_type, Fmi2Causality.output, variability, zero,
                           spec.description)
        self.register_variable(String(
            STATUS_ADDRESS_VARIABLE, causality=Fmi2Causality.local,
            variability=Fmi2Variability.constant,
            getter=self._attach_shim), nested=False)
        self.register_variable(String(
            MESSAGE_VARIABLE, causality=Fmi2Causality.local, variability=Fmi2Variability.discrete,
            getter=lambda: self._fmi_message), nested=False)
        self.register_variable(Real(
            LAST_SUCCESSFUL_TIME_VARIABLE, causality=Fmi2Causality.local,
            variability=Fmi2Variability.continuous, getter=self._last_successful_time),
            nested=False)
        # Per value reference: FMI type and getter, for the hot get/set paths.
        self._vr_fmi_type = [type(v).__name__ for v in self.vars.values()]
        self._vr_getter = [v.getter for v in self.vars.values()]
        self._vr_setter = [v.setter for v in self.vars.values()]
        self._vr_name = [v.name for v in self.vars.values()]
        self._vrs_of_type = {
            fmi_type: frozenset(vr for vr, t in enumerate(self._vr_fmi_type) if t == fmi_type)
            for fmi_type in _VARIABLE_TYPES}

    # ------------------------------------------------------------------ registration
    def _register(self, name, fmi_type, causality, variability, start, description) -> None:
        self._values[name] = start
        self._fmi_types[name] = fmi_type
        var = _VARIABLE_TYPES[fmi_type](
            name, causality=causality, variability=variability, description=description,
            getter=lambda n=name: self._get(n), setter=lambda v, n=name: self._set(n, v))
        self.register_variable(var, nested=False)

    @property
    def public_variables(self) -> list:
        """Registered variables of the interface, in value-reference order (no hidden ones)."""
        return [v for v in self.vars.values() if not v.name.startswith("_fmi.")]

    # ------------------------------------------------------------------ status channel
    def _attach_shim(self) -> str:
        """Address of the status int, read by the native shim once at instantiation."""
        self._shim_attached = True
        return hex(ctypes.addressof(self._fmi_status))

    def _report(self, status: int, message: str) -> None:
        """Make the current FMI call return ``status`` with ``message`` logged to the host.

        Without the shim (a platform it was not built for) the message goes to pythonfmu's
        logger, which delivers it only with debug logging on, and do_step returns False
        (fmi2Discard) so that a failure is never silent."""
        if status >= self._fmi_status.value:
            self._fmi_message = message
            self._fmi_status.value = status
        if not self._shim_attached:
            # pythonfmu hands messages to the host as a printf format: escape '%'.
            self.log(message.replace("%", "%%"), Fmi2Status(status))

    def _last_successful_time(self) -> float:
        """End of the last accepted communication step (the start time before the first):
        the native shim's answer to fmi2GetRealStatus(fmi2LastSuccessfulTime)."""
        if self._model is None:
            self._report(Fmi2Status.error,
                         "getRealStatus(fmi2LastSuccessfulTime): no communication step is "
                         f"possible yet (mode '{self._mode}'); allowed after "
                         "exitInitializationMode")
            return math.nan
        return self._time

    def _guard(self, action: str, fn, *args):
        """Run ``fn``; a ModelError/ValueError becomes an Error status with its message, any
        other exception an Error with its traceback.  Returns fn's result or ``_FAILED``."""
        try:
            return fn(*args)
        except (ModelError, ValueError) as err:
            self._report(Fmi2Status.error, f"{action}: {err}")
        except Exception:  # never let anything reach pythonfmu (it would be fmi2Fatal)
            self._report(Fmi2Status.error, f"{action}: unexpected error\n{traceback.format_exc()}")
        return _FAILED

    # ------------------------------------------------------------------ values
    def _get(self, name: str):
        if name in self._output_set:
            if self._mode == "initialization":
                self._refresh_provisional()
                return self._provisional[name]
            if self._stale:
                self._refresh_outputs()
        return self._values[name]

    def _refresh_outputs(self) -> None:
        """Compute the outputs of the last step (they depend only on the model's state)."""
        self._values.update(self._outputs(self._model))
        self._stale = False

    def _checked_value(self, name: str, value):
        """``value`` converted to the variable's type, if ``name`` may be set now; ModelError
        (nothing stored) otherwise."""
        fmi_type = self._fmi_types[name]
        if name in self._output_set:
            raise ModelError(f"'{name}' is an output and cannot be set")
        if name in self._param_specs and self._mode not in ("instantiated", "initialization"):
            raise ModelError(
                f"parameter '{name}' is fixed: it can only be set before the end of "
                f"initialization (mode is '{self._mode}'); value {value!r} rejected")
        if fmi_type == "Real":
            return float(value)
        if fmi_type == "Integer":
            return int(value)
        if fmi_type == "Boolean":
            return bool(value)
        return str(value)

    def _set(self, name: str, value) -> None:
        self._values[name] = self._checked_value(name, value)
        self._provisional = None

    def _set_values(self, vrs, values, fmi_type: str) -> None:
        """Set several values: every entry is checked before any is stored, so a refused call
        (one bad entry) stores nothing."""
        types, setters, names = self._vr_fmi_type, self._vr_setter, self._vr_name
        n = len(types)

        def apply():
            if len(vrs) != len(values):
                raise ModelError(f"{len(vrs)} value references but {len(values)} values")
            staged = []
            for vr, value in zip(vrs, values, strict=True):
                if not (0 <= vr < n and types[vr] == fmi_type and setters[vr] is not None):
                    raise ModelError(f"no {fmi_type} variable with value reference "
                                     f"{vr_text(vr)}; "
                                     "nothing of this call was stored")
                name = names[vr]
                try:
                    staged.append((name, self._checked_value(name, value)))
                except ModelError as err:
                    raise ModelError(f"{err}; nothing of this call was stored") from None
            for name, value in staged:
                self._values[name] = value
            if staged:
                self._provisional = None
        self._guard(f"set{fmi_type}", apply)

    def _get_values(self, vrs, fmi_type: str, default) -> list:
        getters = self._vr_getter
        if self._vrs_of_type[fmi_type].issuperset(vrs):
            try:  # fast path: every getter at once (they only read stored values)
                return [getters[vr]() for vr in vrs]
            except Exception:  # redone value by value below, with the reports
                pass
        types = self._vr_fmi_type
        n = len(types)
        out = []
        for vr in vrs:
            if not (0 <= vr < n and types[vr] == fmi_type):
                self._report(Fmi2Status.error, f"get{fmi_type}: no {fmi_type} variable with "
                                               f"value reference {vr_text(vr)}")
                out.append(default)
                continue
            value = self._guard(f"get{fmi_type} vr {vr_text(vr)}", getters[vr])
            out.append(default if value is _FAILED else value)
        return out

    def set_real(self, vrs, values):
        self._set_values(vrs, values, "Real")

    def set_integer(self, vrs, values):
        self._set_values(vrs, values, "Integer")

    def set_boolean(self, vrs, values):
        self._set_values(vrs, values, "Boolean")

    def set_string(self, vrs, values):
        self._set_values(vrs, values, "String")

    def get_real(self, vrs):
        return [float(v) for v in self._get_values(vrs, "Real", math.nan)]

    def get_integer(self, vrs):
        # fmi2Integer is 32 bits: saturate (the cumulative counters can exceed it), never wrap.
        return [min(INT32_MAX, max(INT32_MIN, int(v)))
                for v in self._get_values(vrs, "Integer", 0)]

    def get_boolean(self, vrs):
        return [bool(v) for v in self._get_values(vrs, "Boolean", False)]

    def get_string(self, vrs):
        return [str(v) for v in self._get_values(vrs, "String", "")]

    # ------------------------------------------------------------------ parameters
    def parameters(self):
        """The parameter set from the current parameter values (ValueError if invalid)."""
        return self.PARAMETERS.from_public(
            {name: self._values[name] for name in self._param_specs})

    def inputs(self) -> dict[str, float]:
        return {s.name: self._values[s.name] for s in self.INPUTS}

    def _check_inputs(self, inputs: dict[str, float]) -> None:
        for spec in self.INPUTS:
            spec.check(inputs[spec.name])

    def _refresh_provisional(self) -> None:
        """Initial unknowns in initialization mode: outputs of a model built from the current
        values (nothing committed; an invalid set leaves the start values)."""
        if self._provisional is not None:
            return
        try:
            self._check_inputs(self.inputs())
            model = self._build(self.parameters(), self.inputs())
            self._provisional = {**self._values, **self._outputs(model)}
        except Exception:  # reported at exitInitializationMode, where it matters
            self._provisional = dict(self._values)

    # ------------------------------------------------------------------ FMI life cycle
    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        def setup():
            if not math.isfinite(start_time):
                raise ModelError(f"start time {start_time!r} is not finite")
            if self._mode != "instantiated":
                raise ModelError(f"setupExperiment is not allowed in mode '{self._mode}'")
            self._start_time = float(start_time)
        self._guard("setupExperiment", setup)

    def enter_initialization_mode(self):
        def enter():
            if self._mode != "instantiated":
                raise ModelError(
                    f"enterInitializationMode is not allowed in mode '{self._mode}'")
            self._mode = "initialization"
            self._provisional = None
        self._guard("enterInitializationMode", enter)

    def exit_initialization_mode(self):
        def leave():
            if self._mode != "initialization":
                raise ModelError(
                    f"exitInitializationMode is not allowed in mode '{self._mode}'")
            params = self.parameters()
            inputs = self.inputs()
            self._check_inputs(inputs)
            model = self._build(params, inputs)
            outputs = self._outputs(model)
            # Commit only now that everything succeeded.
            self._model = model
            self._values.update(outputs)
            self._time = self._start_time
            self._mode = "stepping"
            self._provisional = None
        self._guard("exitInitializationMode", leave)

    def do_step(self, current_time, step_size, no_set_fmu_state_prior=False):
        def step():
            if self._mode != "stepping":
                raise ModelError(f"doStep is not allowed in mode '{self._mode}' (initialize first)")
            if not (math.isfinite(step_size) and step_size > 0.0):
                raise ModelError(
                    f"communication step size {step_size!r} s is invalid; allowed: finite, > 0")
            if not math.isfinite(current_time):  # (its ulp, inf, would pass the check below)
                raise ModelError(f"communication point {current_time!r} s is not finite; "
                                 f"allowed: the end of the last step, {self._time!r} s")
            tol = COMMUNICATION_POINT_TOLERANCE * step_size + 16.0 * math.ulp(
                max(abs(self._time), abs(current_time)))
            if not (abs(current_time - self._time) <= tol):
                raise ModelError(
                    f"communication point {current_time!r} s does not continue the last step, "
                    f"which ended at {self._time!r} s (tolerance {tol:.3g} s)")
            inputs = self.inputs()
            self._check_inputs(inputs)
            self._step(current_time, step_size, inputs)
            quick = self._quick_outputs(self._model)
            self._values.update(quick)
            self._stale = len(quick) < len(self._output_set)
            self._time = current_time + step_size
        failed = self._guard("doStep", step) is _FAILED
        # With the shim the status channel carries the failure (and True keeps pythonfmu from
        # flagging the instance as terminated); without it, Discard is the only non-OK status.
        return self._shim_attached or not failed

    def terminate(self):
        def stop():
            if self._mode not in ("stepping", "initialization"):
                raise ModelError(f"terminate is not allowed in mode '{self._mode}'")
            self._mode = "terminated"
        self._guard("terminate", stop)

    # ------------------------------------------------------------------ FMU state
    def _get_fmu_state(self) -> dict:
        if self._stale:
            self._guard("getFMUstate", self._refresh_outputs)
        state = self._guard("getFMUstate", lambda: copy.deepcopy({
            "format": STATE_FORMAT,
            "mode": self._mode,
            "start_time": self._start_time,
            "time": self._time,
            "values": self._values,
            "model": None if self._model is None else self._model_state(self._model),
        }))
        return {} if state is _FAILED else state

    def _set_fmu_state(self, state: dict) -> None:
        """Restore a state of ``_get_fmu_state``: its content is checked whole (format, mode,
        finite times, every variable present with a value of its type, the model's snapshot)
        and the model is rebuilt from the snapshot -- no start equilibrium is solved, no start
        condition checked and no file read.  An invalid state changes nothing."""
        def restore():
            s = self._checked_state(state)
            model = None
            if s["model"] is not None:
                params_values = {name: s["values"][name] for name in self._param_specs}
                try:
                    params = self.PARAMETERS.from_public(params_values)
                    model = self._model_from_snapshot(params, s["start_time"], s["model"])
                except (ValueError, TypeError, KeyError, IndexError) as err:
                    raise ModelError(f"the FMU state is invalid: {err}; nothing changed"
                                     ) from None
            self._values = s["values"]
            self._model = model
            self._stale = False
            self._mode = s["mode"]
            self._start_time = s["start_time"]
            self._time = s["time"]
            self._provisional = None
        self._guard("setFMUstate", restore)

    def _checked_state(self, state) -> dict:
        """A deep copy of ``state`` if its content is a valid state of this slave; ModelError
        naming the first problem otherwise."""
        def invalid(what: str) -> ModelError:
            return ModelError(f"the FMU state is invalid: {what}; nothing changed")

        if not isinstance(state, dict) or not state:
            raise invalid("it is empty or not a state of this FMU")
        if state.get("format") != STATE_FORMAT:
            raise invalid(f"its format is {state.get('format')!r}, this FMU reads format "
                          f"{STATE_FORMAT}")
        keys = {"format", "mode", "start_time", "time", "values", "model"}
        if set(state) != keys:
            raise invalid(f"its entries are {sorted(state)}, expected {sorted(keys)}")
        s = copy.deepcopy(state)
        if s["mode"] not in MODES:
            raise invalid(f"mode {s['mode']!r} is not one of {', '.join(MODES)}")
        for key in ("start_time", "time"):
            if not is_finite_float(s[key]):
                raise invalid(f"{key} = {s[key]!r} is not a finite float")
        values = s["values"]
        if not isinstance(values, dict) or set(values) != set(self._values):
            missing = sorted(set(self._values) - set(values)) if isinstance(values, dict) else []
            extra = sorted(set(values) - set(self._values)) if isinstance(values, dict) else []
            raise invalid(f"its variables do not match this FMU's (missing {missing[:3]}, "
                          f"unknown {extra[:3]})")
        for name, value in values.items():
            problem = _value_problem(self._fmi_types[name], value, name in self._output_set)
            if problem:
                raise invalid(f"variable '{name}' = {short_repr(value)}: {problem}")
        model_expected = s["mode"] == "stepping" or (
            s["mode"] == "terminated" and s["model"] is not None)
        if model_expected != (s["model"] is not None) or (
                s["model"] is not None and not isinstance(s["model"], dict)):
            raise invalid(f"mode {s['mode']!r} does not go with model snapshot "
                          f"{short_repr(s['model'])}")
        return s

    @staticmethod
    def _fmu_state_to_bytes(state: dict) -> bytes:
        # repr-based JSON: every finite float round-trips bit for bit.
        return json.dumps(state, sort_keys=True).encode("utf-8")

    @staticmethod
    def _fmu_state_from_bytes(state: bytes) -> dict:
        try:
            return json.loads(state.decode("utf-8"))
        except Exception:
            return {}

    # ------------------------------------------------------------------ model description
    def to_xml(self, model_options=None):
        from .model_description import model_description

        return model_description(self)

    # ------------------------------------------------------------------ subclass hooks
    def _build(self, params, inputs: dict[str, float]):
        """A new model for the parameters and the initial inputs (raise ValueError if invalid)."""
        raise NotImplementedError

    def _step(self, t: float, h: float, inputs: dict[str, float]) -> None:
        """Advance ``self._model`` from t by h with the inputs; raise ValueError to reject
        (the model must then be unchanged)."""
        raise NotImplementedError

    def _outputs(self, model) -> dict[str, Any]:
        """Output values of a model."""
        raise NotImplementedError

    def _quick_outputs(self, model) -> dict[str, Any]:
        """Outputs cheap enough to refresh right after every step (those a master reads every
        step); the rest are computed when first read.  Default: none."""
        return {}

    def _model_state(self, model) -> dict:
        """JSON-able snapshot of the model's complete state."""
        raise NotImplementedError

    def _model_from_snapshot(self, params, start_time: float, snapshot: dict):
        """The model in the state of a snapshot made by ``_model_state`` (which may come from
        a forged or corrupted FMU state: raise ValueError naming what is invalid).  It must
        not solve start conditions or read files: the snapshot holds everything."""
        raise NotImplementedError


def _value_problem(fmi_type: str, value, output: bool) -> str:
    """Why ``value`` cannot be a stored value of a variable of FMI type ``fmi_type`` ("" if
    it can).  Parameters and inputs may hold what a master set (a NaN is refused where it is
    used); outputs are finite."""
    if fmi_type == "Real":
        if not isinstance(value, float):
            return "expected a float"
        if output and not math.isfinite(value):
            return "an output must be finite"
    elif fmi_type == "Integer":
        if isinstance(value, bool) or not isinstance(value, int):
            return "expected an integer"
        if abs(value) > MAX_STATE_INTEGER:
            return f"beyond +-2^53 (+-{MAX_STATE_INTEGER})"
    elif fmi_type == "Boolean":
        if not isinstance(value, bool):
            return "expected true or false"
    elif not isinstance(value, str):
        return "expected a string"
    elif "\0" in value:
        return "a string with a NUL character"
    else:
        try:
            value.encode("utf-8")
        except UnicodeEncodeError:
            return "a string that is not valid Unicode"
    return ""
