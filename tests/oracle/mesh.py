"""Mesh loads: Hertzian normal force and flank friction of every tooth pair in contact, and
the torques they put on the wheel and the pinion (paper eq. 1-2, 10-17 as read in
docs/model.md).  The readable equations the model library's mesh.c is held against.

The rigid-body approach along the tooth normal is common to all pairs of a flank:

    x     = cos(beta_b) * (rb_p phi_p - rb_w phi_w)        (> 0 when the pinion leads)
    delta = flank * x - backlash / 2                       (penetration; < 0 is a gap)

Each pair in the zone of action touches at its own contact point with its own crown offset
g_i (geometry.py; zero on unmodified flanks), so its penetration is delta_i = delta - g_i, and
it carries the load of its load-approach law (contact.py) with the contact's dissipation
(dissipation.py: set by the onset at the last impact speed) on its own penetration rate,
Hunt-Crossley

    W_i = W(delta_i) (1 + d ddelta_i/dt),   W_i >= 0,

or viscous (the squeeze films after an impact that did not rebound, the mesh damping ratio)

    W_i = W(delta_i) + c_i ddelta_i/dt,     W_i >= 0,

W(delta) = K_i delta^(3/2) for smooth point contacts, K_i from the contact law at the pair's
radii (the crown's r_y, or eq. 6's for the paper's contact.geometry 1), Palmgren's line law
for contact.geometry 2, either in series with the asperity layer for contact.roughness 1 and
with the teeth's compliance c_i over the pair's engaged contact line for tooth.compliance 1
(compliance.py).  The dissipation acts on the pair's whole approach delta_i, the film of
eq. 11 on the flanks' own approach (delta_i less the teeth's deflection).
Torques (each gear positive in its own forward direction), with F_i the pair's friction force
and sgn_i the sign of its sliding speed:

    wheel:   tau_w = sum_i  flank W_i cos(beta_b) rb_w + sgn_i F_i rho_w,i
    pinion:  tau_p = sum_i -flank W_i cos(beta_b) rb_p - sgn_i F_i rho_p,i

The parameters are read by attribute (``drive_rattle.MeshParameters`` or any object with its
field names); nothing here calls the model library.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

from . import contact, dissipation, friction, roots
from .compliance import ToothCompliance
from .contact import ApproachLaw
from .geometry import DRIVE, LAYOUT_CROWNED, LAYOUT_LINE, LAYOUT_PAPER, HelicalPairGeometry

DISSIPATION_NONE = 0
DISSIPATION_RESTITUTION = 1
DISSIPATION_FACTOR = 2


@dataclass
class PairLoad:
    """Loads of one tooth pair (SI units), in the order of the library's per-pair rows."""

    slot: int  # pair number modulo MAX_PAIR_SLOTS
    s: float  # roll coordinate of the contact point [m]
    offset: float  # crown offset of the contact point [m]
    r_x: float  # equivalent radius across the contact line [m]
    K: float  # stiffness non-linearity of the contact [N/m^1.5]
    delta: float  # penetration of the pair, delta - offset [m]
    W: float  # normal force [N]
    F: float  # friction force magnitude [N]
    sliding_speed: float  # v_s = w_p rho_p - w_w rho_w [m/s]
    entrainment_speed: float  # u [m/s]
    h: float  # film thickness [m]
    film_parameter: float  # lambda [1]
    dry_fraction: float  # psi [1]
    delta_max_eq7: float  # energy-balance delta_max of eq. 7 at the last impact speed [m]


@dataclass
class MeshLoads:
    """Mesh state on one flank (SI units)."""

    flank: int
    delta: float  # penetration of the flank's rigid-body approach (negative: clearance) [m]
    tau_wheel: float  # torque of the mesh on the wheel [N.m]
    tau_pinion: float  # torque of the mesh on the pinion [N.m]
    W: float  # total normal force [N]
    F: float  # net friction force, positive when it drives the wheel forward [N]
    pairs: list[PairLoad] = field(default_factory=list)


