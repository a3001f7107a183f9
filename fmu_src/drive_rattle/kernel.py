"""Compiled twin of the wheel stepper: ``fmu_src/native/rattle_kernel.c`` loaded with ctypes.

The C kernel performs exactly the computation of :meth:`WheelStepper.step` and of
:func:`interface.mesh_outputs` -- the same floating-point operations in the same order and
the same libm calls -- so its results are identical to the pure-Python stepper's, bit for
bit, only faster (docs/kernel.md).  The Python stepper stays the reference, the fallback
when the shared library is absent, and the way to get the located contact events.

Standard library only at run time; compiling the kernel needs a C compiler (gcc).
"""

from __future__ import annotations

import ctypes
import os
import struct
from pathlib import Path

from . import geometry, lubrication, roots
from .interface import MESH_OUTPUTS
from .parameters import MAX_PAIR_SLOTS, MeshParameters
from .stepper import (
    GRAZING_SAMPLES,
    MAX_PENETRATION_MODULES,
    StepResult,
    WheelState,
    WheelStepper,
    _check_finite,
    check_step_size,
)

#: File name of the shared library, next to this module (in an FMU: resources/drive_rattle/).
LIBRARY_NAME = "_rattle_kernel.so"
#: The C source.
SOURCE = Path(__file__).resolve().parents[1] / "native" / "rattle_kernel.c"
#: Compiler flags: IEEE semantics without contraction (no FMA), as the bit-for-bit identity
#: with the Python stepper requires.
CFLAGS = ("-std=c99", "-O2", "-fno-fast-math", "-ffp-contract=off", "-fPIC", "-shared")

#: Layout version of the arrays shared with the C code (RK_ABI_VERSION there).
ABI_VERSION = 1
_MAGIC = 7261747465.0

#: The model array, in the order of the C enum (M_...).
MODEL_FIELDS = (
    "magic", "abi", "size",
    "rb_pinion", "flank_phase", "base_pitch", "line_span", "s_start", "s_end",
    "line_length", "normal_factor", "half_backlash", "n_breakpoints",
    "bp0", "bp1", "bp2", "bp3",
    "E_star", "arm_wheel", "arm_pinion",
    "J_wheel", "r_y", "length_weighting", "damping", "friction_enabled", "friction_form",
    "shear_speed", "tau_s", "eta", "sigma", "gamma", "density", "h_max", "h_comm_max", "m_n",
    "pen_modules", "pen_limit", "bp_tol", "grazing_samples", "brent_max_iter", "brent_rtol",
    "release_xtol", "max_pair_slots", "lambda_boundary", "lambda_full_film", "sum_mode",
)
STATE_SIZE = 8  # WheelState.as_tuple()
#: The result array: the StepResult aggregates, the event count and the step-end pinion.
RESULT_FIELDS = (
    "tau_wheel_mean", "tau_pinion_mean", "W_peak", "delta_peak", "onsets_drive",
    "onsets_coast", "rhs_evaluations", "events", "pinion_phi", "pinion_w",
)
#: rk_outputs writes the values of MESH_OUTPUTS in their declared order.
OUTPUT_NAMES = tuple(s.name for s in MESH_OUTPUTS)
_C_OUTPUT_NAMES = (
    "wheel.tau_mesh", "pinion.tau_mesh", "wheel.phi", "wheel.w", "mesh.W", "mesh.W_peak",
    "mesh.F", "mesh.delta", "mesh.delta_peak", "mesh.v_impact", "mesh.h", "mesh.lambda",
    "mesh.psi", "mesh.n_contact", "mesh.impacts_drive", "mesh.impacts_coast",
    *(f"pair[{k}].W" for k in range(MAX_PAIR_SLOTS)),
)
INTEGER_OUTPUTS = tuple(s.name for s in MESH_OUTPUTS if s.kind == "Integer")
_ERRLEN = 1024

#: xtol of the release location: the literal in stepper._StepRun._release_time.
RELEASE_XTOL = 1e-15


def _float_sum_mode() -> int | None:
    """How this Python's sum() adds floats: 0 left to right (<= 3.11), 1 Neumaier's
    compensated sum (>= 3.12), None unknown (the kernel cannot reproduce it)."""
    s = sum([0.1] * 10)
    if s == 0.9999999999999999 and sum([1.0, 1e100, 1.0, -1e100]) == 0.0:
        return 0
    if s == 1.0 and sum([1.0, 1e100, 1.0, -1e100]) == 2.0:
        return 1
    return None


_SUM_MODE = _float_sum_mode()


def _brent_rtol() -> float:
    """The default rtol of roots.brent (the release location uses it)."""
    code = roots.brent.__code__
    names = code.co_varnames[:code.co_argcount]
    defaults = roots.brent.__defaults__
    return dict(zip(names[-len(defaults):], defaults, strict=True))["rtol"]


