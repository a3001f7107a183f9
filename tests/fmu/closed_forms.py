"""Closed forms the FMU tests hold the units against (not the model library's code)."""

from __future__ import annotations

import math

from drive_rattle.parameters import DrivelineParameters


def engine_orders(p: DrivelineParameters, t_start: float = 0.0):
    """The input shaft's motion from engine orders (MODEL_NOTES section 3), W_k = order_k w_mean:

        a(t)   = sum_k A_k cos(W_k t + p_k)
        w(t)   = w_mean + sum_k A_k / W_k sin(W_k t + p_k)
        phi(t) = phi_0 + w_mean t - sum_k A_k / W_k^2 (cos(W_k t + p_k) - cos p_k)

    as a function of t [s] returning ``(phi [rad], w [rad/s], a [rad/s^2])``."""
    terms = [(a, k * p.w_mean, ph) for k, a, ph in p.order_terms()]

    def kinematics(t: float) -> tuple[float, float, float]:
        tau = t - t_start
        phi, w, acc = p.phi_start + p.w_mean * tau, p.w_mean, 0.0
        for a, big_w, ph in terms:
            arg = big_w * tau + ph
            phi -= a / (big_w * big_w) * (math.cos(arg) - math.cos(ph))
            w += a / big_w * math.sin(arg)
            acc += a * math.cos(arg)
        return phi, w, acc
    return kinematics
