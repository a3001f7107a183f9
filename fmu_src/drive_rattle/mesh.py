"""Mesh loads: Hertzian normal force and flank friction of every tooth pair in contact, and
the torques they put on the wheel and the pinion (paper eq. 1-2, 10-17 as read in
docs/model.md).

The rigid-body approach along the tooth normal is common to all pairs of a flank:

    x     = cos(beta_b) * (rb_p phi_p - rb_w phi_w)        (> 0 when the pinion leads)
    delta = flank * x - backlash / 2                       (penetration; < 0 is a gap)

Each pair in the zone of action carries W_i = K_i delta^(3/2); K_i comes from the pair's own
roll position.  Torques (each gear positive in its own forward direction):

    wheel:   tau_w = sum_i  flank W_i cos(beta_b) rb_w + sgn(v_s,i) F_i rho_w,i
    pinion:  tau_p = sum_i -flank W_i cos(beta_b) rb_p - sgn(v_s,i) F_i rho_p,i
"""

from __future__ import annotations

from dataclasses import dataclass, field

from . import hertz, lubrication
from .geometry import HelicalPairGeometry
from .parameters import MAX_PAIR_SLOTS, MeshParameters


@dataclass
class PairLoad:
    """Loads of one tooth pair (SI units)."""

    slot: int  # pair number modulo MAX_PAIR_SLOTS
    s: float  # roll coordinate of the engaged contact-line centre [m]
    fraction: float  # engaged fraction of the contact line [1]
    r_x: float  # equivalent radius in the normal plane [m]
    K: float  # stiffness non-linearity used for this pair [N/m^1.5]
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
    delta: float  # penetration (negative: clearance) [m]
    tau_wheel: float  # torque of the mesh on the wheel [N.m]
    tau_pinion: float  # torque of the mesh on the pinion [N.m]
    W: float  # total normal force [N]
    F: float  # net friction force, positive when it drives the wheel forward [N]
    pairs: list[PairLoad] = field(default_factory=list)


class MeshModel:
    """Evaluates the mesh loads for given gear angles and speeds."""

    def __init__(self, params: MeshParameters):
        self.params = params
        self.geometry = g = HelicalPairGeometry(params)
        self.E_star = hertz.effective_modulus(
            params.E_pinion, params.nu_pinion, params.E_wheel, params.nu_wheel)
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

    # ------------------------------------------------------------------ loads
    def torques(
        self, flank: int, phi_p: float, w_p: float, phi_w: float, w_w: float, v_impact: float
    ) -> tuple[float, float, float]:
        """``(tau_wheel, tau_pinion, W)`` on ``flank``: the integrator's right-hand side."""
        loads = self._loads(flank, phi_p, w_p, phi_w, w_w, v_impact, detail=False)
        return loads.tau_wheel, loads.tau_pinion, loads.W

    def loads(
        self, flank: int, phi_p: float, w_p: float, phi_w: float, w_w: float, v_impact: float
    ) -> MeshLoads:
        """Mesh loads on ``flank`` with the per-pair breakdown."""
        return self._loads(flank, phi_p, w_p, phi_w, w_w, v_impact, detail=True)

    def stiffness_sum(self, flank: int, phi_p: float) -> float:
        """Sum of the pairs' stiffness non-linearities K_i [N/m^1.5] at pinion angle phi_p,
        so that the flank's total normal force is stiffness_sum * delta^(3/2)."""
        return sum(self._pair_stiffness(s, frac)[2] for _, s, frac in
                   self.geometry.pairs(flank, phi_p))

    def energy_balance_delta_max(self, flank: int, phi_p: float, v_impact: float) -> float:
        """Largest eq. (7)-(8) delta_max [m] over the pairs in the zone of action of
        ``flank`` for an impact at normal speed ``v_impact`` [m/s]."""
        p = self.params
        out = 0.0
        for _, s, frac in self.geometry.pairs(flank, phi_p):
            r_x, K_full, _ = self._pair_stiffness(s, frac)
            d = hertz.energy_balance_delta_max(v_impact, K_full, r_x, p.r_y, self.E_star,
                                               p.density)
            out = max(out, d)
        return out

    def _pair_stiffness(self, s: float, fraction: float) -> tuple[float, float, float]:
        """``(r_x, K_full, K)`` of a pair at roll coordinate s with engaged fraction."""
        p = self.params
        _, _, r_x = self.geometry.normal_radii(s)
        K_full = hertz.stiffness(self.E_star, r_x, p.r_y)
        return r_x, K_full, (K_full * fraction if p.length_weighting else K_full)

    def _loads(self, flank, phi_p, w_p, phi_w, w_w, v_impact, detail) -> MeshLoads:
        p = self.params
        g = self.geometry
        delta = self.penetration(flank, phi_p, phi_w)
        out = MeshLoads(flank, delta, 0.0, 0.0, 0.0, 0.0)
        if delta <= 0.0:
            return out
        delta_dot = self.approach_rate(flank, w_p, w_w)
        shape = delta * delta**0.5
        if p.damping > 0.0:
            shape *= 1.0 + p.damping * delta_dot
            if shape < 0.0:  # the flanks never pull on each other
                shape = 0.0
        E_star = self.E_star
        tau_w = tau_p = W_sum = F_net = 0.0
        for slot, s, frac in g.pairs(flank, phi_p):
            r_x, K_full, K = self._pair_stiffness(s, frac)
            W = K * shape
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
                A = hertz.apparent_area(W, r_x, p.r_y, E_star)
                d_max = hertz.energy_balance_delta_max(
                    v_impact, K_full, r_x, p.r_y, E_star, p.density)
                h = lubrication.film_thickness(-delta, d_max)
                lam = h / p.sigma
                psi = lubrication.dry_fraction(lam, A_e, A)
                if p.friction_enabled:
                    U = u if p.shear_speed == 0 else v_s
                    F = lubrication.friction_force(
                        p.friction_form, psi, A_e, A, p.tau_s, p.eta, U, h)
                    if v_s != 0.0:
                        sgn = 1.0 if v_s > 0.0 else -1.0
                        tau_w += sgn * F * rho_w
                        tau_p -= sgn * F * rho_p
                        F_net += sgn * F
            if detail:
                out.pairs.append(PairLoad(slot, s, frac, r_x, K, W, F, v_s, u, h, lam, psi, d_max))
        out.tau_wheel, out.tau_pinion, out.W, out.F = tau_w, tau_p, W_sum, F_net
        return out

    def pair_forces(self, loads: MeshLoads) -> list[float]:
        """Normal force per pair slot [N] (``MAX_PAIR_SLOTS`` entries, 0 for empty slots)."""
        forces = [0.0] * MAX_PAIR_SLOTS
        for pair in loads.pairs:
            forces[pair.slot] = pair.W
        return forces
