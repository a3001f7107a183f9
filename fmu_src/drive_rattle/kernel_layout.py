"""The data the compiled kernel shares with Python, declared once.

``fmu_src/native/rattle_kernel.c`` reads its model array, state, result and output arrays and
its error codes by the names generated here into ``fmu_src/native/rattle_kernel_layout.h``.
Each model field is declared with where its value comes from (the Python objects and module
constants the stepper reads), so :func:`pack_model` is the only place that maps Python to the
array, and nothing is written twice:

* the state is :class:`stepper.WheelState`'s fields, the result :class:`stepper.StepResult`'s
  aggregates, the outputs ``interface.MESH_OUTPUTS``, in their declared order;
* the header also carries the codes both sides use (flanks, Hertz laws, friction forms);
* :data:`LAYOUT_HASH` is a hash of the whole generated header (names, order, sizes, codes),
  compiled into the library and checked when it is loaded and on every call, so a library
  built from another layout is never used, even when only two names swapped places.

The build (``drive_rattle_build.kernel``) writes the header before it compiles the kernel
(``drive-rattle-build --update-kernel-header`` only that), refuses to compile against a stale
header, and ``tests/core/test_kernel.py`` fails while the committed one is stale.  Standard
library only (it ships in the FMU with ``kernel.py``: ``pack_model`` and ``LAYOUT_HASH`` are
used at run time).
"""

from __future__ import annotations

import hashlib
import re
from collections.abc import Callable
from dataclasses import dataclass, fields

from . import geometry, hertz, lubrication, roots, stepper
from .geometry import MAX_PAIR_SLOTS
from .interface import MESH_OUTPUTS

#: Bumped when the meaning of the arrays or the functions' arguments change without a change
#: of the names (3: refusals as codes and numbers only, no message text).
ABI_VERSION = 3
#: First entry of the model array ("rattle" in ASCII digits), against stray arrays.
MAGIC = 7261747465.0
#: Largest number of roll breakpoints per base pitch (geometry._roll_breakpoints has 4).
MAX_BREAKPOINTS = 4
#: Extra values of a refused step (the numbers its message quotes, or a library call's code
#: and arguments).
ERROR_VALUES = 4
#: The kernel's own limits (the Python stepper has none of them; kernel.py words the
#: refusals): tooth pairs held per roll coordinate, the largest |pair number| (pair numbers are
#: exact integers in doubles below 2**53), main-loop iterations without progress in time
#: before a step is refused (the Python loop would not end), and the largest number of grid
#: substeps (an int64).
MAX_PAIRS = 16
PAIR_NUMBER_LIMIT = 2.0**52
STALL_LIMIT = 1_000_000
MAX_GRID_SUBSTEPS = 9.2e18


@dataclass(frozen=True)
class ModelField:
    """One entry (``count`` > 1: a block of entries) of the model array, with its value taken
    from the stepper: ``value(stepper)`` is a float, or for a block a sequence of at most
    ``count`` floats (padded with 0)."""

    name: str
    value: Callable
    description: str
    count: int = 1


def _law(s):
    return s.mesh.law


def _padded(values, count, name):
    values = [float(v) for v in values]
    if len(values) > count:
        raise ValueError(f"{len(values)} values of {name!r}; the kernel holds at most {count}")
    return values + [0.0] * (count - len(values))


def _breakpoints(s):
    return s.geometry._breakpoints


def _chebyshev_terms(s):
    law = _law(s)
    n = len(law.kappa)
    if not len(law.alpha) == len(law.zeta) == n:
        raise ValueError("the Chebyshev series of the contact law differ in length")
    return n


_T = hertz.MAX_CHEBYSHEV_TERMS

