"""Mesh loads: Hertzian normal force and flank friction of every tooth pair in contact, and
the torques they put on the wheel and the pinion (paper eq. 1-2, 10-17 as read in
docs/model.md).

The rigid-body approach along the tooth normal is common to all pairs of a flank:

    x     = cos(beta_b) * (rb_p phi_p - rb_w phi_w)        (> 0 when the pinion leads)
    delta = flank * x - backlash / 2                       (penetration; < 0 is a gap)

Each pair in the zone of action touches at its own contact point with its own crown offset
g_i (geometry.py), so its penetration is delta_i = delta - g_i, and it carries the Hertz force
with Hunt-Crossley dissipation on its own penetration rate,

    W_i = K_i delta_i^(3/2) (1 + d ddelta_i/dt),   W_i >= 0,

K_i from the contact law at the pair's radii.  Torques (each gear positive in its own forward
direction), with F_i the pair's friction force and sgn_i the sign of its sliding speed:

    wheel:   tau_w = sum_i  flank W_i cos(beta_b) rb_w + sgn_i F_i rho_w,i
    pinion:  tau_p = sum_i -flank W_i cos(beta_b) rb_p - sgn_i F_i rho_p,i
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from . import hertz, lubrication
from .geometry import MAX_PAIR_SLOTS
from .parameters import MeshParameters

DISSIPATION_NONE = 0
DISSIPATION_RESTITUTION = 1
DISSIPATION_FACTOR = 2


@dataclass
class PairLoad:
    """Loads of one tooth pair (SI units)."""

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


def damping_factor(params: MeshParameters) -> float:
    """Hunt-Crossley factor d [s/m] of the parameters' contact.dissipation model."""
    if params.dissipation == DISSIPATION_RESTITUTION:
        return hertz.hunt_crossley_factor(params.restitution, params.restitution_speed)
    if params.dissipation == DISSIPATION_FACTOR:
        return params.damping
    return 0.0


