"""Compiled twin of the wheel stepper: ``fmu_src/native/rattle_kernel.c`` loaded with ctypes.

The C kernel performs exactly the computation of :meth:`WheelStepper.step` and of
:func:`interface.mesh_outputs` -- the same floating-point operations in the same order and
the same libm calls -- so its results are identical to the pure-Python stepper's, bit for
bit, only faster (docs/kernel.md).  The Python stepper stays the reference, the fallback
when the shared library is absent, and the way to get the located contact events.

The arrays shared with the C code are declared in :mod:`kernel_layout`; a refused step is
reported with the messages of :mod:`stepper`, so no layout and no message is written twice.

Standard library only at run time; compiling the kernel needs a C compiler (gcc).
"""

from __future__ import annotations

import ctypes
import os
import struct
from pathlib import Path

from . import kernel_layout as layout
from .parameters import MeshParameters
from .stepper import (
    StepResult,
    WheelState,
    WheelStepper,
    _check_finite,
    check_step_size,
    diverged_error,
    penetration_error,
    stiffness_error,
)

#: File name of the shared library, next to this module (in an FMU: resources/drive_rattle/).
LIBRARY_NAME = "_rattle_kernel.so"
#: The C source; it includes the generated layout header next to it.
SOURCE = Path(__file__).resolve().parents[1] / "native" / "rattle_kernel.c"
#: Compiler flags: IEEE semantics without contraction (no FMA), as the bit-for-bit identity
#: with the Python stepper requires.
CFLAGS = ("-std=c99", "-O2", "-fno-fast-math", "-ffp-contract=off", "-fPIC", "-shared")

#: Names of the arrays' entries (kernel_layout declares them).
MODEL_SIZE = layout.MODEL_SIZE
STATE_FIELDS = layout.STATE_FIELDS
RESULT_FIELDS = layout.RESULT_FIELDS
OUTPUT_NAMES = layout.OUTPUT_FIELDS
INTEGER_OUTPUTS = layout.OUTPUT_INTEGERS
_ERRLEN = 1024
_CODE = {name: i for i, name in enumerate(layout.ERROR_CODES)}


# ------------------------------------------------------------------ building and loading
def default_library_path() -> Path:
    """Where :func:`load_kernel` looks by default: next to this module."""
    return Path(__file__).resolve().parent / LIBRARY_NAME


def compile_kernel(out_path, cc: str = "gcc", source=None) -> Path:
    """Compile the kernel into the shared library ``out_path`` (written atomically).

    ``source`` defaults to :data:`SOURCE`; it includes ``rattle_kernel_layout.h`` from the
    folder of :data:`SOURCE`.  Raises RuntimeError when that header is stale (it no longer
    matches :mod:`kernel_layout`), or with the compiler's output when the compiler is missing
    or fails."""
    import subprocess  # build time only

    if not layout.header_is_current():
        raise RuntimeError(
            f"{layout.HEADER} does not match drive_rattle/kernel_layout.py; regenerate it "
            "with `python build_fmu.py --update-kernel-header` (every build does it) and "
            "commit it")
    src = Path(source) if source is not None else SOURCE
    out = Path(out_path)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.{os.getpid()}.tmp")
    cmd = [cc, *CFLAGS, "-I", str(layout.HEADER.parent), "-o", str(tmp), str(src), "-lm"]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    except OSError as exc:
        raise RuntimeError(f"cannot run the C compiler {cc!r}: {exc}") from exc
    if proc.returncode != 0:
        tmp.unlink(missing_ok=True)
        raise RuntimeError(
            f"compiling the rattle kernel failed (exit {proc.returncode}): {' '.join(cmd)}\n"
            f"{proc.stdout}{proc.stderr}")
    os.replace(tmp, out)
    return out


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
    # Pointers and an int only: without argtypes ctypes passes the arrays as pointers with
    # the least per-call work (the hot path).
    lib.rk_step.argtypes, lib.rk_step.restype = None, ctypes.c_int
    lib.rk_outputs.argtypes, lib.rk_outputs.restype = None, ctypes.c_int
    _LOADED[key] = lib
    return lib


