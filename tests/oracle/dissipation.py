"""The contact's dissipation set at each onset (docs/model.md section 3.3): the squeeze-film
(Stokes number) impact law, the squeeze films after an impact that does not rebound, the mesh
damping ratio.  The readable equations the model library's dissipation.c is held against.

Squeeze-film law (contact.dissipation = 3).  A lubricated impact at normal speed v loses speed
in the oil film between the flanks; with the Stokes number

    St = m_n v / (6 pi eta phi A),

m_n the wheel's normal mass, eta the viscosity, phi the starved film's fraction of the flooded
squeeze force and A the squeeze-film area of the pairs that touch first, its coefficient of
restitution is

    e = e_dry (1 - St_c / St)   for St > St_c,   0 (no rebound) otherwise

(Davis, Rager and Good 2002; Gondret, Lance and Petit 2002; Mueller and Huang 2016).  The model
realizes e exactly for each impact by the Hunt-Crossley factor that gives it at the impact's
speed; an impact whose e is below STICK_RESTITUTION does not rebound: it loses its approach
speed, and the contact goes on damped by the pairs' squeeze films at the roughness gap,
c_i = 6 pi eta phi A_i / sigma.

Mesh damping ratio (contact.dissipation = 4): c = 2 zeta sqrt(k m_n), k = sum_i 3/2 K_i
delta_i^(1/2) the contact's linearized stiffness, shared as c_i = c k_i / k.

The mesh model is read by attribute (``tests.oracle.mesh.MeshModel``); nothing here calls the
model library.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from . import contact
from .geometry import LAYOUT_LINE

DISSIPATION_SQUEEZE = 3
DISSIPATION_RATIO = 4
#: Below this restitution an impact of the squeeze-film law is taken as not rebounding.
STICK_RESTITUTION = 5e-4


def pair_area(r_x: float, r_y: float) -> float:
    """Squeeze-film area A [m^2] of a pair of radii r_x, r_y: the Reynolds squeeze film of the
    rigid paraboloidal gap h0 + x^2/(2 r_x) + y^2/(2 r_y) carries F = 6 pi eta A (-dh0/dt) / h0
    with A = 2 (r_x r_y)^(3/2) / (r_x + r_y) (R^2 for a sphere of radius R)."""
    return 2.0 * (r_x * r_y) ** 1.5 / (r_x + r_y)


def line_pair_area(params, r_x: float, length: float) -> float:
    """The squeeze-film area of a pair in line contact as the law uses it: a cylinder of radius
    R, length L at the gap h0 + x^2/(2R) carries F = 3 sqrt(2) pi eta L R^(3/2) (-dh0/dt) /
    h0^(3/2), so the approach loses 6 sqrt(2) pi eta phi L R^(3/2) / sqrt(sigma) down to the
    roughness, which is the point law's 6 pi eta phi A St_c for A = sqrt(2) L R^(3/2) /
    (St_c sqrt(sigma)) (0 for St_c = 0: no film loss)."""
    if not params.stokes_critical > 0.0:
        return 0.0
    return math.sqrt(2.0) * length * r_x**1.5 / (params.stokes_critical * math.sqrt(params.sigma))


def flank_area(model, flank: int, phi_p: float) -> float:
    """Squeeze-film area of ``flank`` at the pinion angle ``phi_p``: the pairs whose crown
    offset is within the roughness sigma of the smallest (they touch first), each with its own
    r_y (the crown's, or eq. 6's), or its line's area for the line contact."""
    line = model.geometry.layout == LAYOUT_LINE
    laws = model.pair_laws(flank, phi_p)
    first = min((pl.offset for pl in laws), default=math.inf)
    return sum(line_pair_area(model.params, pl.r_x, pl.length) if line
               else pair_area(pl.r_x, pl.r_y) for pl in laws
               if pl.offset < first + model.params.sigma)


def stokes_number(model, v: float, area: float) -> float:
    """St = m_n v / (6 pi eta phi A); infinite with no film area (no pair in the zone)."""
    p = model.params
    resistance = 6.0 * math.pi * p.eta * p.squeeze_fraction * area
    return model.normal_mass * v / resistance if resistance > 0.0 else math.inf