MODEL_FIELDS: tuple[ModelField, ...] = (
    ModelField("magic", lambda s: MAGIC, "kernel_layout.MAGIC"),
    ModelField("layout_hash", lambda s: float(LAYOUT_HASH), "kernel_layout.LAYOUT_HASH"),
    ModelField("size", lambda s: float(MODEL_SIZE), "number of entries of this array"),
    # geometry.HelicalPairGeometry
    ModelField("rb_pinion", lambda s: s.geometry.rb_pinion, "base radius of the pinion [m]"),
    ModelField("flank_phase", lambda s: s.geometry.flank_phase, "roll of pair 0 at phi_p = 0 [m]"),
    ModelField("base_pitch", lambda s: s.geometry.base_pitch, "transverse base pitch [m]"),
    ModelField("line_span", lambda s: s.geometry.line_span, "roll span of a contact line [m]"),
    ModelField("s_start", lambda s: s.geometry.s_start, "start of the path of contact [m]"),
    ModelField("s_end", lambda s: s.geometry.s_end, "end of the path of contact [m]"),
    ModelField("line_length", lambda s: s.geometry.line_length, "line of action length [m]"),
    ModelField("normal_factor", lambda s: s.geometry.normal_factor, "cos(beta_b)"),
    ModelField("half_backlash", lambda s: s.geometry.half_backlash, "half the backlash [m]"),
    ModelField("crown_factor", lambda s: s.geometry.crown_factor, "crown drop per roll^2 [1/m]"),
    ModelField("n_breakpoints", lambda s: float(len(_breakpoints(s))),
               "number of roll breakpoints"),
    ModelField("breakpoints", _breakpoints, "roll breakpoints mod base pitch [m]",
               MAX_BREAKPOINTS),
    ModelField("cos_alpha_t", lambda s: s.geometry.cos_alpha_t, "cos(alpha_t)"),
    ModelField("sin_alpha_t", lambda s: s.geometry.sin_alpha_t, "sin(alpha_t)"),
    ModelField("sin_beta_b", lambda s: s.geometry.sin_beta_b, "sin(beta_b)"),
    # mesh.MeshModel
    ModelField("E_star", lambda s: s.mesh.E_star, "contact modulus E* [Pa]"),
    ModelField("arm_wheel", lambda s: s.mesh.arm_wheel, "cos(beta_b) rb_wheel [m]"),
    ModelField("arm_pinion", lambda s: s.mesh.arm_pinion, "cos(beta_b) rb_pinion [m]"),
    ModelField("normal_mass", lambda s: s.mesh.normal_mass, "wheel mass on the normal [kg]"),
    ModelField("damping", lambda s: s.mesh.damping, "Hunt-Crossley factor d [s/m]"),
    # hertz.ContactLaw
    ModelField("law", lambda s: float(_law(s).law), "contact law code (RK_LAW_...)"),
    ModelField("law_E_star", lambda s: _law(s).E_star, "the law's E* [Pa]"),
    ModelField("r_y", lambda s: _law(s).r_y, "flank radius along the contact line [m]"),
    ModelField("t_mid", lambda s: _law(s).t_mid, "centre of the ln(R/r) range"),
    ModelField("t_scale", lambda s: _law(s).t_scale, "1 / half-width of the ln(R/r) range"),
    ModelField("chebyshev_terms", lambda s: float(_chebyshev_terms(s)),
               "number of Chebyshev coefficients per series (0: equivalent sphere)"),
    ModelField("kappa", lambda s: _law(s).kappa, "Chebyshev series of kappa(ln rho)", _T),
    ModelField("alpha", lambda s: _law(s).alpha, "Chebyshev series of alpha(ln rho)", _T),
    ModelField("zeta", lambda s: _law(s).zeta, "Chebyshev series of zeta(ln rho)", _T),
    # parameters.MeshParameters
    ModelField("J_wheel", lambda s: s.params.J_wheel, "wheel.J [kg.m2]"),
    ModelField("friction_enabled", lambda s: float(s.params.friction_enabled),
               "friction.enabled"),
    ModelField("friction_form", lambda s: float(s.params.friction_form), "friction.form"),
    ModelField("shear_speed", lambda s: float(s.params.shear_speed), "friction.shear_speed"),
    ModelField("tau_s", lambda s: s.params.tau_s, "friction.tau_s [Pa]"),
    ModelField("eta", lambda s: s.params.eta, "lubricant.eta [Pa.s]"),
    ModelField("sigma", lambda s: s.params.sigma, "surface.sigma [m]"),
    ModelField("gamma", lambda s: s.params.gamma, "surface.gamma [m]"),
    ModelField("density", lambda s: s.params.density, "material.rho [kg/m3]"),
    ModelField("h_max", lambda s: s.params.h_max, "solver.h_max [s]"),
    ModelField("h_comm_max", lambda s: s.params.h_comm_max, "solver.h_comm_max [s]"),
    ModelField("rattle_time", lambda s: s.params.rattle_time, "rattle.time_constant [s]"),
    # module constants
    ModelField("penetration_limit",
               lambda s: stepper.MAX_PENETRATION_MODULES * s.params.m_n,
               "MAX_PENETRATION_MODULES * gear.m_n, as WheelStepper.step computes it [m]"),
    ModelField("breakpoint_tolerance", lambda s: geometry.BREAKPOINT_TOLERANCE,
               "geometry.BREAKPOINT_TOLERANCE [m]"),
    ModelField("grazing_samples", lambda s: float(stepper.GRAZING_SAMPLES),
               "stepper.GRAZING_SAMPLES"),
    ModelField("brent_max_iterations", lambda s: float(roots.MAX_ITERATIONS),
               "roots.MAX_ITERATIONS"),
    ModelField("brent_rtol", lambda s: stepper.EVENT_RTOL, "stepper.EVENT_RTOL"),
    ModelField("event_xtol", lambda s: stepper.EVENT_XTOL, "stepper.EVENT_XTOL [s]"),
    ModelField("engagement_min_fraction", lambda s: stepper.ENGAGEMENT_MIN_FRACTION,
               "stepper.ENGAGEMENT_MIN_FRACTION"),
    ModelField("lambda_boundary", lambda s: lubrication.LAMBDA_BOUNDARY,
               "lubrication.LAMBDA_BOUNDARY"),
    ModelField("lambda_full_film", lambda s: lubrication.LAMBDA_FULL_FILM,
               "lubrication.LAMBDA_FULL_FILM"),
    ModelField("contact_rate_safety", lambda s: stepper.CONTACT_RATE_SAFETY,
               "stepper.CONTACT_RATE_SAFETY"),
    ModelField("max_contact_substeps", lambda s: float(stepper.MAX_CONTACT_SUBSTEPS),
               "stepper.MAX_CONTACT_SUBSTEPS"),
    ModelField("grid_slack", lambda s: stepper.GRID_SLACK, "stepper.GRID_SLACK"),
)
MODEL_SIZE = sum(f.count for f in MODEL_FIELDS)

