"""The closed-form numbers of docs/model.md: values of the model's laws and derived quantities
at the default parameters (not runs of the rattle), each the text of one block of
``model_doc.BLOCKS``.  They come from the model library -- its derived quantities
(``rm_describe``), the laws at given arguments (``rm_probe_*``: the pairs' coefficients, the
loads and the approach of a pair) and static equilibria the unit solves at its start -- and
from the parameter specs (drive_rattle.parameters); a value chosen to illustrate a law (a
load, a damping) is a named constant here and the text gives the law's output at it.  Values
that are neither (published hardness, Johnson's bound) are named constants with their source.

tests/cosim/test_model_doc.py holds every block to a fresh computation and
checks the sentences around them that depend on the numbers (about two seconds in all).
"""

from __future__ import annotations

import ctypes
import math
from functools import lru_cache

from . import band, contact_laws, squeeze_impacts
from .probe_rows import loads, pair_laws

# --- section 2: the reference pair ----------------------------------------------------

def _derived() -> dict:
    from drive_rattle import MeshParameters

    return MeshParameters().derived()


def reference_pair() -> str:
    """The default (reference) pair's centre distance and contact ratios (the library's)."""
    d = _derived()
    return (f"a = {d['centre_distance'] * 1e3:.5g} mm, ε_α = {d['eps_alpha']:.4g}, "
            f"ε_β = {d['eps_beta']:.4g}, ε_γ = {d['eps_gamma']:.4g}")


def crown_radius() -> str:
    """The default crowning's r_y of the reference pair."""
    return f"{_derived()['r_y']:.3g} m for the reference pair"


def eq6_radius() -> str:
    """Eq. 6's r_y at the reference pair's pitch point, and its pitch radii."""
    d = _derived()
    return (f"r_y = **{d['r_y_eq6_pitch'] * 1e3:.4g} mm** at the pitch point (the pitch radii "
            f"{d['r_pinion'] * 1e3:.4g} and {d['r_wheel'] * 1e3:.4g} mm)")


def half_lines() -> str:
    """Half the reference pair's longest contact line, b / (2 cos beta_b)."""
    import math

    from drive_rattle import MeshParameters

    half = MeshParameters().b / (2 * math.cos(_derived()["beta_b"]))
    return f"b/(2 cos β_b) = {half * 1e3:.3g} mm"


def _pitch_pair_laws(p) -> list[list[dict]]:
    """The drive flank's pairs (``rm_probe_pair_laws``, LAW_FIELDS) at LAW_SAMPLES pinion
    angles over a base pitch, for the mesh parameters ``p``."""
    import math

    from drive_rattle.library import MESH
    from drive_rattle.units import Unit

    unit = Unit(MESH, p, initialize=False)
    try:
        return [pair_laws(unit, k * 2.0 * math.pi / p.z_pinion / LAW_SAMPLES)
                for k in range(LAW_SAMPLES)]
    finally:
        unit.close()


def line_lengths() -> str:
    """The mean total contact-line length b eps_alpha / cos(beta_b) of the reference pair and
    the range of the engaged lines' sum over a base pitch (the library's line contact)."""
    import math

    from drive_rattle import MeshParameters

    p = MeshParameters(contact_geometry=2)
    d = p.derived()
    totals = [sum(r["length"] for r in rows) for rows in _pitch_pair_laws(p)]
    mean = p.b * d["eps_alpha"] / math.cos(d["beta_b"])
    return (f"{mean * 1e3:.4g} mm for the reference pair, the sum of the engaged lines "
            f"{min(totals) * 1e3:.3g}–{max(totals) * 1e3:.3g} mm over a base pitch "
            f"({LAW_SAMPLES} angles; the mean tested)")


#: Pinion angles over a base pitch at which the pairs' laws are sampled.
LAW_SAMPLES = 200


@lru_cache(maxsize=4)
def _pair_laws(geometry: int) -> list[tuple[float, float, float, float]]:
    """(r_x, r_y, K of the exact law, K of eq. 2) of every pair in the zone on the drive flank
    at LAW_SAMPLES pinion angles over a base pitch, for ``contact.geometry`` ``geometry``."""
    from drive_rattle import MeshParameters

    exact, sphere = (_pitch_pair_laws(MeshParameters(contact_geometry=geometry, hertz_law=law))
                     for law in (0, 1))
    return [(a["r_x"], a["r_y"], a["K"], b["K"])
            for rows_a, rows_b in zip(exact, sphere, strict=True)
            for a, b in zip(rows_a, rows_b, strict=True)]


def crowned_laws() -> str:
    """The crowned default's r_y/r_x over a base pitch and how much softer eq. 2 is there."""
    rows = _pair_laws(0)
    rho = [ry / rx for rx, ry, _, _ in rows]
    soft = [exact / sphere for _, _, exact, sphere in rows]
    return (f"{min(soft):.2g}–{max(soft):.2g} times softer than the exact law (ρ = r_y/r_x = "
            f"{min(rho):.0f}–{max(rho):.0f} over a base pitch)")