def pack_model(stepper: WheelStepper) -> list[float]:
    """The model array of ``stepper`` (:func:`kernel_layout.pack_model`)."""
    return layout.pack_model(stepper)


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
# The `last` array of rk_outputs: the aggregates the outputs read, and the pinion.
_LAST_FLOATS = tuple((name, RESULT_FIELDS.index(name)) for name in
                     ("tau_wheel_mean", "tau_pinion_mean", "W_peak", "delta_peak"))
_INTEGER_INDICES = tuple(OUTPUT_NAMES.index(name) for name in INTEGER_OUTPUTS)


class CompiledWheelStepper(WheelStepper):
    """:class:`WheelStepper` whose :meth:`step` runs the compiled kernel.

    The initial state (the static equilibrium) comes from the Python constructor.  ``state``,
    ``pinion`` and ``last`` follow each step as the Python stepper's do; ``last.events`` is
    empty (the Python stepper reports events; :attr:`last_event_count` counts them).
    :meth:`outputs` gives the values of ``interface.mesh_outputs``.

    The state lives in a C array; ``state`` builds the :class:`WheelState` on demand, and a
    state read (or assigned) through ``state`` is written back before the next step or
    outputs call, so changing it in place works as with the Python stepper.
    """

    def __init__(self, params: MeshParameters, phi_p: float = 0.0, w_p: float = 0.0,
                 tau_load: float = 0.0, *, library: ctypes.CDLL | None = None):
        self._init_buffers(library)
        super().__init__(params, phi_p, w_p, tau_load)
        self._model = (ctypes.c_double * MODEL_SIZE)(*pack_model(self))

    def _setup_from_snapshot(self, params, state, pinion, last, *, library=None) -> None:
        """:meth:`WheelStepper.from_snapshot` for the kernel: its buffers, then the state."""
        self._init_buffers(library)
        super()._setup_from_snapshot(params, state, pinion, last)
        self._model = (ctypes.c_double * MODEL_SIZE)(*pack_model(self))

    def _init_buffers(self, library: ctypes.CDLL | None) -> None:
        """The kernel library and the C arrays shared with it."""
        lib = library if library is not None else load_kernel()
        if lib is None:
            raise RuntimeError(
                f"the compiled rattle kernel {LIBRARY_NAME} is not available "
                f"(looked in {default_library_path().parent}); use WheelStepper")
        self._lib = lib
        self._rk_step = lib.rk_step
        self._rk_outputs = lib.rk_outputs
        self._state = _DoubleState()
        self._state_obj: WheelState | None = None
        self._state_dirty = False  # True: the WheelState object is the authoritative state
        self._inputs = _DoubleInputs()
        self._inputs_b = memoryview(self._inputs).cast("B")
        self._result = _DoubleResult()
        self._result_mv = memoryview(self._result).cast("B").cast("d")
        self._err_values = _DoubleErrorValues()
        self._last_arr = _DoubleResult()
        self._out = _DoubleOutputs()
        self._out_mv = memoryview(self._out).cast("B").cast("d")
        self._err = ctypes.create_string_buffer(_ERRLEN)

    # The state: a WheelState on demand, written back when it may have been changed.
    @property
    def state(self) -> WheelState:
        obj = self._state_obj
        if obj is None:
            obj = self._state_obj = WheelState.from_tuple(self._state)
        self._state_dirty = True
        return obj

    @state.setter
    def state(self, value: WheelState) -> None:
        self._state_obj = value
        self._state_dirty = True

    def _pack_state(self) -> None:
        self._state[:] = self._state_obj.as_tuple()

    def step(self, h: float, phi_p: float, w_p: float, a_p: float = 0.0,
             tau_load: float = 0.0) -> StepResult:
        """As :meth:`WheelStepper.step` (no events are reported)."""
        if self._state_dirty:
            self._pack_state()
        try:
            _pack_inputs(self._inputs_b, 0, h, phi_p, w_p, a_p, tau_load)
        except (struct.error, TypeError, OverflowError):
            # Not a float: raise what the Python stepper raises for it.
            _check_finite(phi_p=phi_p, w_p=w_p, a_p=a_p, tau_load=tau_load)
            check_step_size(h, self.params.h_comm_max)
            raise
        code = self._rk_step(self._model, self._state, self._inputs, self._result,
                             self._err_values, self._err, _ERRLEN)
        if code:
            raise self._refusal(code, h, phi_p, w_p, a_p, tau_load)
        self._state_obj = None
        self._state_dirty = False
        values = self._result_mv.tolist()
        self.pinion = (values[_R_PINION[0]], values[_R_PINION[1]])
        self.last = result = StepResult(
            **{name: (int(values[i]) if integer else values[i])
               for name, i, integer in _RESULT_AGGREGATES})
        return result

    def _refusal(self, code: int, h, phi_p, w_p, a_p, tau_load) -> Exception:
        """The exception the Python stepper raises for the kernel's return ``code``."""
        v = self._err_values
        if code == _CODE["input"]:
            _check_finite(phi_p=phi_p, w_p=w_p, a_p=a_p, tau_load=tau_load)
            check_step_size(h, self.params.h_comm_max)
        elif code == _CODE["diverged"]:
            return diverged_error(v[0], v[1])
        elif code == _CODE["penetration"]:
            return penetration_error(v[0], v[1])
        elif code == _CODE["too_stiff"]:
            return stiffness_error(v[0], v[1], v[2], v[3])
        message = self._err.value.decode("utf-8", "replace")
        if code == _CODE["value_error"]:
            return ValueError(message)
        if code == _CODE["overflow_error"]:
            return OverflowError(message)
        if code == _CODE["type_error"]:
            return TypeError(message)
        return RuntimeError(f"rattle kernel: return code {code}: {message}")

    def wheel_angle_speed(self) -> tuple[float, float]:
        """``(state.phi, state.w)`` without building the WheelState (cheap, for hot paths)."""
        if self._state_dirty:
            s = self._state_obj
            return s.phi, s.w
        a = self._state
        return a[0], a[1]

    @property
    def last_event_count(self) -> int:
        """Number of located events (onsets, releases, friction reversals) in the last step."""
        return int(self._result[_R_EVENT_COUNT])

    def output_values(self) -> list[float]:
        """The values of ``interface.MESH_OUTPUTS`` now, in their declared order (Integer
        outputs as int); cheaper than :meth:`outputs` where the names are known."""
        if self._state_dirty:
            self._pack_state()
        last, arr = self.last, self._last_arr
        for name, i in _LAST_FLOATS:
            arr[i] = getattr(last, name)
        arr[_R_PINION[0]], arr[_R_PINION[1]] = self.pinion
        code = self._rk_outputs(self._model, self._state, arr, self._out)
        if code:
            raise ValueError(
                f"the mesh outputs cannot be evaluated at pinion.phi = {self.pinion[0]!r} rad "
                f"(wheel.phi = {self._state[0]!r} rad; kernel code {code})")
        values = self._out_mv.tolist()
        for i in _INTEGER_INDICES:
            values[i] = int(values[i])
        return values

    def outputs(self) -> dict[str, float]:
        """The values of ``interface.MESH_OUTPUTS`` now (as ``interface.mesh_outputs``)."""
        return dict(zip(OUTPUT_NAMES, self.output_values(), strict=True))


def new_stepper(params: MeshParameters, phi_p: float = 0.0, w_p: float = 0.0,
                tau_load: float = 0.0, prefer_compiled: bool = True) -> WheelStepper:
    """A :class:`CompiledWheelStepper` when ``prefer_compiled`` and the kernel library loads,
    else the pure-Python :class:`WheelStepper`."""
    if prefer_compiled:
        lib = load_kernel()
        if lib is not None:
            return CompiledWheelStepper(params, phi_p, w_p, tau_load, library=lib)
    return WheelStepper(params, phi_p, w_p, tau_load)


__all__ = [
    "LIBRARY_NAME", "SOURCE", "CompiledWheelStepper", "compile_kernel", "default_library_path",
    "load_kernel", "new_stepper", "pack_model",
]
