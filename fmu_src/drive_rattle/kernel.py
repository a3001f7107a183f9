"""Compiled twin of the wheel stepper: ``fmu_src/native/rattle_kernel.c`` loaded with ctypes.

The C kernel performs exactly the computation of :meth:`WheelStepper.step` and of
:meth:`WheelStepper.outputs` -- the same floating-point operations in the same order and the
same libm calls -- so its results are identical to the pure-Python stepper's, bit for bit,
only faster (docs/kernel.md).  :class:`CompiledWheelStepper` implements the stepper contract
(``stepper.WheelStepperBase``) beside the Python :class:`WheelStepper`, which stays the
reference, the fallback when the shared library is absent, and the way to get the located
contact events.

The arrays shared with the C code are declared in :mod:`kernel_layout`.  The kernel holds no
message text: a refused step comes back as a code and its numbers, and :func:`refusal` raises
what the Python stepper raises, from the same functions (``stepper``, ``roots``,
``lubrication``) or, where Python fails inside a library call, by making that call.

Standard library only (it ships in the FMU); the build compiles the library
(``drive_rattle_build.kernel``).
"""

from __future__ import annotations

import ctypes
import math
import operator
import struct
from pathlib import Path

from . import kernel_layout as layout
from .lubrication import unknown_form_error
from .parameters import MeshParameters
from .roots import bracket_error
from .stepper import (
    PinionState,
    StepResult,
    WheelSnapshot,
    WheelState,
    WheelStepper,
    WheelStepperBase,
    _check_finite,
    check_step_size,
    diverged_error,
    penetration_error,
    stiffness_error,
)

#: File name of the shared library, next to this module (in an FMU: resources/drive_rattle/).
LIBRARY_NAME = "_rattle_kernel.so"

#: Names of the arrays' entries (kernel_layout declares them).
MODEL_SIZE = layout.MODEL_SIZE
STATE_FIELDS = layout.STATE_FIELDS
RESULT_FIELDS = layout.RESULT_FIELDS
OUTPUT_NAMES = layout.OUTPUT_FIELDS
INTEGER_OUTPUTS = layout.OUTPUT_INTEGERS

#: The library calls of a refusal with code "library", made again here so that Python raises
#: its own exception with its own text (kernel_layout.LIBRARY_CALLS, in order).
_CALLS = {
    "pow": lambda x, y: x**y,
    "sqrt": lambda x, y: math.sqrt(x),
    "log": lambda x, y: math.log(x),
    "exp": lambda x, y: math.exp(x),
    "floor": lambda x, y: math.floor(x),
    "ceil": lambda x, y: math.ceil(x),
    "int": lambda x, y: int(x),
    "none_gt": lambda x, y: operator.gt(None, x),
}
if tuple(_CALLS) != layout.LIBRARY_CALLS:
    raise ImportError("kernel_layout.LIBRARY_CALLS changed; update kernel._CALLS")


# ------------------------------------------------------------------ loading
def default_library_path() -> Path:
    """Where :func:`load_kernel` looks by default: next to this module."""
    return Path(__file__).resolve().parent / LIBRARY_NAME


_LOADED: dict[str, ctypes.CDLL] = {}


def load_kernel(path=None) -> ctypes.CDLL | None:
    """The kernel library at ``path`` (default: :func:`default_library_path`), or None when it
    is absent, cannot be loaded or was built for another layout (its compiled layout hash
    differs from :data:`kernel_layout.LAYOUT_HASH`).  Never raises for these."""
    p = Path(path) if path is not None else default_library_path()
    key = str(p.resolve()) if p.exists() else str(p)
    lib = _LOADED.get(key)
    if lib is not None:
        return lib
    if not p.is_file():
        return None
    try:
        lib = ctypes.CDLL(key)
        layout_hash = lib.rk_layout_hash
        lib.rk_step, lib.rk_outputs  # noqa: B018 (present?)
    except (OSError, AttributeError):
        return None
    layout_hash.argtypes, layout_hash.restype = [], ctypes.c_ulonglong
    if layout_hash() != layout.LAYOUT_HASH:
        return None
    # Pointers only: without argtypes ctypes passes the arrays as pointers with the least
    # per-call work (the hot path).
    lib.rk_step.argtypes, lib.rk_step.restype = None, ctypes.c_int
    lib.rk_outputs.argtypes, lib.rk_outputs.restype = None, ctypes.c_int
    _LOADED[key] = lib
    return lib