def eq6_laws() -> str:
    """Eq. 6's r_y over the path of contact, r_y/r_x, and the exact law against eq. 2."""
    rows = _pair_laws(1)
    ry = [r for _, r, _, _ in rows]
    rho = [r / x for x, r, _, _ in rows]
    stiff = [(exact / sphere - 1.0) * 100 for _, _, exact, sphere in rows]
    return (f"{min(ry) * 1e3:.3g}–{max(ry) * 1e3:.3g} mm along the path of contact, r_y/r_x = "
            f"{min(rho):.2g}–{max(rho):.3g}; there the exact elliptical law "
            f"(`contact.hertz_law` = 0) is {min(stiff):.0f}–{max(stiff):.0f} % stiffer than "
            "eq. 2 (= 1)")


# --- section 3.3: the dissipation laws' constants ----------------------------------------

#: The mesh damping ratios of section 3.3 and the speed [m/s] and substep [s] of their single
#: impacts (a rigid spur pair: the Hertz law, whose restitution is then speed-independent).
ZETAS = (0.03, 0.05, 0.1)
ZETA_IMPACT = {"v": 4e-3, "h_max": 5e-7}
#: The speeds [m/s] at which the Hunt-Crossley restitution of the defaults' factor is given.
HUNT_CROSSLEY_SPEEDS = (1e-3, 20e-3, 100e-3)
#: The pinion angles over a base pitch at which the flooded critical speed is taken.
PITCH_SAMPLES = 201


_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def _sci(x: float, digits: int = 3) -> str:
    mantissa, exponent = f"{x:.{digits - 1}e}".split("e")
    return f"{mantissa}·10{str(int(exponent)).translate(_SUPERSCRIPT)}"


def dissipation_constants() -> str:
    """The squeeze-film law's area, critical speeds and film damping at the defaults, the
    Hunt-Crossley factor of the defaults' restitution, and the mesh damping ratio's
    restitutions: the model library's probes and single impacts (section 3.3)."""
    import math

    from drive_rattle import MeshParameters

    p = MeshParameters()
    pitch = 2.0 * math.pi / p.z_pinion
    angles = [k * pitch / (PITCH_SAMPLES - 1) for k in range(PITCH_SAMPLES)]
    (v_c,) = squeeze_impacts.critical_speeds({})
    (low,) = squeeze_impacts.critical_speeds(band.SQUEEZE_LOW)
    (high,) = squeeze_impacts.critical_speeds(band.SQUEEZE_HIGH)
    flooded = squeeze_impacts.critical_speeds({"squeeze_fraction": 1.0}, angles)
    d, hc = squeeze_impacts.hunt_crossley(p.restitution, p.restitution_speed,
                                          HUNT_CROSSLEY_SPEEDS)
    ratio = [squeeze_impacts.measured_restitution(
        ZETA_IMPACT["v"], dissipation=4, damping_ratio=z, beta=0.0, tooth_compliance=0,
        h_max=ZETA_IMPACT["h_max"]) for z in ZETAS]

    def band_case(c):
        return f"St_c {c['stokes_critical']:g}, φ {c['squeeze_fraction']:g}"

    return (
        "\n* squeeze-film area of the default flank at φp = 0: A = "
        f"{_sci(squeeze_impacts.squeeze_area())} m²;\n"
        f"* critical speed at φp = 0: v_c = {v_c * 1e3:.3g} mm/s at the defaults (St_c "
        f"{p.stokes_critical:g}, φ {p.squeeze_fraction:g}); over section 6.4's band from "
        f"{low * 1e3:.2g} mm/s ({band_case(band.SQUEEZE_LOW)}) to {high * 1e3:.2g} mm/s "
        f"({band_case(band.SQUEEZE_HIGH)}); flooded (φ = 1) {flooded[0] * 1e3:.3g} mm/s, "
        f"{min(flooded) * 1e3:.3g}–{max(flooded) * 1e3:.3g} mm/s over a base pitch of the "
        f"pinion's angle ({PITCH_SAMPLES} angles);\n"
        "* film damping of a sticking contact on the pair at the pitch point: "
        f"{squeeze_impacts.pitch_point_damper():.3g} N·s/m;\n"
        f"* Hunt–Crossley from e = {p.restitution:g} at {p.restitution_speed * 1e3:g} mm/s "
        f"(`contact.restitution`, `contact.restitution_speed`): d = {d:.3g} s/m, whose "
        "restitution is " + ", ".join(f"{e:.2g} at {v * 1e3:g} mm/s"
                                       for v, e in zip(HUNT_CROSSLEY_SPEEDS, hc, strict=True))
        + ";\n"
        "* mesh damping ratio, one impact of a rigid spur pair on the pinion at rest at "
        f"{ZETA_IMPACT['v'] * 1e3:g} mm/s (`solver.h_max` = {ZETA_IMPACT['h_max'] * 1e6:g} "
        "µs): e = " + ", ".join(f"{e:.3f}" for e in ratio) + " for ζ = "
        + ", ".join(f"{z:g}" for z in ZETAS) + ".\n\n"
        "(`doc_constants.dissipation_constants`: the model library's `rm_probe_squeeze`, "
        "`rm_probe_loads`, `rm_probe_damping_factor` and `rm_probe_restitution`, and single "
        "impacts stepped through it.)\n")



