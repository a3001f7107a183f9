"""Monolithic reference: the mesh and the driveline solved as one ODE system with scipy's
``solve_ivp`` (LSODA or Radau), contact onsets as events.

Unlike the co-simulation, nothing is held over a communication step: the pinion follows the
engine-order kinematics exactly and the output-shaft torque acts continuously.  The mesh
forces are the oracle's (:mod:`tests.oracle.mesh`: the readable equations), not the model
library's; the library only supplies the co-simulation's initial state (the units' coupled
start, ``drive_rattle.units.coupled_start_inputs``), so that both start from the same point.
The Hertz force is C1 at the contact onset (W ~ delta^(3/2)), so the integrator runs through
onsets and releases and the onsets are recorded as (non-terminal) events.  The film's
dependence on the last impact speed is left out (the eq. 7 delta_max is then 0): it only
matters in the mixed regime, which needs impact speeds above about 40 mm/s with the default
surfaces.  Slow (the forces are Python): the tests that use it are marked slow.

State ``y = [phi_w, w_w, phi_v, w_v]`` (wheel and vehicle-side angle and speed).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

from drive_rattle.parameters import DrivelineParameters, MeshParameters
from drive_rattle.units import coupled_start_inputs

from .geometry import COAST, DRIVE
from .mesh import MeshModel


@dataclass
class ReferenceResult:
    time: np.ndarray  # communication points [s]
    wheel_phi: np.ndarray
    wheel_w: np.ndarray
    W: np.ndarray  # total normal force at the points [N]
    onset_times: list[float] = field(default_factory=list)
    onset_speeds: list[float] = field(default_factory=list)
    onset_flanks: list[int] = field(default_factory=list)
    rhs_evaluations: int = 0


class EngineOrders:
    """Input-shaft motion from engine orders (MODEL_NOTES section 3):

        a(t)   = sum_k A_k cos(W_k t + p_k),            W_k = order_k * w_mean
        w(t)   = w_mean + sum_k A_k / W_k sin(W_k t + p_k)
        phi(t) = phi_0 + w_mean t - sum_k A_k / W_k^2 (cos(W_k t + p_k) - cos p_k)

    so the mean speed is exactly ``w_mean`` and the three signals are mutually consistent."""

    def __init__(self, p: DrivelineParameters, t_start: float = 0.0):
        self.w_mean = p.w_mean
        self.phi_0 = p.phi_start
        self.t_start = t_start
        self.terms = [(A, k * p.w_mean, ph) for k, A, ph in p.order_terms()]

    def __call__(self, t: float) -> tuple[float, float, float]:
        """``(phi [rad], w [rad/s], a [rad/s^2])`` at time t [s]."""
        tau = t - self.t_start
        phi = self.phi_0 + self.w_mean * tau
        w, a = self.w_mean, 0.0
        for A, W, ph in self.terms:
            arg = W * tau + ph
            phi -= A / (W * W) * (math.cos(arg) - math.cos(ph))
            w += A / W * math.sin(arg)
            a += A * math.cos(arg)
        return phi, w, a


def grid(step: float, stop: float) -> np.ndarray:
    """The co-simulation's communication points from 0: integer nanoseconds."""
    step_ns = round(step * 1e9)
    return np.array([k * step_ns / 1e9 for k in range(round(stop * 1e9 / step_ns) + 1)])


def solve(mesh_params: MeshParameters | None = None,
          driveline_params: DrivelineParameters | None = None, stop_time: float = 0.1,
          sample_step: float = 1e-4, method: str = "LSODA", rtol: float = 1e-9,
          atol_angle: float = 1e-13) -> ReferenceResult:
    """Solve from the co-simulation's initial state to ``stop_time`` [s]; sample at the
    communication grid of ``sample_step`` [s].  ``atol_angle`` [rad] is the absolute tolerance
    on the angles (1e-13 rad is 5e-15 m on the tooth normal); speeds get 1e-10 rad/s."""
    mp = mesh_params or MeshParameters()
    dp = driveline_params or DrivelineParameters()
    if dp.speed_table:
        raise ValueError("the reference runs on engine orders only")
    kin = EngineOrders(dp, 0.0)
    # The co-simulation's initial state: the wheel where the coupled start puts it (the
    # driveline's inputs are the mesh's initial outputs), the shaft in steady state behind it
    # (the vehicle at the wheel speed, the shaft wound up by the drag).
    _, start = coupled_start_inputs(mp, dp, 0.0)
    phi_w0, w_w0 = start["wheel.phi"], start["wheel.w"]
    phi_v0 = phi_w0 - (dp.drag + dp.drag_viscous * w_w0) / dp.k_shaft
    mesh = MeshModel(mp)
    J, Jv = mp.J_wheel, dp.J_vehicle
    k, c = dp.k_shaft, dp.c_shaft
    counter = [0]

    def mesh_torque(t, phi_w, w_w):
        phi_p, w_p, _ = kin(t)
        tau = W = 0.0
        for flank in (DRIVE, COAST):
            if mesh.penetration(flank, phi_p, phi_w) > 0.0:
                tw, _, wf = mesh.torques(flank, phi_p, w_p, phi_w, w_w, 0.0)
                tau, W = tau + tw, W + wf
        return tau, W

    def rhs(t, y):
        counter[0] += 1
        phi_w, w_w, phi_v, w_v = y
        tau_shaft = k * (phi_w - phi_v) + c * (w_w - w_v)
        return [w_w, (mesh_torque(t, phi_w, w_w)[0] - tau_shaft) / J, w_v,
                (tau_shaft - dp.drag - dp.drag_viscous * w_v) / Jv]

    def onset(flank):
        def ev(t, y):
            return mesh.penetration(flank, kin(t)[0], y[0])
        ev.terminal = False
        ev.direction = 1.0  # penetration starting
        return ev

    points = grid(sample_step, stop_time)
    y0 = np.array([phi_w0, w_w0, phi_v0, w_w0])
    atol = np.array([atol_angle, 1e-10, atol_angle, 1e-10])
    sol = solve_ivp(rhs, (0.0, points[-1]), y0, method=method, rtol=rtol, atol=atol,
                    t_eval=points, events=[onset(DRIVE), onset(COAST)])
    if sol.status < 0:
        raise RuntimeError(f"solve_ivp failed: {sol.message}")
    W = np.array([mesh_torque(t, a, b)[1] for t, a, b in zip(sol.t, sol.y[0], sol.y[1],
                                                            strict=True)])
    result = ReferenceResult(sol.t, sol.y[0], sol.y[1], W, rhs_evaluations=counter[0])
    for flank, times, states in zip((DRIVE, COAST), sol.t_events, sol.y_events, strict=True):
        for t_ev, y_ev in zip(times, states, strict=True):
            result.onset_times.append(float(t_ev))
            result.onset_speeds.append(float(mesh.approach_rate(flank, kin(t_ev)[1], y_ev[1])))
            result.onset_flanks.append(flank)
    order = np.argsort(result.onset_times)
    for name in ("onset_times", "onset_speeds", "onset_flanks"):
        values = getattr(result, name)
        setattr(result, name, [values[i] for i in order])
    return result