# ------------------------------------------------------------------ building and loading
def default_library_path() -> Path:
    """Where :func:`load_kernel` looks by default: next to this module."""
    return Path(__file__).resolve().parent / LIBRARY_NAME


def compile_kernel(out_path, cc: str = "gcc", source=None) -> Path:
    """Compile the kernel into the shared library ``out_path`` (written atomically).

    ``source`` defaults to :data:`SOURCE`.  Raises RuntimeError with the compiler's output
    when the compiler is missing or fails."""
    import subprocess  # build time only

    src = Path(source) if source is not None else SOURCE
    out = Path(out_path)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.{os.getpid()}.tmp")
    cmd = [cc, *CFLAGS, "-o", str(tmp), str(src), "-lm"]
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
    is absent, cannot be loaded, was built from a different kernel version, or this Python
    sums floats in a way the kernel does not reproduce.  Never raises for these."""
    p = Path(path) if path is not None else default_library_path()
    key = str(p.resolve()) if p.exists() else str(p)
    lib = _LOADED.get(key)
    if lib is not None:
        return lib
    if _SUM_MODE is None or not p.is_file():
        return None
    try:
        lib = ctypes.CDLL(key)
        abi = lib.rk_abi_version
        step, outputs = lib.rk_step, lib.rk_outputs
        lib.rk_step_v, lib.rk_outputs_v  # noqa: B018 (present?)
    except (OSError, AttributeError):
        return None
    abi.argtypes, abi.restype = [], ctypes.c_int
    if abi() != ABI_VERSION * 1000 + len(MODEL_FIELDS):
        return None
    dp, dbl = ctypes.POINTER(ctypes.c_double), ctypes.c_double
    step.argtypes = [dp, dp, dbl, dbl, dbl, dbl, dbl, dp, ctypes.POINTER(ctypes.c_char),
                     ctypes.c_int]
    step.restype = ctypes.c_int
    outputs.argtypes = [dp, dp, dp, dbl, dbl, dp]
    outputs.restype = ctypes.c_int
    # The array variants take pointers and an int only; without argtypes ctypes passes the
    # arrays as pointers with the least per-call work (the hot path).
    lib.rk_step_v.argtypes, lib.rk_step_v.restype = None, ctypes.c_int
    lib.rk_outputs_v.argtypes, lib.rk_outputs_v.restype = None, ctypes.c_int
    _LOADED[key] = lib
    return lib


def pack_model(stepper: WheelStepper) -> list[float]:
    """The model array of ``stepper``: its geometry, mesh constants and parameters exactly as
    the Python objects hold them (nothing is re-derived in C)."""
    g, m, p = stepper.geometry, stepper.mesh, stepper.params
    bps = tuple(g._breakpoints)
    if len(bps) > 4:
        raise ValueError(f"{len(bps)} roll breakpoints; the kernel handles at most 4")
    if _SUM_MODE is None:
        raise RuntimeError("this Python's float sum() is not reproduced by the kernel")
    values = {
        "magic": _MAGIC, "abi": float(ABI_VERSION), "size": float(len(MODEL_FIELDS)),
        "rb_pinion": g.rb_pinion, "flank_phase": g.flank_phase, "base_pitch": g.base_pitch,
        "line_span": g.line_span, "s_start": g.s_start, "s_end": g.s_end,
        "line_length": g.line_length, "normal_factor": g.normal_factor,
        "half_backlash": g.half_backlash, "n_breakpoints": float(len(bps)),
        **{f"bp{i}": (bps[i] if i < len(bps) else 0.0) for i in range(4)},
        "E_star": m.E_star, "arm_wheel": m.arm_wheel, "arm_pinion": m.arm_pinion,
        "J_wheel": p.J_wheel, "r_y": p.r_y, "length_weighting": float(p.length_weighting),
        "damping": p.damping, "friction_enabled": float(p.friction_enabled),
        "friction_form": float(p.friction_form), "shear_speed": float(p.shear_speed),
        "tau_s": p.tau_s, "eta": p.eta, "sigma": p.sigma, "gamma": p.gamma,
        "density": p.density, "h_max": p.h_max, "h_comm_max": p.h_comm_max, "m_n": p.m_n,
        "pen_modules": MAX_PENETRATION_MODULES,
        "pen_limit": MAX_PENETRATION_MODULES * p.m_n,  # as WheelStepper.step computes it
        "bp_tol": geometry.BREAKPOINT_TOLERANCE, "grazing_samples": float(GRAZING_SAMPLES),
        "brent_max_iter": float(roots.MAX_ITERATIONS), "brent_rtol": _brent_rtol(),
        "release_xtol": RELEASE_XTOL, "max_pair_slots": float(MAX_PAIR_SLOTS),
        "lambda_boundary": lubrication.LAMBDA_BOUNDARY,
        "lambda_full_film": lubrication.LAMBDA_FULL_FILM, "sum_mode": float(_SUM_MODE),
    }
    return [float(values[name]) for name in MODEL_FIELDS]


# ------------------------------------------------------------------ the stepper
_DoubleState = ctypes.c_double * STATE_SIZE
_DoubleResult = ctypes.c_double * len(RESULT_FIELDS)
_DoubleInputs = ctypes.c_double * 5
_DoubleOutputs = ctypes.c_double * len(_C_OUTPUT_NAMES)
_pack_inputs = struct.Struct("5d").pack_into  # h, phi_p, w_p, a_p, tau_load
# The aggregates of `last` and the pinion, into an array of the result layout.
_pack_last = struct.Struct("4d32x2d").pack_into
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
        lib = library if library is not None else load_kernel()
        if lib is None:
            raise RuntimeError(
                f"the compiled rattle kernel {LIBRARY_NAME} is not available "
                f"(looked in {default_library_path().parent}); use WheelStepper")
        if OUTPUT_NAMES != _C_OUTPUT_NAMES:
            raise RuntimeError("interface.MESH_OUTPUTS changed; update the kernel's outputs")
        self._lib = lib
        self._rk_step_v = lib.rk_step_v
        self._rk_outputs_v = lib.rk_outputs_v
        self._state = _DoubleState()
        self._state_obj: WheelState | None = None
        self._state_dirty = False  # True: the WheelState object is the authoritative state
        self._inputs = _DoubleInputs()
        self._inputs_b = memoryview(self._inputs).cast("B")
        self._result = _DoubleResult()
        self._result_mv = memoryview(self._result).cast("B").cast("d")
        self._last_arr = _DoubleResult()
        self._last_b = memoryview(self._last_arr).cast("B")
        self._out = _DoubleOutputs()
        self._out_mv = memoryview(self._out).cast("B").cast("d")
        self._err = ctypes.create_string_buffer(_ERRLEN)
        super().__init__(params, phi_p, w_p, tau_load)
        self._model = (ctypes.c_double * len(MODEL_FIELDS))(*pack_model(self))

    # The state: a WheelState on demand, written back when it may have been changed.
    @property
    def state(self) -> WheelState:
        obj = self._state_obj
        if obj is None:
            a = self._state
            obj = self._state_obj = WheelState(a[0], a[1], int(a[2]), a[3], a[4], a[5],
                                               int(a[6]), int(a[7]))
        self._state_dirty = True
        return obj

    @state.setter
    def state(self, value: WheelState) -> None:
        self._state_obj = value
        self._state_dirty = True

    def _pack_state(self) -> None:
        s = self._state_obj
        a = self._state
        a[0], a[1], a[2], a[3] = s.phi, s.w, s.flank, s.v_impact_drive
        a[4], a[5], a[6], a[7] = (s.v_impact_coast, s.v_impact_last, s.impacts_drive,
                                  s.impacts_coast)

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
        if self._rk_step_v(self._model, self._state, self._inputs, self._result, self._err,
                           _ERRLEN):
            raise ValueError(self._err.value.decode("utf-8", "replace"))
        self._state_obj = None
        self._state_dirty = False
        tw, tp, Wp, dp, od, oc, nrhs, _nev, pphi, pw = self._result_mv.tolist()
        self.pinion = (pphi, pw)
        self.last = result = StepResult(tw, tp, Wp, dp, int(od), int(oc), [], int(nrhs))
        return result

    def wheel_angle_speed(self) -> tuple[float, float]:
        """``(state.phi, state.w)`` without building the WheelState (cheap, for hot paths)."""
        if self._state_dirty:
            s = self._state_obj
            return s.phi, s.w
        a = self._state
        return a[0], a[1]

    @property
    def last_event_count(self) -> int:
        """Number of contact events (onsets and releases) in the last step."""
        return int(self._result[7])

    def output_values(self) -> list[float]:
        """The values of ``interface.MESH_OUTPUTS`` now, in their declared order (Integer
        outputs as int); cheaper than :meth:`outputs` where the names are known."""
        if self._state_dirty:
            self._pack_state()
        last = self.last
        phi_p, w_p = self.pinion
        _pack_last(self._last_b, 0, last.tau_wheel_mean, last.tau_pinion_mean, last.W_peak,
                   last.delta_peak, phi_p, w_p)
        if self._rk_outputs_v(self._model, self._state, self._last_arr, self._out):
            raise ValueError(
                f"the mesh outputs cannot be evaluated at pinion.phi = {phi_p!r} rad "
                f"(wheel.phi = {self._state[0]!r} rad)")
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
    if prefer_compiled and OUTPUT_NAMES == _C_OUTPUT_NAMES:
        lib = load_kernel()
        if lib is not None:
            return CompiledWheelStepper(params, phi_p, w_p, tau_load, library=lib)
    return WheelStepper(params, phi_p, w_p, tau_load)


__all__ = [
    "LIBRARY_NAME", "SOURCE", "CompiledWheelStepper", "compile_kernel", "default_library_path",
    "load_kernel", "new_stepper", "pack_model",
]