# --- section 6.1: the separation load ---------------------------------------------------

def separation_load() -> str:
    """The default orders, the pinion's deepest deceleration, M* and the default drag over it
    (``multistability.deepest_deceleration``, ``separation_load``)."""
    from drive_rattle import DrivelineParameters, MeshParameters

    from . import multistability as ms

    mesh, drive = MeshParameters(), DrivelineParameters()
    orders = [k for k in range(1, 5) if getattr(drive, f"amplitude_{k}")]
    a = ms.deepest_deceleration(drive)
    m_star = ms.separation_load(mesh, drive)
    return ("With the default engine orders ("
            + "/".join(f"{getattr(drive, f'order_{k}'):g}" for k in orders) + " at "
            + "/".join(f"{getattr(drive, f'amplitude_{k}'):g}" for k in orders)
            + f" rad/s²) the pinion's deepest deceleration is {a:.4g} rad/s² (tested), so a "
            f"load below\n\n    M* = I_w (z_p/z_w) · {a:.4g} rad/s² = {m_star:.4g} N·m\n\n"
            "lets the fluctuation separate the teeth quasi-statically (MODEL_NOTES §3). The "
            f"default drag is **{drive.drag / m_star:.3g} M* = {drive.drag:.4g} N·m**")


# --- section 6: the coupled system's memory ---------------------------------------------

def vehicle_mode() -> str:
    """The default driveline's vehicle mode: frequency, damping ratio and decay time
    (``DrivelineParameters().derived()``, the library's)."""
    from drive_rattle import DrivelineParameters

    d = DrivelineParameters().derived()
    return (f"f = √(k/J_v)/2π = {d['vehicle_mode_frequency']:.3g} Hz with damping ratio "
            f"ζ = (c + c_v)/(2√(k J_v)) = {d['vehicle_mode_damping_ratio'] * 100:.2g} %, so a "
            "disturbance of the vehicle's steady state decays as exp(−t/τ) with **τ = 1/(ζ ω) "
            f"= {d['vehicle_mode_decay_time']:.4g} s**")


def start_offset() -> str:
    """The wheel's mean line ahead of its coupled start angle, rho sum A_k/W_k^2 cos p_k (the
    engine orders' mean angle offset at the defaults), and the shaft torque it adds."""
    import math

    from drive_rattle import DrivelineParameters, MeshParameters

    mesh, drive = MeshParameters(), DrivelineParameters()
    ratio = mesh.z_pinion / mesh.z_wheel
    offset = ratio * sum(
        getattr(drive, f"amplitude_{k}") / (getattr(drive, f"order_{k}") * drive.w_mean) ** 2
        * math.cos(getattr(drive, f"phase_{k}")) for k in range(1, 5)
        if getattr(drive, f"amplitude_{k}"))
    torque = drive.k_shaft * offset
    return (f"ρ Σ A_k/W_k² cos p_k = {offset * 1e3:.2g} mrad ahead of its start angle (the "
            "orders' mean angle offset, ρ = z_p/z_w), so the shaft's mean torque after the "
            f"start is the drag plus k × {offset * 1e3:.2g} mrad = {torque * 1e3:+.3g} mN·m "
            f"({torque / drive.drag * 100:+.2g} %)")


# --- static equilibria under the default drag (sections 2.1, 3.1, 3.4, 3.5, 4, 5) ---------

#: Pinion angles over a base pitch at which the static equilibria are solved.
STATIC_SAMPLES = 20
#: The contact models of the text as section 3.6 runs them: the paper's ellipsoids with rigid
#: teeth as printed, the others with the default teeth; and the asperity layer.
CROWNED = contact_laws.CASES["default (crowned, exact law)"]
PAPER = contact_laws.CASES["paper, exact law"]
LINE = contact_laws.CASES["line (Palmgren)"]
ROUGH = {"roughness": 1}


def _approach(unit, law: dict, pen: float) -> tuple:
    """rm_probe_approach: (W, dW/d(pen), energy, area, the flanks' own approach)."""
    out = (ctypes.c_double * 5)()
    unit.call("rm_probe_approach", law["K"], law["W_r"], law["c_t"], law["kz"], pen, out)
    return tuple(out)