# ------------------------------------------------------------------ refusals
def refusal(code: int, values, inputs: dict[str, float] | None = None,
            h_comm_max: float = math.inf) -> Exception:
    """The exception the Python core raises where the kernel returned ``code`` with the
    numbers ``values`` (``kernel_layout.ERROR_CODES``).  ``inputs`` (the step's inputs by
    name) and ``h_comm_max`` serve the "input" code, which the Python checks word."""
    name = layout.ERROR_CODES[code] if 0 <= code < len(layout.ERROR_CODES) else None
    v = list(values)
    if name == "input" and inputs is not None:
        try:
            _check_finite(**{k: x for k, x in inputs.items() if k != "h"})
            check_step_size(inputs["h"], h_comm_max)
        except ValueError as err:
            return err
    elif name == "diverged":
        return diverged_error(v[0], v[1])
    elif name == "penetration":
        return penetration_error(v[0], v[1])
    elif name == "too_stiff":
        return stiffness_error(v[0], v[1], v[2], v[3])
    elif name == "no_bracket":
        return bracket_error(v[0], v[1], v[2], v[3])
    elif name == "friction_form":
        return unknown_form_error(int(v[0]))
    elif name == "library" and 0 <= v[0] < len(layout.LIBRARY_CALLS):
        call = layout.LIBRARY_CALLS[int(v[0])]
        try:
            result = _CALLS[call](v[1], v[2])
        except (ArithmeticError, ValueError, TypeError) as err:
            return err
        return ValueError(f"rattle kernel: {call}({v[1]!r}, {v[2]!r}) = {result!r} is not a "
                          "real number the kernel can go on with")
    elif name == "layout":
        return RuntimeError(
            f"rattle kernel: model array layout mismatch (kernel layout {layout.LAYOUT_HASH} "
            f"with {MODEL_SIZE} fields; rebuild {LIBRARY_NAME} from the sources of this "
            "version)")
    elif name == "model_values":
        return RuntimeError(f"rattle kernel: {int(v[0])} breakpoints, {int(v[1])} Chebyshev "
                            f"terms, law {int(v[2])}: beyond the kernel's arrays")
    elif name == "too_many_pairs":
        return ValueError(f"more than {int(v[0])} tooth pairs in the zone of action")
    elif name == "pair_number_range":
        return ValueError(f"roll coordinate {v[0]!r} m beyond the kernel's range (pair number "
                          f"{v[1]!r}; |pinion angle| too large)")
    elif name == "no_progress":
        return ValueError(f"the step makes no progress at t = {v[0]!r} s (the integrator is "
                          "stuck; reduce solver.h_max or the communication step)")
    elif name == "substep_count":
        return ValueError(f"step size h = {v[0]!r} s needs {v[1]!r} substeps")
    return RuntimeError(f"rattle kernel: return code {code} ({name}) with {v}")


# ------------------------------------------------------------------ the stepper
_DoubleState = ctypes.c_double * len(STATE_FIELDS)
_DoubleResult = ctypes.c_double * len(RESULT_FIELDS)
_DoubleInputs = ctypes.c_double * len(layout.INPUT_FIELDS)
_DoubleOutputs = ctypes.c_double * len(OUTPUT_NAMES)
_DoubleErrorValues = ctypes.c_double * layout.ERROR_VALUES
_pack_inputs = struct.Struct(f"{len(layout.INPUT_FIELDS)}d").pack_into
if layout.INPUT_FIELDS != ("h", "phi_p", "w_p", "a_p", "tau_load"):
    raise ImportError("kernel_layout.INPUT_FIELDS changed; update CompiledWheelStepper.step")
# StepResult from the result array: (attribute, index, integer?) of each aggregate.
_RESULT_AGGREGATES = tuple((name, RESULT_FIELDS.index(name), name in layout.RESULT_INTEGERS)
                           for name in layout.RESULT_AGGREGATES)
_R_EVENT_COUNT = RESULT_FIELDS.index("event_count")
_R_PINION = (RESULT_FIELDS.index("pinion_phi"), RESULT_FIELDS.index("pinion_w"))
_S_PHI, _S_W = STATE_FIELDS.index("phi"), STATE_FIELDS.index("w")
# The `last` array of rk_outputs: the aggregates the outputs read, and the pinion.
_LAST_FLOATS = tuple((name, RESULT_FIELDS.index(name)) for name in
                     ("tau_wheel_mean", "tau_pinion_mean", "W_peak", "delta_peak"))
_INTEGER_INDICES = tuple(OUTPUT_NAMES.index(name) for name in INTEGER_OUTPUTS)