class PairLaw(NamedTuple):
    """A pair in the zone of action with its load-approach law's coefficients (the order of
    the library's rm_probe_pair_laws rows, then its crown offset and rate)."""

    slot: int
    s: float  # roll coordinate of its contact point [m]
    length: float  # of its engaged contact line [m]
    r_x: float  # [m]
    r_y: float  # [m] (0 for a line)
    K: float  # of the smooth law W = K delta^p
    ka: float  # semi-major axis a = ka W^(1/3) (ellipse)
    kz: float  # area A = kz W^(2/3) (ellipse) or kz W^(1/2) (line)
    W_r: float  # asperity layer's load scale [N] (0: smooth)
    c_t: float  # the teeth's compliance over the engaged line [m/N] (0: rigid teeth)
    offset: float  # crown offset [m]
    dg: float  # its rate per roll of the face centre


def damping_factor(params) -> float:
    """Hunt-Crossley factor d [s/m] of the parameters' contact.dissipation model."""
    if params.dissipation == DISSIPATION_RESTITUTION:
        return contact.hunt_crossley_factor(params.restitution, params.restitution_speed)
    if params.dissipation == DISSIPATION_FACTOR:
        return params.damping
    return 0.0


class MeshModel:
    """Evaluates the mesh loads for given gear angles and speeds."""

    def __init__(self, params):
        self.params = params
        self.geometry = g = HelicalPairGeometry(params)
        self.E_star = contact.effective_modulus(
            params.E_pinion, params.nu_pinion, params.E_wheel, params.nu_wheel)
        if g.layout == LAYOUT_LINE:  # Palmgren's law: no elliptical contact to tabulate
            self.law = contact.ContactLaw(contact.LAW_EQUIVALENT_SPHERE, self.E_star, g.r_y,
                                        (0.0, 0.0))
        else:
            self.law = contact.ContactLaw(params.hertz_law, self.E_star, g.r_y,
                                        g.radius_ratio_range())
        self.approach = ApproachLaw(g.layout == LAYOUT_LINE, getattr(params, "roughness", 0),
                                    self.E_star, params.sigma, params.gamma,
                                    getattr(params, "asperity_density", 1e9))
        self.damping = damping_factor(params)
        self.tooth = (ToothCompliance(params, g) if getattr(params, "tooth_compliance", 0) == 1
                      else None)
        # Arms of the normal force about each axis: cos(beta_b) * base radius.
        self.arm_wheel = g.normal_factor * g.rb_wheel
        self.arm_pinion = g.normal_factor * g.rb_pinion
        # Effective mass of the wheel along the tooth normal (energy-consistent).
        self.normal_mass = params.J_wheel / self.arm_wheel**2

    # ------------------------------------------------------------------ kinematics
    def penetration(self, flank: int, phi_p: float, phi_w: float) -> float:
        """Normal penetration delta [m] of ``flank`` (negative: remaining clearance)."""
        g = self.geometry
        return flank * (self.arm_pinion * phi_p - self.arm_wheel * phi_w) - g.half_backlash

    def wheel_angle(self, flank: int, phi_p: float, delta: float) -> float:
        """The wheel angle [rad] at which ``flank`` has penetration ``delta`` against the
        pinion at ``phi_p``."""
        x = flank * (self.geometry.half_backlash + delta)
        return (self.arm_pinion * phi_p - x) / self.arm_wheel

    def approach_rate(self, flank: int, w_p: float, w_w: float) -> float:
        """d(delta)/dt [m/s] of ``flank``."""
        return flank * (self.arm_pinion * w_p - self.arm_wheel * w_w)

    def pair_rate(self, flank: int, w_p: float, dg: float) -> float:
        """Rate [m/s] at which a pair's crown offset grows (dg/ds_n times the roll speed of
        its face centre, flank rb_p w_p)."""
        return dg * (flank * self.geometry.rb_pinion * w_p)

    # ------------------------------------------------------------------ pairs
    def pair_laws(self, flank: int, phi_p: float) -> list[PairLaw]:
        """The pairs in the zone of action of ``flank`` with their laws' coefficients."""
        g, a = self.geometry, self.approach
        if g.layout == LAYOUT_CROWNED:  # the engaged lines' lengths, by slot
            lengths = {slot: length for slot, _, length in g.lines(flank, phi_p)}
            rows = [(slot, s, lengths[slot], off, dg)
                    for slot, s, off, dg in g.pairs(flank, phi_p)]
        else:
            rows = [(slot, s, length, 0.0, 0.0) for slot, s, length in g.lines(flank, phi_p)]
        out = []
        for slot, s, length, offset, dg in rows:
            r_x = g.normal_radii(s)[2]
            if g.layout == LAYOUT_LINE:
                r_y, ka = 0.0, 0.0
                K = a.line_coefficient(length) if length > 0.0 else 0.0
                kz = a.line_area_coefficient(r_x, length)
            else:
                r_y = g.radius_y_eq6(s) if g.layout == LAYOUT_PAPER else self.law.r_y
                K, _R, ka, kz = self.law.coefficients_at(r_x, r_y)
            W_r = a.asperity_scale(r_x, r_y, length) if a.rough and K > 0.0 else 0.0
            c_t = self.tooth.pair(s, length) if self.tooth is not None else 0.0
            out.append(PairLaw(slot, s, length, r_x, r_y, K, ka, kz, W_r, c_t, offset, dg))
        return out

    # ------------------------------------------------------------------ loads
    def stiffness_sum(self, flank: int, phi_p: float) -> float:
        """sum K_i over the pairs in the zone of action of ``flank`` (W = K delta^p)."""
        return sum(pl.K for pl in self.pair_laws(flank, phi_p))

    def static_force(self, flank: int, phi_p: float, delta: float) -> float:
        """Total normal force [N] of ``flank`` at penetration ``delta`` without dissipation:
        sum_i W_i(delta - g_i) over the pairs that touch."""
        total = 0.0
        for pl in self.pair_laws(flank, phi_p):
            d = delta - pl.offset
            if d > 0.0:
                total += self.approach.force(pl.K, pl.W_r, d, pl.c_t)
        return total

    def elastic_energy(self, flank: int, phi_p: float, delta: float) -> float:
        """sum_i integral_0^(delta - g_i) W_i [J] over the pairs of ``flank`` that touch."""
        return sum(self.approach.energy(pl.K, pl.W_r, delta - pl.offset, pl.c_t)
                   for pl in self.pair_laws(flank, phi_p) if delta > pl.offset)

    def torques(self, flank: int, phi_p: float, w_p: float, phi_w: float, w_w: float,
                v_impact: float) -> tuple[float, float, float]:
        """``(tau_wheel, tau_pinion, W)`` on ``flank``."""
        loads = self.loads(flank, phi_p, w_p, phi_w, w_w, v_impact)
        return loads.tau_wheel, loads.tau_pinion, loads.W

    def loads(self, flank: int, phi_p: float, w_p: float, phi_w: float, w_w: float,
              v_impact: float) -> MeshLoads:
        """Mesh loads on ``flank`` with the per-pair breakdown (every pair in the zone of
        action, the ones that do not touch with their penetration and zero loads)."""
        p = self.params
        g = self.geometry
        delta = self.penetration(flank, phi_p, phi_w)
        out = MeshLoads(flank, delta, 0.0, 0.0, 0.0, 0.0)
        if delta <= 0.0:
            return out
        delta_dot = self.approach_rate(flank, w_p, w_w)
        a = self.approach
        # the contact's dissipation as an onset on this flank at v_impact sets it
        onset = dissipation.onset(self, flank, phi_p, v_impact)
        pair_laws = self.pair_laws(flank, phi_p)
        ratio = dissipation.ratio_dampings(self, [
            a.stiffness(pl.K, pl.W_r, delta - pl.offset, pl.c_t)
            for pl in pair_laws if delta - pl.offset > 0.0])
        for pl in pair_laws:
            slot, s, offset, dg = pl.slot, pl.s, pl.offset, pl.dg
            r_x, K, ka, kz = pl.r_x, pl.K, pl.ka, pl.kz
            pen = delta - offset
            if pen <= 0.0:
                out.pairs.append(PairLoad(slot, s, offset, r_x, K, pen,
                                          0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0))
                continue
            W = a.force(K, pl.W_r, pen, pl.c_t)
            c = (dissipation.film_damping(self, r_x, pl.r_y, pl.length, pen) if onset.sticks
                 else ratio.pop(0) if ratio else 0.0)
            if onset.d > 0.0:
                W *= 1.0 + onset.d * (delta_dot - self.pair_rate(flank, w_p, dg))
                W = max(W, 0.0)  # the flanks never pull on each other
            elif c > 0.0:
                W += c * (delta_dot - self.pair_rate(flank, w_p, dg))
                W = max(W, 0.0)
            out.tau_wheel += flank * W * self.arm_wheel
            out.tau_pinion -= flank * W * self.arm_pinion
            out.W += W
            rho_p, rho_w = s, g.line_length - s
            v_s = friction.sliding_speed(w_p, rho_p, w_w, rho_w)
            u = friction.entrainment_speed(w_p, rho_p, w_w, rho_w)
            F = h = lam = psi = d_max = 0.0
            if W > 0.0:
                A_e = friction.asperity_area(W, self.E_star, p.gamma, p.sigma)
                A = a.area(kz, W)
                d_max = a.film_delta_max(v_impact, K, r_x, ka, pl.length, p.density)
                # eq. 11 on the flanks' own approach
                h = friction.film_thickness(-a.surface(K, pl.W_r, pen, pl.c_t), d_max)
                if p.film == friction.FILM_EHL:
                    h = max(h, friction.central_film_thickness(
                        u, W, r_x, pl.r_y, self.E_star, p.eta, p.alpha_pv))
                lam = h / p.sigma
                psi = friction.dry_fraction(lam)
                if p.friction_enabled:
                    U = u if p.shear_speed == 0 else v_s
                    tau_v = (friction.viscous_stress(
                        p.viscous_law, p.eta, p.alpha_pv, p.tau_limit_0, p.tau_limit_slope,
                        W / A, U, h) if psi < 1.0 else 0.0)
                    F = friction.friction_force(p.friction_form, psi, A_e, A, p.tau_s,
                                                   tau_v)
                    sgn = math.copysign(1.0, v_s) if v_s != 0.0 else 0.0
                    out.tau_wheel += sgn * F * rho_w
                    out.tau_pinion -= sgn * F * rho_p
                    out.F += sgn * F
            out.pairs.append(PairLoad(slot, s, offset, r_x, K, pen, W, F, v_s, u, h, lam, psi,
                                      d_max))
        return out

    # ------------------------------------------------------------------ static start
    def equilibrium_penetration(self, phi_p: float, w_p: float, tau_load: float) -> float:
        """The penetration [m] of the loaded flank (drive for tau_load > 0) at which the mesh
        torque on the wheel turning at the rigid ratio balances ``tau_load`` [N.m]."""
        if tau_load == 0.0:
            return 0.0
        flank = DRIVE if tau_load > 0.0 else -DRIVE
        w_w = w_p * self.geometry.ratio

        def residual(delta):
            phi_w = self.wheel_angle(flank, phi_p, delta)
            return self.loads(flank, phi_p, w_p, phi_w, w_w, 0.0).tau_wheel - tau_load

        hi = 1e-9
        while (residual(hi) > 0.0) != (flank == DRIVE):
            hi *= 2.0
        return roots.brent(residual, 0.0, hi, xtol=1e-20, rtol=roots.BRENT_RTOL)