@lru_cache(maxsize=16)
def static_pairs(changes: tuple = (), v_impact: float = 0.0, load: float | None = None
                 ) -> tuple:
    """The pairs in the zone of action on the drive flank at the static equilibrium of the
    defaults changed by ``changes`` (name, value pairs; the contact's dissipation off) under
    ``load`` [N m] (the default drag) at the default engine speed and the rigid speed ratio
    (the unit's start, ``init.in_contact``), at STATIC_SAMPLES pinion angles over a base
    pitch.  Per angle a tuple of dicts: the pair's loads (``rm_probe_loads`` with an onset at
    ``v_impact``, LOAD_FIELDS; "delta" is the pair's own penetration), its law
    (``rm_probe_pair_laws``, LAW_FIELDS, under "law") and, loaded, its contact's own approach
    (the teeth's deflection not counted) and apparent area (``rm_probe_approach``: "own",
    "area")."""
    from drive_rattle import DrivelineParameters, MeshParameters, MeshUnit
    from drive_rattle.library import MESH
    from drive_rattle.units import Unit

    # the contact's dissipation off: a static state loads only the elastic law (a pair's crown
    # offset moves with the mesh, so a film damper would add a rate's force to its load)
    p = MeshParameters(**{"dissipation": 0, **dict(changes)})
    drive = DrivelineParameters()
    load = drive.drag if load is None else load
    d = p.derived()
    unit = Unit(MESH, p, initialize=False)
    found = []
    try:
        for k in range(STATIC_SAMPLES):
            phi_p = k * d["base_pitch"] / d["rb_pinion"] / STATIC_SAMPLES
            with MeshUnit(p, phi_p, drive.w_mean, load) as start:
                wheel = start.wheel()
            laws = {int(r["slot"]): r for r in pair_laws(unit, phi_p)}
            pairs = []
            for r in loads(unit, phi_p, drive.w_mean, *wheel, v_impact):
                r["law"] = laws[int(r["slot"])]
                if r["W"] > 0.0:
                    law_w, _, _, r["area"], r["own"] = _approach(unit, r["law"], r["delta"])
                    # the probe's law at the pair's penetration is its load (a check of the
                    # fields read, not of the law)
                    if abs(law_w - r["W"]) > 1e-9 * r["W"]:
                        raise RuntimeError(f"pair {r['slot']}: the law gives {law_w} N at its "
                                           f"penetration, the loads {r['W']} N")
                pairs.append(r)
            found.append(tuple(pairs))
    finally:
        unit.close()
    return tuple(found)


def loaded_pairs(changes: dict, **kw) -> list[dict]:
    return [r for rows in static_pairs(tuple(sorted(changes.items())), **kw) for r in rows
            if r["W"] > 0.0]


def _span(values, fmt: str = ".2g", scale: float = 1.0) -> str:
    lo, hi = (format(x * scale, fmt) for x in (min(values), max(values)))
    return lo if lo == hi else f"{lo}–{hi}"


#: The load [N] at which section 2.1 gives the paper's ellipse, and section 3.1 the crowned.
PAPER_ELLIPSE_LOAD = 5.0
CROWNED_ELLIPSE_LOAD = 10.0


def paper_ellipse() -> str:
    """The paper's ellipsoids' semi-major axis a = k_a W^(1/3) (the library's k_a) at the loads
    of the static equilibria under the default drag, and at PAPER_ELLIPSE_LOAD."""
    rows = loaded_pairs(PAPER)
    a = [r["law"]["ka"] * r["W"] ** (1 / 3) for r in rows]
    a_at = [r["law"]["ka"] * PAPER_ELLIPSE_LOAD ** (1 / 3) for r in rows]
    return (f"{_span(a, scale=1e3)} mm at the {_span([r['W'] for r in rows])} N a pair "
            f"carries under the default drag (static equilibria over a base pitch, rigid teeth "
            f"as printed) and {_span(a_at, scale=1e3)} mm at {PAPER_ELLIPSE_LOAD:g} N")


def crowned_ellipse() -> str:
    """The crowned default's semi-major axis a = k_a W^(1/3) at CROWNED_ELLIPSE_LOAD, over the
    pairs in the zone of action over a base pitch."""
    a = [r["law"]["ka"] * CROWNED_ELLIPSE_LOAD ** (1 / 3)
         for rows in static_pairs() for r in rows]
    return f"a = {_span(a, '.2f', 1e3)} mm at {CROWNED_ELLIPSE_LOAD:g} N"


def peak_pressure(row: dict) -> float:
    """The Hertz strip's peak pressure (4/pi) W/A [Pa] of a loaded line pair (Johnson eq. 4.45:
    p0 = 2W/(pi b L), A = 2bL the library's apparent area)."""
    return 4.0 / math.pi * row["W"] / row["area"]


