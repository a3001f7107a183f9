"""Hertzian point contact of the equivalent ellipsoid (paper eq. 1, 2, 7, 8, 14).

Plain functions of SI floats.  The closed-form impact solution is code here too, so that
tests hold the integrated motion against it (MODEL_NOTES section 4).
"""

from __future__ import annotations

import math
from typing import NamedTuple

#: Contact duration of an undamped Hertz impact in units of delta_max / v:
#: t_c = 2 delta_max / v * integral_0^1 (1 - x^(5/2))^(-1/2) dx = (4/5) B(2/5, 1/2) delta_max / v.
CONTACT_DURATION_FACTOR = 0.8 * math.gamma(0.4) * math.gamma(0.5) / math.gamma(0.9)


def effective_modulus(E1: float, nu1: float, E2: float, nu2: float) -> float:
    """Johnson's contact modulus E* [Pa]: 1/E* = (1-nu1^2)/E1 + (1-nu2^2)/E2.

    The paper prints 2/(...) (the "reduced modulus" E' = 2E*), which with K = 4/3 E* sqrt(R)
    would double the stiffness (MODEL_NOTES section 2).
    """
    return 1.0 / ((1.0 - nu1 * nu1) / E1 + (1.0 - nu2 * nu2) / E2)


def stiffness(E_star: float, r_x: float, r_y: float) -> float:
    """Contact stiffness non-linearity K [N/m^1.5] of eq. (2): K = 4/3 E* (r_x r_y)^(1/4)."""
    return (4.0 / 3.0) * E_star * math.sqrt(math.sqrt(r_x * r_y))


def contact_radius(W: float, r_x: float, r_y: float, E_star: float) -> float:
    """Geometric-mean semi-axis sqrt(a b) [m] of the contact ellipse under load W [N]
    (Hertz): (3 W sqrt(r_x r_y) / (4 E*))^(1/3)."""
    return (3.0 * W * math.sqrt(r_x * r_y) / (4.0 * E_star)) ** (1.0 / 3.0)


def contact_semi_axes(W: float, r_x: float, r_y: float, E_star: float) -> tuple[float, float]:
    """Semi-axes (a along y, b along x) [m] of the contact ellipse.

    sqrt(ab) from Hertz and a/b = (r_y/r_x)^(2/3) (Johnson's approximation; the paper prints
    the inverse ratio, which would make the ellipse long across the contact line).
    """
    c = contact_radius(W, r_x, r_y, E_star)
    q = (r_y / r_x) ** (1.0 / 3.0)  # sqrt(a/b)
    return c * q, c / q


def apparent_area(W: float, r_x: float, r_y: float, E_star: float) -> float:
    """Apparent Hertzian contact area A = pi a b [m^2] (eq. 14)."""
    c = contact_radius(W, r_x, r_y, E_star)
    return math.pi * c * c


def footprint_length(W: float, r_y: float, E_star: float) -> float:
    """Length l of the equivalent ellipsoid [m], eq. (8) with E*^2 (MODEL_NOTES erratum):
    l = 2 (9 W^2 r_y^2 / (16 E*^2))^(1/6) = 2 (3 W r_y / (4 E*))^(1/3)."""
    return 2.0 * (3.0 * W * r_y / (4.0 * E_star)) ** (1.0 / 3.0)


def energy_balance_delta_max(
    v: float, K: float, r_x: float, r_y: float, E_star: float, density: float
) -> float:
    """delta_max [m] of eq. (7)-(8): the equivalent ellipsoid of mass m = rho pi r_x^2 l
    striking at speed v [m/s], with 1/2 m v^2 = 2/5 K delta_max^(5/2).

    l is evaluated at the peak load W = K delta_max^(3/2), so m = C sqrt(delta_max) with
    C = 2 rho pi r_x^2 (3 K r_y / (4 E*))^(1/3), and the balance gives the closed form
    delta_max = v sqrt(5 C / (4 K)).
    """
    C = 2.0 * density * math.pi * r_x * r_x * (3.0 * K * r_y / (4.0 * E_star)) ** (1.0 / 3.0)
    return abs(v) * math.sqrt(5.0 * C / (4.0 * K))


class HertzImpact(NamedTuple):
    """Closed-form undamped Hertz impact of a mass on W = K delta^(3/2)."""

    delta_max: float  # m
    W_max: float  # N
    t_contact: float  # s
    v_rebound: float  # m/s


def hertz_impact(m: float, K: float, v: float) -> HertzImpact:
    """Closed-form impact of mass m [kg] at approach speed v [m/s] on stiffness K [N/m^1.5]:
    delta_max = (5 m v^2 / (4 K))^(2/5), W_max = K delta_max^(3/2),
    t_c = 2.9432 delta_max / v, rebound speed = v (MODEL_NOTES section 4)."""
    v = abs(v)
    d = (5.0 * m * v * v / (4.0 * K)) ** 0.4
    return HertzImpact(d, K * d**1.5, CONTACT_DURATION_FACTOR * d / v, v)