def restitution(params, St: float) -> float:
    """e_dry (1 - St_c / St) above the critical Stokes number, 0 at and below it."""
    if not St > params.stokes_critical:
        return 0.0
    return params.restitution_dry * (1.0 - params.stokes_critical / St)


def critical_speed(model, area: float) -> float:
    """The approach speed [m/s] at the critical Stokes number: St_c 6 pi eta phi A / m_n."""
    p = model.params
    return (p.stokes_critical * 6.0 * math.pi * p.eta * p.squeeze_fraction * area
            / model.normal_mass)


class Onset(NamedTuple):
    """What an onset sets: the law's values and the contact's dissipation."""

    area: float  # squeeze-film area [m^2]
    stokes: float  # Stokes number
    restitution: float  # the law's coefficient of restitution
    d: float  # Hunt-Crossley factor of the contact [s/m]
    sticks: bool  # the impact does not rebound (the contact's squeeze films damp it)


def onset(model, flank: int, phi_p: float, v: float) -> Onset:
    """The dissipation an onset on ``flank`` at ``phi_p`` with approach speed ``v`` sets: for
    the squeeze-film law, the Hunt-Crossley factor that realizes its e(v), or no rebound."""
    p = model.params
    if p.dissipation != DISSIPATION_SQUEEZE:
        return Onset(0.0, 0.0, 0.0, model.damping, False)
    if not v > 0.0:
        return Onset(0.0, 0.0, 0.0, 0.0, True)
    area = flank_area(model, flank, phi_p)
    St = stokes_number(model, v, area)
    e = restitution(p, St)
    if not e >= STICK_RESTITUTION:
        return Onset(area, St, e, 0.0, True)
    return Onset(area, St, e, contact.hunt_crossley_factor(e, v), False)


#: The penetration over which a pair's film damping engages, as a fraction of sigma.
FILM_ENGAGEMENT = 0.01


def film_damping(model, r_x: float, r_y: float, length: float = 0.0,
                 pen: float = math.inf) -> float:
    """Squeeze-film damping [N.s/m] of a touching pair (radii r_x, r_y; contact line
    ``length`` for the line contact; penetration ``pen``) after an impact that did not
    rebound: its film at the roughness gap, 6 pi eta phi A / sigma, or for a line 3 sqrt(2)
    pi eta phi L R^(3/2) / sigma^(3/2), engaged linearly over the pair's first
    FILM_ENGAGEMENT sigma of penetration (so that the load is continuous where a pair starts
    to carry it)."""
    p = model.params
    engaged = min(1.0, pen / (FILM_ENGAGEMENT * p.sigma))
    if model.geometry.layout == LAYOUT_LINE:
        return engaged * (3.0 * math.sqrt(2.0) * math.pi * p.eta * p.squeeze_fraction * length
                          * r_x**1.5 / p.sigma**1.5)
    return engaged * 6.0 * math.pi * p.eta * p.squeeze_fraction * pair_area(r_x, r_y) / p.sigma


def ratio_dampings(model, stiffnesses: list[float]) -> list[float]:
    """Each touching pair's share c k_i / k of the mesh damping ratio's c = 2 zeta sqrt(k m_n),
    from the pairs' linearized stiffnesses k_i = dW_i/d(delta_i) (3/2 K_i delta_i^(1/2) for
    smooth Hertz)."""
    k = sum(stiffnesses)
    if not (model.params.dissipation == DISSIPATION_RATIO and k > 0.0):
        return [0.0 for _ in stiffnesses]
    c = 2.0 * model.params.damping_ratio * math.sqrt(model.normal_mass * k)
    # the share k_i / k first: c k_i underflows below the smallest double at first contact
    # (c ~ 1e-108 N s/m, k_i ~ 1e-216 N/m at 1e-38 m of approach), the share does not
    return [c * (k_i / k) for k_i in stiffnesses]