#: The state array: WheelState's fields in order (``int`` fields are stored exactly).
STATE_FIELDS = tuple(f.name for f in fields(stepper.WheelState))
STATE_INTEGERS = tuple(f.name for f in fields(stepper.WheelState) if f.type == "int")
#: The result array: StepResult's aggregates and cost counters, the number of located events
#: (onsets, releases, reversals, pair engagements) and the pinion at the step end
#: (``pinion``).
RESULT_AGGREGATES = tuple(f.name for f in fields(stepper.StepResult) if f.name != "events")
RESULT_INTEGERS = tuple(f.name for f in fields(stepper.StepResult)
                        if f.name != "events" and f.type == "int")
RESULT_FIELDS = (*RESULT_AGGREGATES, "event_count", "pinion_phi", "pinion_w")
#: The output array: the values of interface.MESH_OUTPUTS in declared order.
OUTPUT_FIELDS = tuple(s.name for s in MESH_OUTPUTS)
OUTPUT_INTEGERS = tuple(s.name for s in MESH_OUTPUTS if s.fmi_type == "Integer")
#: The step's inputs, as rk_step reads them.
INPUT_FIELDS = ("h", "phi_p", "w_p", "a_p", "tau_load")

#: Return codes of rk_step and rk_outputs, with what the error values hold; kernel.py raises
#: the exception Python raises (kernel.refusal).  "layout": a model array of another layout;
#: "model_values": counts beyond the kernel's arrays (breakpoints, Chebyshev terms, law);
#: "input": a non-finite input or an invalid step size (Python raises it from the same
#: checks); "diverged" (phi, w), "penetration" (depth, limit), "too_stiff" (fastest, k, c,
#: mass): the stepper's refusals; "library" (call, x, y): a library call that raises in Python
#: (``LIBRARY_CALLS``); "no_bracket" (a, fa, b, fb): Brent's method without a bracket;
#: "friction_form" (form); the kernel's own limits: "too_many_pairs" (MAX_PAIRS),
#: "pair_number_range" (u, n), "no_progress" (t), "substep_count" (h, n).
ERROR_CODES = ("ok", "layout", "model_values", "input", "diverged", "penetration",
               "too_stiff", "library", "no_bracket", "friction_form", "too_many_pairs",
               "pair_number_range", "no_progress", "substep_count")
#: The library calls the kernel reports by code: pow (x ** y), math.sqrt, math.log,
#: math.exp, math.floor, math.ceil, int(), and ``None > 0.0`` (Brent's method meeting the
#: None of a pair that left the zone).
LIBRARY_CALLS = ("pow", "sqrt", "log", "exp", "floor", "ceil", "int", "none_gt")

