"""FMI glue shared by the drive-rattle slaves: registration from the physics specs, parameter
application at the end of initialization, checked stepping, full state save/restore, and
error reporting that never lets an exception escape.

pythonfmu turns any exception raised in a slave method into fmi2Fatal (after which freeing the
instance corrupts the host), and ignores every return value but do_step's.  So every entry
point here catches everything, and reports failures through the status channel of the native
shim (``native.py``): a C ``int`` whose address the shim reads at instantiation, plus the message
variable.  The shim returns that status from the FMI call and logs the message to the host.
A rejected call changes nothing: new values are computed into temporaries and committed last.

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

#: Names of the two hidden String variables of the status channel; registered last, so their
#: value references follow the public ones, and left out of the modelDescription.
STATUS_ADDRESS_VARIABLE = "_fmi.status_address"
MESSAGE_VARIABLE = "_fmi.message"

OK, WARNING, DISCARD, ERROR = 0, 1, 2, 3

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
        self._fmi_status = ctypes.c_int(OK)
        self._fmi_message = ""
        self._shim_attached = False  # set when the native shim reads the status address
        self._param_specs: dict[str, ParameterSpec] = {}
        self._values: dict[str, Any] = {}
        self._kinds: dict[str, str] = {}
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
            self._register(spec.name, spec.kind, Fmi2Causality.parameter,
                           Fmi2Variability.fixed, spec.default, spec.description)
        for spec in self.INPUTS:
            self._register(spec.name, spec.kind, Fmi2Causality.input,
                           Fmi2Variability.continuous, spec.start, spec.description)
        for spec in self.OUTPUTS:
            variability = (Fmi2Variability.continuous if spec.kind == "Real"
                           else Fmi2Variability.discrete)
            zero = 0.0 if spec.kind == "Real" else 0
            self._register(spec.name, spec.kind, Fmi2Causality.output, variability, zero,
                           spec.description)
        self.register_variable(String(
            STATUS_ADDRESS_VARIABLE, causality=Fmi2Causality.local,
            variability=Fmi2Variability.constant,
            getter=self._attach_shim), nested=False)
        self.register_variable(String(
            MESSAGE_VARIABLE, causality=Fmi2Causality.local, variability=Fmi2Variability.discrete,
            getter=lambda: self._fmi_message), nested=False)
        # Per value reference: FMI type and getter, for the hot get/set paths.
        self._vr_kind = [self._kinds.get(v.name, "String") for v in self.vars.values()]
        self._vr_getter = [v.getter for v in self.vars.values()]
        self._vr_setter = [v.setter for v in self.vars.values()]
        self._vrs_of_kind = {kind: frozenset(vr for vr, k in enumerate(self._vr_kind) if k == kind)
                             for kind in ("Real", "Integer", "Boolean", "String")}

    # ------------------------------------------------------------------ registration
    def _register(self, name, kind, causality, variability, start, description) -> None:
        self._values[name] = start
        self._kinds[name] = kind
        var = _VARIABLE_TYPES[kind](
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

    def _guard(self, action: str, fn, *args):
        """Run ``fn``; a ModelError/ValueError becomes an Error status with its message, any
        other exception an Error with its traceback.  Returns fn's result or ``_FAILED``."""
        try:
            return fn(*args)
        except (ModelError, ValueError) as err:
            self._report(ERROR, f"{action}: {err}")
        except Exception:  # never let anything reach pythonfmu (it would be fmi2Fatal)
            self._report(ERROR, f"{action}: unexpected error\n{traceback.format_exc()}")
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

    def _set(self, name: str, value) -> None:
        kind = self._kinds[name]
        if name in self._output_set:
            raise ModelError(f"'{name}' is an output and cannot be set")
        if name in self._param_specs and self._mode not in ("instantiated", "initialization"):
            raise ModelError(
                f"parameter '{name}' is fixed: it can only be set before the end of "
                f"initialization (mode is '{self._mode}'); value {value!r} rejected")
        if kind == "Real":
            value = float(value)
        elif kind == "Integer":
            value = int(value)
        elif kind == "Boolean":
            value = bool(value)
        else:
            value = str(value)
        self._values[name] = value
        self._provisional = None

    def _set_values(self, vrs, values, kind: str) -> None:
        kinds, setters = self._vr_kind, self._vr_setter
        n = len(kinds)

        def apply():
            for vr, value in zip(vrs, values, strict=True):
                if not (0 <= vr < n and kinds[vr] == kind and setters[vr] is not None):
                    raise ModelError(f"no {kind} variable with value reference {vr}")
                setters[vr](value)
        self._guard(f"set{kind}", apply)

    def _get_values(self, vrs, kind: str, default) -> list:
        getters = self._vr_getter
        if self._vrs_of_kind[kind].issuperset(vrs):
            try:  # fast path: every getter at once (they only read stored values)
                return [getters[vr]() for vr in vrs]
            except Exception:  # redone value by value below, with the reports
                pass
        kinds = self._vr_kind
        n = len(kinds)
        out = []
        for vr in vrs:
            if not (0 <= vr < n and kinds[vr] == kind):
                self._report(ERROR, f"get{kind}: no {kind} variable with value reference {vr}")
                out.append(default)
                continue
            value = self._guard(f"get{kind} vr {vr}", getters[vr])
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
        return [int(v) for v in self._get_values(vrs, "Integer", 0)]

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
            "mode": self._mode,
            "start_time": self._start_time,
            "time": self._time,
            "values": self._values,
            "model": None if self._model is None else self._model_state(self._model),
        }))
        return {} if state is _FAILED else state

    def _set_fmu_state(self, state: dict) -> None:
        def restore():
            if not state:
                raise ModelError("the FMU state is empty or invalid")
            s = copy.deepcopy(state)
            values = dict(self._values)
            for name, value in s["values"].items():
                if name not in values:
                    raise ModelError(f"the FMU state holds an unknown variable '{name}'")
                values[name] = value
            model = None
            if s["model"] is not None:
                saved_values, self._values = self._values, values
                try:
                    model = self._build(self.parameters(), self.inputs())
                finally:
                    self._values = saved_values
                self._restore_model_state(model, s["model"])
            self._values = values
            self._model = model
            self._stale = False
            self._mode = s["mode"]
            self._start_time = s["start_time"]
            self._time = s["time"]
            self._provisional = None
        self._guard("setFMUstate", restore)

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

    def _model_state(self, model) -> Any:
        """JSON-able snapshot of the model's complete state."""
        raise NotImplementedError

    def _restore_model_state(self, model, state) -> None:
        """Load a snapshot made by ``_model_state`` into a freshly built model."""
        raise NotImplementedError