def line_statics() -> str:
    """The line contact's loaded pairs under the default drag: load, engaged line, load per
    length, the Hertz strip's half-width b = A/(2L) (the library's area A = 2bL), its peak
    pressure and the contact's own approach, and the roughness over it."""
    from drive_rattle import MeshParameters

    rows = loaded_pairs(LINE)
    sigma = MeshParameters().sigma
    half = [r["area"] / (2.0 * r["law"]["length"]) for r in rows]
    lengths = [r["law"]["length"] for r in rows]
    return (f"{_span([r['W'] for r in rows])} N over {_span(lengths, scale=1e3)} mm of line:"
            f" {_span([r['W'] / r['law']['length'] for r in rows])} N/m, a Hertz "
            f"half-width of {_span(half, scale=1e6)} µm, "
            f"{_span([peak_pressure(r) for r in rows], scale=1e-6)} MPa peak "
            f"pressure and an approach of {_span([r['own'] for r in rows], scale=1e9)} nm, "
            f"{_span([sigma / r['own'] for r in rows], '.0f')} times below the flanks' "
            f"roughness")


#: Johnson's bound on the roughness parameter sigma/delta_0 below which a smooth-surface law
#: holds (K. L. Johnson, Contact Mechanics, 1985, ch. 13).
JOHNSON_ALPHA = 0.05


def largest_own_approaches(changes: dict) -> list[float]:
    """Per angle, the largest own approach of the loaded pairs (the flank's smooth approach)."""
    return [max(r["own"] for r in rows if r["W"] > 0.0)
            for rows in static_pairs(tuple(sorted(changes.items())))]


def smooth_approaches() -> str:
    """The approach a smooth law needs by Johnson's bound, and the static smooth approaches of
    the three contact models under the default drag with their sigma/delta_0."""
    from drive_rattle import DrivelineParameters, MeshParameters

    sigma = MeshParameters().sigma

    def case(changes):
        own = largest_own_approaches(changes)
        return (f"{_span(own, scale=1e9)} nm",
                f"α = {_span([sigma / x for x in own], '.3g')}")

    crowned, paper, line = (case(c) for c in (CROWNED, PAPER, LINE))
    return (f"that needs δ₀ > {sigma / JOHNSON_ALPHA * 1e6:.3g} µm. In the paper scenario the "
            f"static approaches under the default drag ({DrivelineParameters().drag:g} N·m; "
            "the largest of the loaded pairs' own approaches, the teeth's deflection not "
            f"counted, at {STATIC_SAMPLES} angles over a base pitch) are {crowned[0]} for the "
            f"crowned default ({crowned[1]}), {paper[0]} for the paper's ellipsoids "
            f"({paper[1]}) and {line[0]} under Palmgren's law ({line[1]})")


def layer_approaches() -> dict[str, list[float]]:
    """The asperity layer's approach over sigma of every loaded pair under the default drag,
    per contact model with ``contact.roughness`` = 1: the pair's own approach less the smooth
    law's approach at its load (the library's smooth law, solved for the load)."""
    from scipy.optimize import brentq

    from drive_rattle import MeshParameters
    from drive_rattle.library import MESH
    from drive_rattle.units import Unit

    found = {}
    for name, changes in (("crowned", CROWNED), ("paper", PAPER), ("line", LINE)):
        p = MeshParameters(**changes)
        smooth = Unit(MESH, p, initialize=False)
        try:
            ratios = []
            for r in loaded_pairs({**changes, **ROUGH}):
                bulk = math.exp(brentq(
                    lambda ln_x, r=r, u=smooth: _approach(u, r["law"], math.exp(ln_x))[0] - r["W"],
                    math.log(1e-15), math.log(r["own"]), xtol=1e-12))
                ratios.append((r["own"] - bulk) / p.sigma)
        finally:
            smooth.close()
        found[name] = ratios
    return found


def layer_approach() -> str:
    found = layer_approaches()
    return (f"{_span(found['crowned'])}σ for the crowned flanks and {_span(found['line'])}σ "
            f"for the line, but {_span(found['paper'])}σ for the paper's small ellipsoids")


#: The hardness of case-hardened steel [Pa] (about 700 HV) of the plasticity index.
HARDNESS = 6.9e9


def plasticity_index() -> str:
    """Greenwood and Williamson's plasticity index (E*/H) sqrt(sigma/gamma) at the defaults."""
    from drive_rattle import MeshParameters

    p = MeshParameters()
    psi = p.derived()["E_star"] / HARDNESS * math.sqrt(p.sigma / p.gamma)
    return f"{psi:.3g} for case-hardened steel (H ≈ {HARDNESS / 1e9:g} GPa)"


# --- section 4: film and friction at the static loads ------------------------------------