#: Codes both sides use, as C macros.
CODES = {
    "RK_DRIVE": geometry.DRIVE,
    "RK_COAST": geometry.COAST,
    "RK_LAW_EXACT": hertz.LAW_EXACT,
    "RK_LAW_EQUIVALENT_SPHERE": hertz.LAW_EQUIVALENT_SPHERE,
    "RK_FORM_LOAD_SHARING": lubrication.FORM_LOAD_SHARING,
    "RK_FORM_APPARENT_AREA": lubrication.FORM_APPARENT_AREA,
    "RK_FORM_AS_PRINTED": lubrication.FORM_AS_PRINTED,
    "RK_N_SLOTS": MAX_PAIR_SLOTS,
    "RK_MAX_CHEBYSHEV_TERMS": hertz.MAX_CHEBYSHEV_TERMS,
    "RK_MAX_BREAKPOINTS": MAX_BREAKPOINTS,
    "RK_ERROR_VALUES": ERROR_VALUES,
    "RK_MAX_PAIRS": MAX_PAIRS,
    "RK_PAIR_NUMBER_LIMIT": PAIR_NUMBER_LIMIT,
    "RK_STALL_LIMIT": STALL_LIMIT,
    "RK_MAX_GRID_SUBSTEPS": MAX_GRID_SUBSTEPS,
    "RK_ABI_VERSION": ABI_VERSION,
}


def c_name(name: str) -> str:
    """C identifier part for a Python/FMI name: 'pair[3].W' -> 'PAIR_3_W'."""
    return re.sub(r"[^0-9A-Za-z]+", "_", name).strip("_").upper()


def _enum(prefix: str, names, comments=None) -> list[str]:
    lines = [f"enum {{ /* {prefix}: see kernel_layout.py */"]
    for i, name in enumerate(names):
        note = f" /* {comments[i]} */" if comments else ""
        lines.append(f"    {prefix}{c_name(name)} = {i},{note}")
    lines.append(f"    {prefix}COUNT = {len(names)}")
    lines.append("};")
    return lines


def _body() -> str:
    lines = ["/* model array (kernel.pack_model) */", "enum {"]
    index = 0
    for f in MODEL_FIELDS:
        lines.append(f"    M_{c_name(f.name)} = {index}, /* {f.description} */")
        index += f.count
    lines.append(f"    M_COUNT = {index}")
    lines.append("};")
    for f in MODEL_FIELDS:
        if f.count > 1:
            lines.append(f"#define M_{c_name(f.name)}_LENGTH {f.count}")
    lines.append("")
    lines.append("/* state array: stepper.WheelState */")
    lines += _enum("S_", STATE_FIELDS)
    lines.append("")
    lines.append("/* result array: stepper.StepResult aggregates, event count, pinion */")
    lines += _enum("R_", RESULT_FIELDS)
    lines.append("")
    lines.append("/* output array: interface.MESH_OUTPUTS */")
    lines += _enum("O_", OUTPUT_FIELDS)
    lines.append("")
    lines.append("/* input array of rk_step */")
    lines += _enum("I_", INPUT_FIELDS)
    lines.append("")
    lines.append("/* return codes of rk_step and rk_outputs */")
    lines += _enum("RK_ERR_", ERROR_CODES)
    lines.append("")
    lines.append("/* library calls of RK_ERR_LIBRARY */")
    lines += _enum("RK_CALL_", LIBRARY_CALLS)
    lines.append("")
    for name, value in CODES.items():
        lines.append(f"#define {name} ({value})")
    lines.append(f"#define RK_MAGIC {MAGIC!r}")
    return "\n".join(lines) + "\n"


def layout_hash(body: str) -> int:
    """48-bit hash of a layout's header body (exact as a double in the model array)."""
    return int(hashlib.sha256(body.encode()).hexdigest()[:12], 16)


_BODY = _body()
#: Hash of the generated layout: names, order, sizes and codes.
LAYOUT_HASH = layout_hash(_BODY)


def render_header() -> str:
    """The text of ``rattle_kernel_layout.h``."""
    return (
        "/* GENERATED by drive_rattle/kernel_layout.py -- do not edit.\n"
        " * Regenerate: drive-rattle-build --update-kernel-header (every build does it). */\n"
        "#ifndef RATTLE_KERNEL_LAYOUT_H\n#define RATTLE_KERNEL_LAYOUT_H\n\n"
        f"{_BODY}\n"
        f"#define RK_LAYOUT_HASH {LAYOUT_HASH}ULL\n\n"
        "#endif\n")


def pack_model(stepper_) -> list[float]:
    """The model array of a WheelStepper: each field's value, as the Python objects hold it."""
    out: list[float] = []
    for f in MODEL_FIELDS:
        value = f.value(stepper_)
        if f.count == 1:
            out.append(float(value))
        else:
            out.extend(_padded(value, f.count, f.name))
    return out