class MeshModel:
    """Evaluates the mesh loads for given gear angles and speeds."""

    def __init__(self, params: MeshParameters):
        self.params = params
        self.geometry = g = params.geometry
        self.E_star = hertz.effective_modulus(
            params.E_pinion, params.nu_pinion, params.E_wheel, params.nu_wheel)
        self.law = hertz.ContactLaw(params.hertz_law, self.E_star, g.r_y,
                                    g.radius_ratio_range())
        self.damping = damping_factor(params)
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

    def approach_rate(self, flank: int, w_p: float, w_w: float) -> float:
        """d(delta)/dt [m/s] of ``flank``."""
        return flank * (self.arm_pinion * w_p - self.arm_wheel * w_w)

    def pair_rate(self, flank: int, w_p: float, dg: float) -> float:
        """Rate [m/s] at which a pair's crown offset grows (dg/ds_n times the roll speed of
        its face centre, flank rb_p w_p)."""
        return dg * (flank * self.geometry.rb_pinion * w_p)

    def sliding_speed(self, s: float, w_p: float, w_w: float) -> float:
        """Sliding speed v_s [m/s] at the contact point with roll coordinate s."""
        return lubrication.sliding_speed(w_p, s, w_w, self.geometry.line_length - s)

    # ------------------------------------------------------------------ loads
    def torques(self, flank: int, phi_p: float, w_p: float, phi_w: float, w_w: float,
                v_impact: float, signs=None) -> tuple[float, float, float]:
        """``(tau_wheel, tau_pinion, W)`` on ``flank``: the integrator's right-hand side.

        ``signs`` (optional, per pair slot) fixes the direction of each pair's friction for a
        substep between located reversals; without it the sign of the sliding speed is used."""
        loads = self._loads(flank, phi_p, w_p, phi_w, w_w, v_impact, signs, False)
        return loads.tau_wheel, loads.tau_pinion, loads.W

    def loads(self, flank: int, phi_p: float, w_p: float, phi_w: float, w_w: float,
              v_impact: float, signs=None) -> MeshLoads:
        """Mesh loads on ``flank`` with the per-pair breakdown."""
        return self._loads(flank, phi_p, w_p, phi_w, w_w, v_impact, signs, True)

    def static_force(self, flank: int, phi_p: float, delta: float) -> float:
        """Total normal force [N] of ``flank`` at penetration ``delta`` without dissipation:
        sum_i K_i (delta - g_i)^(3/2) over the pairs that touch."""
        law = self.law
        total = 0.0
        for _slot, s, g, _dg in self.geometry.pairs(flank, phi_p):
            d = delta - g
            if d > 0.0:
                K = law.coefficients(self.geometry.normal_radii(s)[2]).K
                total += K * (d * math.sqrt(d))
        return total

    def contact_rates(self, flank: int, phi_p: float, w_p: float, delta: float,
                      delta_dot: float) -> tuple[float, float]:
        """``(k, c)``: the contact's stiffness dW/d(delta) [N/m] and damping dW/d(delta_dot)
        [N.s/m] summed over the touching pairs at penetration ``delta`` and rate
        ``delta_dot``; they set the contact's time scales sqrt(m/k) and m/c."""
        law, d = self.law, self.damping
        k_sum = c_sum = 0.0
        for _slot, s, g, dg in self.geometry.pairs(flank, phi_p):
            pen = delta - g
            if pen > 0.0:
                K = law.coefficients(self.geometry.normal_radii(s)[2]).K
                root = math.sqrt(pen)
                factor = 1.0 + d * (delta_dot - self.pair_rate(flank, w_p, dg))
                if factor > 0.0:
                    k_sum += 1.5 * K * root * factor
                c_sum += K * d * (pen * root)
        return k_sum, c_sum

    def _loads(self, flank, phi_p, w_p, phi_w, w_w, v_impact, signs, detail) -> MeshLoads:
        p = self.params
        g = self.geometry
        law = self.law
        delta = self.penetration(flank, phi_p, phi_w)
        out = MeshLoads(flank, delta, 0.0, 0.0, 0.0, 0.0)
        if delta <= 0.0:
            return out
        delta_dot = self.approach_rate(flank, w_p, w_w)
        damping = self.damping
        E_star = self.E_star
        tau_w = tau_p = W_sum = F_net = 0.0
        for slot, s, offset, dg in g.pairs(flank, phi_p):
            pen = delta - offset
            if pen <= 0.0:
                if detail:
                    r_x = g.normal_radii(s)[2]
                    out.pairs.append(PairLoad(slot, s, offset, r_x, law.coefficients(r_x).K,
                                              pen, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0))
                continue
            r_x = g.normal_radii(s)[2]
            K, _R, ka, kz = law.coefficients(r_x)
            W = K * (pen * math.sqrt(pen))
            if damping > 0.0:
                W *= 1.0 + damping * (delta_dot - self.pair_rate(flank, w_p, dg))
                if W < 0.0:  # the flanks never pull on each other
                    W = 0.0
            tau_w += flank * W * self.arm_wheel
            tau_p -= flank * W * self.arm_pinion
            W_sum += W
            F = 0.0
            rho_p, rho_w = s, g.line_length - s
            v_s = lubrication.sliding_speed(w_p, rho_p, w_w, rho_w)
            u = lubrication.entrainment_speed(w_p, rho_p, w_w, rho_w)
            h = lam = psi = d_max = 0.0
            if (p.friction_enabled or detail) and W > 0.0:
                A_e = lubrication.asperity_area(W, E_star, p.gamma, p.sigma)
                A = kz * W ** (2.0 / 3.0)
                d_max = hertz.film_delta_max(v_impact, K, r_x, ka, p.density)
                h = lubrication.film_thickness(-pen, d_max)
                lam = h / p.sigma
                psi = lubrication.dry_fraction(lam)
                if p.friction_enabled:
                    U = u if p.shear_speed == 0 else v_s
                    F = lubrication.friction_force(
                        p.friction_form, psi, A_e, A, p.tau_s, p.eta, U, h)
                    if signs is not None:
                        sgn = signs[slot]
                    elif v_s > 0.0:
                        sgn = 1.0
                    elif v_s < 0.0:
                        sgn = -1.0
                    else:
                        sgn = 0.0
                    if sgn != 0.0:
                        tau_w += sgn * F * rho_w
                        tau_p -= sgn * F * rho_p
                        F_net += sgn * F
            if detail:
                out.pairs.append(PairLoad(slot, s, offset, r_x, K, pen, W, F, v_s, u, h, lam,
                                          psi, d_max))
        out.tau_wheel, out.tau_pinion, out.W, out.F = tau_w, tau_p, W_sum, F_net
        return out

    def energy_balance_delta_max(self, flank: int, phi_p: float, v_impact: float) -> float:
        """Largest eq. (7)-(8) delta_max [m] over the pairs in the zone of action of
        ``flank`` for an impact at normal speed ``v_impact`` [m/s]."""
        out = 0.0
        for _, s, _g, _dg in self.geometry.pairs(flank, phi_p):
            r_x = self.geometry.normal_radii(s)[2]
            K, _R, ka, _kz = self.law.coefficients(r_x)
            d = hertz.film_delta_max(v_impact, K, r_x, ka, self.params.density)
            if d > out:
                out = d
        return out

    def pair_forces(self, loads: MeshLoads) -> list[float]:
        """Normal force per pair slot [N] (``MAX_PAIR_SLOTS`` entries, 0 for empty slots)."""
        forces = [0.0] * MAX_PAIR_SLOTS
        for pair in loads.pairs:
            forces[pair.slot] = pair.W
        return forces
