"""Film, regime of lubrication and flank friction (paper eq. 11-17, read as docs/model.md says):
the readable equations the model library's friction.c is held against.

Plain functions of SI floats; the oracle's mesh model (mesh.py) calls them per tooth pair.
"""

from __future__ import annotations

import math

#: Film parameter below which the contact is in boundary lubrication (psi = 1).
LAMBDA_BOUNDARY = 1.0
#: Film parameter above which the contact is in full-film lubrication (psi = 0).
LAMBDA_FULL_FILM = 3.0

FORM_LOAD_SHARING = 0
FORM_APPARENT_AREA = 1
FORM_AS_PRINTED = 2


def film_thickness(rigid_gap: float, delta_max: float) -> float:
    """Film thickness h [m] of eq. (11): the rigid gap (negative while the flanks
    interpenetrate) plus the energy-balance delta_max of eq. (7), never negative."""
    h = rigid_gap + delta_max
    return h if h > 0.0 else 0.0


FILM_EQ11 = 0
FILM_EHL = 1


def central_film_thickness(u: float, W: float, r_x: float, r_y: float, E_star: float,
                           eta: float, alpha: float) -> float:
    """Central film thickness h_c [m] of an isothermal, fully flooded elastohydrodynamic point
    contact (Hamrock and Dowson 1977):

        h_c / r_x = 2.69 U^0.67 G^0.53 W^-0.067 (1 - 0.61 exp(-0.73 k)),

    U = eta |u| / (E' r_x), G = alpha E', W = load / (E' r_x^2), k = 1.03 (r_y / r_x)^0.64 and
    E' = 2 E*, r_x the radius in the rolling direction."""
    E2 = 2.0 * E_star
    U = eta * abs(u) / (E2 * r_x)
    G = alpha * E2
    Wd = W / (E2 * r_x * r_x)
    k = 1.03 * (r_y / r_x) ** 0.64
    return r_x * 2.69 * U**0.67 * G**0.53 * Wd**-0.067 * (1.0 - 0.61 * math.exp(-0.73 * k))


def asperity_area(W: float, E_star: float, gamma: float, sigma: float) -> float:
    """Real contact area A_e [m^2] of elastic asperity tips, eq. (13):
    A_e = 3.2 W / E* sqrt(gamma / sigma)."""
    return 3.2 * W / E_star * math.sqrt(gamma / sigma)


def dry_fraction(lam: float) -> float:
    """Proportion psi of the load carried by asperity (boundary) contact, eq. (12)-(15) read
    continuously: 1 for lambda <= 1 (boundary), 0 for lambda >= 3 (full film), and linear in
    between, psi = (3 - lambda) / 2.

    The paper's psi = A_e/A in the mixed regime jumps at both limits (to A_e/A ~ 0.03 at
    lambda = 1+, which cut the friction 38-fold, and from A_e/A to 0 at lambda = 3); the linear
    share joins the boundary and full-film readings of every friction form continuously
    (docs/model.md section 4)."""
    if lam <= LAMBDA_BOUNDARY:
        return 1.0
    if lam >= LAMBDA_FULL_FILM:
        return 0.0
    return (LAMBDA_FULL_FILM - lam) / (LAMBDA_FULL_FILM - LAMBDA_BOUNDARY)


VISCOUS_NEWTONIAN = 0
VISCOUS_BARUS_LIMITED = 1


def viscous_stress(law: int, eta: float, alpha: float, tau_limit_0: float,
                   tau_limit_slope: float, p: float, U: float, h: float) -> float:
    """Shear stress [Pa] of the film in the viscous term of eq. (12), at the pair's mean Hertz
    pressure ``p`` [Pa], shear speed ``U`` and film thickness ``h > 0``:

    law 0 (the paper): Newtonian and isoviscous, eta |U| / h;
    law 1: Barus' (1893) piezoviscosity eta(p) = eta exp(alpha p), bounded by the limiting
    shear stress tau_L = tau_L0 + gamma_L p as Bair and Winer (1979) write it,
    tau = tau_L (1 - exp(-eta(p) |U| / (h tau_L))).
    """
    if law == VISCOUS_NEWTONIAN:
        return eta * abs(U) / h
    if law != VISCOUS_BARUS_LIMITED:
        raise ValueError(f"viscous law {law!r} unknown; allowed: {VISCOUS_NEWTONIAN}, "
                         f"{VISCOUS_BARUS_LIMITED}")
    if U == 0.0:
        return 0.0
    tau_L = tau_limit_0 + tau_limit_slope * p
    ratio = eta * abs(U) / (h * tau_L)
    if ratio == 0.0:
        return 0.0
    # eta exp(alpha p) |U| / (h tau_L) through its logarithm: exp(alpha p) may overflow
    x = math.exp(min(alpha * p + math.log(ratio), 709.0))
    return -tau_L * math.expm1(-x)


def friction_force(
    form: int, psi: float, A_e: float, A: float, tau_s: float, tau_viscous: float
) -> float:
    """Magnitude of the flank friction force [N], eq. (12) in the chosen reading, with
    ``tau_viscous`` the film's shear stress (:func:`viscous_stress`; 0 where psi = 1, the
    viscous term being evaluated only where psi < 1, which implies h > sigma > 0).

    form 0 (load sharing, default): psi A_e tau_s + (1 - psi) A tau_viscous -- boundary shear on
    the real asperity area of eq. (13), viscous shear of the film on the apparent area;
    form 1 (apparent area): A (psi tau_s + (1 - psi) tau_viscous);
    form 2 (as printed): A_e (psi tau_s + (1 - psi) tau_viscous).
    """
    viscous = tau_viscous
    if form == FORM_LOAD_SHARING:
        return psi * A_e * tau_s + (1.0 - psi) * A * viscous
    if form == FORM_APPARENT_AREA:
        return A * (psi * tau_s + (1.0 - psi) * viscous)
    if form == FORM_AS_PRINTED:
        return A_e * (psi * tau_s + (1.0 - psi) * viscous)
    raise unknown_form_error(form)


def unknown_form_error(form: int) -> ValueError:
    """The refusal of a friction form that is not one of the FORM_ codes."""
    return ValueError(f"friction form {form!r} unknown; allowed: {FORM_LOAD_SHARING}, "
                      f"{FORM_APPARENT_AREA}, {FORM_AS_PRINTED}")


def entrainment_speed(w_p: float, rho_p: float, w_w: float, rho_w: float) -> float:
    """Entraining (mean rolling) speed u [m/s] of the two flanks at the contact, transverse
    plane: u = (w_p rho_p + w_w rho_w) / 2 (replaces eq. 16-17, see docs/model.md)."""
    return 0.5 * (w_p * rho_p + w_w * rho_w)


def sliding_speed(w_p: float, rho_p: float, w_w: float, rho_w: float) -> float:
    """Sliding speed v_s = w_p rho_p - w_w rho_w [m/s] of the pinion flank relative to the
    wheel flank, along the profile tangent; it changes sign at the pitch point."""
    return w_p * rho_p - w_w * rho_w