#: The EHL option of section 4 (Barus with limiting shear on the sliding speed).
EHL = {"film": 1, "viscous_law": 1, "shear_speed": 1}
#: The film parameter at which section 4 gives the mixed regime's friction coefficient.
MIXED_LAMBDA = 1.1
#: The impact speed [m/s] at which section 4 gives eq. 7's delta_max.
EQ7_SPEED = 4e-3


def ehl_film() -> str:
    """The EHL central film and its film parameter on the loaded pairs in steady drive under
    the default drag (the library's loads)."""
    from drive_rattle import MeshParameters

    rows = loaded_pairs(EHL)
    return (f"h_c = {_span([r['h'] for r in rows], scale=1e6)} µm, so λ = h_c/σ = "
            f"{_span([r['film_parameter'] for r in rows])} with σ = "
            f"{MeshParameters().sigma * 1e6:g} µm")


def boundary_coefficients() -> list[tuple[float, float]]:
    """Per loaded pair of the default static equilibria, (A_e tau_s/W, A tau_s/W): the boundary
    friction coefficient of the load-sharing form (the library's F/W, psi = 1) and of the
    apparent-area form at the same load (the library's apparent area A)."""
    from drive_rattle import MeshParameters

    tau_s = MeshParameters().tau_s
    return [(r["F"] / r["W"], r["area"] * tau_s / r["W"]) for r in loaded_pairs(CROWNED)]


def boundary_friction() -> str:
    """The boundary friction coefficient F/W of the default loaded pairs (psi = 1)."""
    return _span([a for a, _ in boundary_coefficients()])


def mixed_friction() -> str:
    """The boundary share psi mu of the mixed regime at MIXED_LAMBDA, psi = (3 - lambda)/2."""
    mu = [a for a, _ in boundary_coefficients()]
    return (f"friction coefficient {_span([m * (3.0 - MIXED_LAMBDA) / 2.0 for m in mu])} "
            f"instead of {_span(mu)} at λ = {MIXED_LAMBDA:g}")


def form_jump() -> str:
    """How far the printed psi = A_e/A cut the boundary term as lambda crossed 1: A/A_e, the
    apparent-area form's boundary friction over the load-sharing form's."""
    ratio = [b / a for a, b in boundary_coefficients()]
    return (f"fell {_span(ratio)}-fold as λ crossed 1 (ψ = A_e/A = "
            f"{_span([1.0 / x for x in ratio])} at the default drag's static loads)")


def form_one_coefficient() -> str:
    return f"A τ_s/W = {_span([b for _, b in boundary_coefficients()])}"


def eq7_film() -> str:
    """Eq. 7's delta_max of the default loaded pairs after an onset at EQ7_SPEED."""
    rows = loaded_pairs(CROWNED, v_impact=EQ7_SPEED)
    return (f"{_span([r['delta_max_eq7'] for r in rows], '.1g', 1e6)} µm at "
            f"{EQ7_SPEED * 1e3:g} mm/s")


# --- section 5: sliding at the pitch point; the inputs' extrapolation -----------------------

def sliding_accelerations() -> tuple[float, float]:
    """(the kinematic sliding acceleration [m/s^2] of the crowned pair whose contact point
    crosses the pitch point, at the default speed and the rigid ratio: the library's sliding
    speed differentiated along the pinion's angle; the friction's share F rho_w^2/I_w of the
    pair at the static equilibrium under the default drag)."""
    from drive_rattle import DrivelineParameters, MeshParameters
    from drive_rattle.library import MESH
    from drive_rattle.units import MeshUnit, Unit

    p, drive = MeshParameters(), DrivelineParameters()
    d = p.derived()
    phi_p = -d["base_pitch"] / (4.0 * d["rb_pinion"])  # slot 0's contact point at the pitch
    with MeshUnit(p, phi_p, drive.w_mean, drive.drag) as start:
        phi_w, w_w = start.wheel()
    unit = Unit(MESH, p, initialize=False)
    try:
        def at_pitch(phi):
            (pair,) = [r for r in loads(unit, phi, drive.w_mean, phi_w, w_w, 0.0)
                       if int(r["slot"]) == 0]
            return pair

        step = 1e-6
        rate = (at_pitch(phi_p + step)["sliding_speed"]
                - at_pitch(phi_p - step)["sliding_speed"]) / (2.0 * step) * drive.w_mean
        pair = at_pitch(phi_p)
    finally:
        unit.close()
    rho_w = d["line_length"] - pair["s"]
    return abs(rate), pair["F"] * rho_w ** 2 / p.J_wheel


def sliding_acceleration() -> str:
    kinematic, friction = sliding_accelerations()
    return (f"the contact point crossing the pitch point at {float(f'{kinematic:.2g}'):g} m/s² "
            f"of sliding acceleration against the friction's {friction:.1g} m/s² (the pair at "
            "the static equilibrium under the default drag)")