class CompiledWheelStepper(WheelStepperBase):
    """The wheel stepper contract (``stepper.WheelStepperBase``) on the compiled kernel.

    The start state (the static equilibrium) is solved by the shared constructor in Python;
    the kernel only steps forward from a given state.  The state lives in a C array
    (``state`` builds the :class:`WheelState` value on demand); ``last_result.events`` is
    empty (the Python stepper reports events; :attr:`last_event_count` counts them).
    ``library`` is a loaded kernel (:func:`load_kernel`), by default the one next to this
    module.
    """

    def __init__(self, params: MeshParameters, phi_p: float = 0.0, w_p: float = 0.0,
                 tau_load: float = 0.0, *, library: ctypes.CDLL | None = None):
        super().__init__(params, phi_p, w_p, tau_load, library=library)

    def _setup(self, params: MeshParameters, library: ctypes.CDLL | None = None) -> None:
        """The mesh model, the kernel library and the C arrays shared with it."""
        super()._setup(params)
        lib = library if library is not None else load_kernel()
        if lib is None:
            raise RuntimeError(
                f"the compiled rattle kernel {LIBRARY_NAME} is not available "
                f"(looked in {default_library_path().parent}); use WheelStepper")
        self._lib = lib
        self._rk_step = lib.rk_step
        self._rk_outputs = lib.rk_outputs
        self._model = (ctypes.c_double * MODEL_SIZE)(*layout.pack_model(self))
        self._state = _DoubleState()
        self._inputs = _DoubleInputs()
        self._inputs_b = memoryview(self._inputs).cast("B")
        self._result = _DoubleResult()
        self._result_mv = memoryview(self._result).cast("B").cast("d")
        self._err_values = _DoubleErrorValues()
        self._last_arr = _DoubleResult()
        self._out = _DoubleOutputs()
        self._out_mv = memoryview(self._out).cast("B").cast("d")

    def _load(self, snapshot: WheelSnapshot) -> None:
        self._state[:] = snapshot.state.as_tuple()
        self._pinion = PinionState(float(snapshot.pinion[0]), float(snapshot.pinion[1]))
        self._last = StepResult(*snapshot.result.aggregates())

    def snapshot(self) -> WheelSnapshot:
        return WheelSnapshot(self.state, self._pinion, StepResult(*self._last.aggregates()))

    @property
    def state(self) -> WheelState:
        return WheelState.from_tuple(self._state)

    @property
    def pinion(self) -> PinionState:
        return self._pinion

    @property
    def last_result(self) -> StepResult:
        return self._last

    def wheel_angle_speed(self) -> tuple[float, float]:
        a = self._state
        return a[_S_PHI], a[_S_W]

    def step(self, h: float, phi_p: float, w_p: float, a_p: float = 0.0,
             tau_load: float = 0.0) -> StepResult:
        """As :meth:`WheelStepper.step` (no events are reported)."""
        try:
            _pack_inputs(self._inputs_b, 0, h, phi_p, w_p, a_p, tau_load)
        except (struct.error, TypeError, OverflowError):
            # Not a float: raise what the Python stepper raises for it.
            _check_finite(phi_p=phi_p, w_p=w_p, a_p=a_p, tau_load=tau_load)
            check_step_size(h, self.params.h_comm_max)
            raise
        code = self._rk_step(self._model, self._state, self._inputs, self._result,
                             self._err_values)
        if code:
            raise refusal(code, self._err_values,
                          {"h": h, "phi_p": phi_p, "w_p": w_p, "a_p": a_p, "tau_load": tau_load},
                          self.params.h_comm_max)
        values = self._result_mv.tolist()
        self._pinion = PinionState(values[_R_PINION[0]], values[_R_PINION[1]])
        self._last = result = StepResult(
            **{name: (int(values[i]) if integer else values[i])
               for name, i, integer in _RESULT_AGGREGATES})
        return result

    @property
    def last_event_count(self) -> int:
        """Number of located events (onsets, releases, friction reversals, pair engagements)
        in the last step."""
        return int(self._result[_R_EVENT_COUNT])

    def output_values(self) -> list[float]:
        """The values of ``interface.MESH_OUTPUTS`` now, in their declared order (Integer
        outputs as int); cheaper than :meth:`outputs` where the names are known."""
        last, arr = self._last, self._last_arr
        for name, i in _LAST_FLOATS:
            arr[i] = getattr(last, name)
        arr[_R_PINION[0]], arr[_R_PINION[1]] = self._pinion
        code = self._rk_outputs(self._model, self._state, arr, self._out, self._err_values)
        if code:
            raise refusal(code, self._err_values)
        values = self._out_mv.tolist()
        for i in _INTEGER_INDICES:
            values[i] = int(values[i])
        return values

    def outputs(self) -> dict[str, float]:
        """The values of ``interface.MESH_OUTPUTS`` now (as :meth:`WheelStepper.outputs`)."""
        return dict(zip(OUTPUT_NAMES, self.output_values(), strict=True))


def new_stepper(params: MeshParameters, phi_p: float = 0.0, w_p: float = 0.0,
                tau_load: float = 0.0, prefer_compiled: bool = True) -> WheelStepperBase:
    """A :class:`CompiledWheelStepper` when ``prefer_compiled`` and the kernel library loads,
    else the pure-Python :class:`WheelStepper`."""
    if prefer_compiled:
        lib = load_kernel()
        if lib is not None:
            return CompiledWheelStepper(params, phi_p, w_p, tau_load, library=lib)
    return WheelStepper(params, phi_p, w_p, tau_load)


__all__ = ["LIBRARY_NAME", "CompiledWheelStepper", "default_library_path", "load_kernel",
           "new_stepper", "refusal"]