#: The communication steps [s] at which section 5 gives the inputs' extrapolation error.
EXTRAPOLATION_STEPS = (1e-4, 1e-3)


def _order_extremes(samples: int = 20000) -> tuple[float, float]:
    """(the pinion's largest jerk [rad/s^3], the largest deviation of its speed from the mean
    [rad/s]) of the default engine orders, sampled over 64 periods of the lowest order."""
    import numpy as np

    from drive_rattle import DrivelineParameters

    drive = DrivelineParameters()
    terms = drive.order_terms()
    lowest = min(k for k, _, _ in terms)
    t = np.linspace(0.0, 2.0 * math.pi / (lowest * drive.w_mean) * 64, samples * 64,
                    endpoint=False)
    jerk = sum(-A * k * drive.w_mean * np.sin(k * drive.w_mean * t + ph) for k, A, ph in terms)
    speed = sum(A / (k * drive.w_mean) * np.sin(k * drive.w_mean * t + ph)
                for k, A, ph in terms)
    return float(np.max(np.abs(jerk))), float(np.max(np.abs(speed)))


def extrapolation_error() -> str:
    """jerk H^3/12 on the tooth normal (the pinion's base arm r_bp cos beta_b) at the
    EXTRAPOLATION_STEPS, with the default orders' largest jerk."""
    from drive_rattle import MeshParameters

    jerk, _ = _order_extremes()
    arm = MeshParameters().derived()["arm_pinion"]
    fine, coarse = (jerk * h ** 3 / 12.0 * arm for h in EXTRAPOLATION_STEPS)
    step = [f"{h:.0e}".replace("e-0", "e-") for h in EXTRAPOLATION_STEPS]
    return (f"jerk·H³/12 ≈ {fine * 1e9:.2g} nm at {step[0]} s; ≈ {coarse * 1e6:.2g} µm at "
            f"{step[1]} s, the default orders' largest jerk {_sci(jerk)} rad/s³ on the pinion's "
            "base arm r_bp cos β_b")


# --- section 6: damping the soft coupling -------------------------------------------------

#: The shaft and vehicle-side dampings [N m s/rad] section 6 gives as examples.
SHAFT_DAMPING_EXAMPLE = 0.5
VEHICLE_DAMPING_EXAMPLE = 0.2


def shaft_damping() -> str:
    """The shaft damper's torque on the wheel's speed fluctuation (the orders' largest speed
    deviation times z_p/z_w) at SHAFT_DAMPING_EXAMPLE, against the default drag."""
    from drive_rattle import DrivelineParameters, MeshParameters

    mesh, drive = MeshParameters(), DrivelineParameters()
    _, speed = _order_extremes()
    dw = speed * mesh.z_pinion / mesh.z_wheel
    return (f"c × {dw:.2f} rad/s: at c = {SHAFT_DAMPING_EXAMPLE:g} N·m·s/rad, "
            f"{SHAFT_DAMPING_EXAMPLE * dw / drive.drag:.2g} times the drag")


def vehicle_damping() -> str:
    """The vehicle mode's damping ratio and decay time with VEHICLE_DAMPING_EXAMPLE on the
    vehicle side (the library's derived values), and the mean drag it adds at the wheel's
    mean speed."""
    from drive_rattle import DrivelineParameters, MeshParameters

    mesh = MeshParameters()
    drive = DrivelineParameters(drag_viscous=VEHICLE_DAMPING_EXAMPLE)
    d = drive.derived()
    w_v = drive.w_mean * mesh.z_pinion / mesh.z_wheel
    return (f"c_v = {VEHICLE_DAMPING_EXAMPLE:g} N·m·s/rad: ζ = "
            f"{d['vehicle_mode_damping_ratio']:.2g}, τ = {d['vehicle_mode_decay_time']:.2g} s) "
            f"but adds a mean drag c_v ω_v of {VEHICLE_DAMPING_EXAMPLE * w_v:.2g} N·m")


# --- further constants the text quotes (sections 3.4, 3.5, 4, 6, 7) ---------------------------

def roughness_parameter() -> str:
    """The defaults' roughness parameter eta gamma sigma."""
    from drive_rattle import MeshParameters

    p = MeshParameters()
    return f"η γ σ = {p.asperity_density * p.gamma * p.sigma:.2g}"


#: The approaches [sigma] at which section 3.5 gives the rough law's deficit.
DEFICIT_APPROACHES = (100.0, 1e3, 1e5)


def roughness_deficits() -> list[list[float]]:
    """1 - W_rough/W_smooth at DEFICIT_APPROACHES for the first pair in the zone at phi_p = 0
    (drive flank) of each contact model (the crowned, the paper's, the line), the library's
    laws with and without the asperity layer at the rough unit's coefficients."""
    from drive_rattle import MeshParameters
    from drive_rattle.library import MESH
    from drive_rattle.units import Unit

    sigma = MeshParameters().sigma
    found = []
    for changes in (CROWNED, PAPER, LINE):
        rough = Unit(MESH, MeshParameters(**{**changes, **ROUGH}), initialize=False)
        smooth = Unit(MESH, MeshParameters(**changes), initialize=False)
        try:
            law = pair_laws(rough, 0.0)[0]
            found.append([1.0 - _approach(rough, law, k * sigma)[0]
                          / _approach(smooth, {**law, "W_r": 0.0}, k * sigma)[0]
                          for k in DEFICIT_APPROACHES])
        finally:
            rough.close()
            smooth.close()
    return found


def roughness_deficit() -> str:
    from drive_rattle import MeshParameters

    sigma = MeshParameters().sigma
    at = list(zip(*roughness_deficits(), strict=True))
    near, far, farthest = DEFICIT_APPROACHES
    return (f"{_span(at[0], scale=100)} % at {near:g}σ = {near * sigma * 1e6:g} µm, "
            f"{_span(at[1], scale=100)} % at {far:g}σ, at most {max(at[2]) * 100:.1g} % at "
            f"10{str(round(math.log10(farthest))).translate(_SUPERSCRIPT)}σ")


#: The pressure [Pa] at which section 4 gives Barus' viscosity factor.
BARUS_PRESSURE = 400e6


def barus_factor() -> str:
    from drive_rattle import MeshParameters

    x = MeshParameters().alpha_pv * BARUS_PRESSURE
    return f"e^(αp) = e^{x:.3g} ≈ {float(f'{math.exp(x):.1g}'):g} at {BARUS_PRESSURE / 1e6:g} MPa"


def ehl_ellipticity() -> str:
    """Hamrock and Dowson's ellipticity k = 1.03 (r_y/r_x)^0.64 of the crowned pairs over a base
    pitch (the library's radii)."""
    k = [1.03 * (r["law"]["r_y"] / r["law"]["r_x"]) ** 0.64
         for rows in static_pairs() for r in rows]
    return f"k = {_span(k, '.0f')}"


def backlash_angle() -> str:
    """Half the backlash as the wheel's angle, j_n / (2 r_bw cos beta_b)."""
    d = _derived()
    return f"j_n/(2 r_bw cos β_b) = {d['half_backlash'] / d['arm_wheel'] * 1e3:.2g} mrad"


def order_frequencies() -> str:
    """The default engine orders' frequencies k n/60 at the default engine speed."""
    from drive_rattle import DrivelineParameters

    drive = DrivelineParameters()
    hz = [k * drive.w_mean / (2.0 * math.pi) for k, _, _ in drive.order_terms()]
    rpm = drive.w_mean * 60.0 / (2.0 * math.pi)
    return "/".join(f"{f:.1f}" for f in hz) + f" Hz at {rpm:.4g} rpm"


#: The radius ratio at which section 3.1 compares eq. 2 with the exact law (MODEL_NOTES §4's).
SPHERE_RATIO = 10.0


def sphere_at_ratio() -> str:
    """How much stiffer the exact law is than eq. 2's sphere at SPHERE_RATIO: K_exact =
    E* sqrt(R) kappa (``rm_probe_exact_ellipse``) over (4/3) E* (R r)^(1/4) = (4/3) E* sqrt(R)
    rho^(-1/4)."""
    from drive_rattle import MeshParameters
    from drive_rattle.library import MESH
    from drive_rattle.units import Unit

    out = (ctypes.c_double * 4)()
    with Unit(MESH, MeshParameters(), initialize=False) as unit:
        unit.call("rm_probe_exact_ellipse", SPHERE_RATIO, out)
    ratio = out[1] / (4.0 / 3.0 * SPHERE_RATIO ** -0.25)
    return f"at ρ = {SPHERE_RATIO:g}, {(ratio - 1.0) * 100:.0f} %"


def rigid_stiffness() -> str:
    """The rigid teeth's static mesh stiffness over ISO 6336-1's (``mesh_stiffness``): the
    point contacts at the paper scenario's load, the crowned and line contacts at the loads
    where ISO's holds."""
    from . import mesh_stiffness as ms

    light, *working = ms.LOADS[0], *(q for q in ms.LOADS if q >= ms.ISO_LOAD)
    (crowned, _), (paper, _), (line, _) = ms.CONTACTS
    ratios = ms.stiffness_ratios(loads=(light, *working), teeth=0)
    soft = [ratios[c][0] for c in (crowned, paper)]
    stiff = [x for c in (crowned, line) for x in ratios[c][1:]]
    return (f"the point contacts too soft at the rattle load ({_span(soft)} × at {light:g} N/mm, "
            "where the soft Hertz contact dominates) and the crowned and line contacts "
            f"{_span(stiff)} times too stiff at working loads ("
            + "–".join(f"{q:g}" for q in working) + " N/mm)")
