"""The Driveline unit (driveline.c): the input-shaft kinematics (engine orders against their
closed form, their deepest deceleration, measured speed tables integrated exactly) and the
output shaft (steady state, free vibration, the exact solution of stiff or heavily damped
shafts, the constant-load model)."""

import math

import numpy as np
import pytest

from drive_rattle import DrivelineParameters, DrivelineUnit, MeshParameters
from drive_rattle.parameters import RPM
from drive_rattle.units import coupled_start_inputs
from tests.oracle.reference import EngineOrders

from .helpers import DEEPEST_DECELERATION, PERIOD, H


def pinion_series(p: DrivelineParameters, n: int, h: float = H):
    """(t, phi, w, a) of the pinion outputs over n steps of a driveline behind a wheel at rest."""
    unit = DrivelineUnit(p, 0.0, 0.0)
    rows = []
    for k in range(n + 1):
        out = unit.outputs()
        rows.append((unit.time, out["pinion.phi"], out["pinion.w"], out["pinion.a"]))
        if k < n:
            unit.step(h, 0.0, 0.0)
    return np.array(rows).T


# ------------------------------------------------------------------ input shaft
def test_engine_orders_are_the_closed_form_with_an_exact_mean():
    p = DrivelineParameters(a_over_step=False)  # the instantaneous acceleration
    kin = EngineOrders(p)
    n = round(60 / 830 * 2 / H)  # two crank revolutions = 4 periods of order 2
    t, phi, w, a = pinion_series(p, n)
    expected = np.array([kin(x) for x in t]).T
    assert np.max(np.abs(phi - expected[0])) < 1e-12 * np.max(np.abs(phi)) + 1e-15
    assert w == pytest.approx(expected[1], rel=1e-13)
    assert a == pytest.approx(expected[2], rel=1e-12, abs=1e-10)
    # the three signals are consistent, and the mean speed is exactly engine.w_mean
    assert np.gradient(phi, t)[1:-1] == pytest.approx(w[1:-1], rel=1e-5)
    assert np.gradient(w, t)[1:-1] == pytest.approx(a[1:-1], rel=1e-3, abs=1.0)
    assert (phi[-1] - phi[0]) / (t[-1] - t[0]) == pytest.approx(830 * RPM, rel=1e-6)
    assert (t[0], phi[0], w[0], a[0]) == (0.0, 0.0, 830 * RPM, 650.0)
    # order 2 of 830 rpm is 27.67 Hz (not the paper's 26 Hz, MODEL_NOTES section 2)
    assert 2 * p.w_mean / (2 * math.pi) == pytest.approx(27.667, abs=1e-3)


def test_m_star_is_the_deepest_deceleration_of_the_default_pinion():
    unit = DrivelineUnit(DrivelineParameters(a_over_step=False), 0.0, 0.0)
    deepest = 0.0
    for _ in range(round(PERIOD / 1e-5)):
        deepest = min(deepest, unit.outputs()["pinion.a"])
        unit.step(1e-5, 0.0, 0.0)
    assert -deepest == pytest.approx(DEEPEST_DECELERATION, rel=1e-4)


def test_the_acceleration_over_the_step_keeps_the_pinion_speed_continuous():
    # pinion.a_over_step: a = (w(t + h) - w(t)) / h, h the last step, so that w + a h is the
    # next step's speed (from the first step on: before it no step is known)
    _, _, w, a = pinion_series(DrivelineParameters(), 200)
    assert w[1:-1] + a[1:-1] * H == pytest.approx(w[2:], rel=1e-14)


def test_a_speed_table_is_integrated_exactly(tmp_path):
    f = tmp_path / "speed.csv"
    f.write_text("time_s,speed_rad_s\n0,10\n1,20\n3,20\n")
    unit = DrivelineUnit(DrivelineParameters(speed_table=str(f), phi_start=1.0), 0.0, 0.0)
    seen = {}
    for k in range(40001):
        if k in (0, 5000, 20000, 40000):
            out = unit.outputs()
            seen[k * H] = (out["pinion.phi"], out["pinion.w"])
        if k < 40000:
            unit.step(H, 0.0, 0.0)
    assert seen[0.0] == (1.0, 10.0)
    assert seen[0.5] == pytest.approx((1.0 + 0.5 * 10 + 0.5 * 10 * 0.25, 15.0), rel=1e-11)
    assert seen[2.0] == pytest.approx((1.0 + 15.0 + 20.0, 20.0), rel=1e-11)
    assert seen[4.0] == pytest.approx((1.0 + 15.0 + 40.0 + 20.0, 20.0), rel=1e-11)  # held


# ------------------------------------------------------------------ output shaft
def test_the_output_shaft_in_steady_state_transmits_the_drag():
    p = DrivelineParameters(drag=0.2, drag_viscous=0.01)
    w = 44.5
    unit = DrivelineUnit(p, 0.0, w)
    assert unit.outputs()["wheel.tau_load"] == pytest.approx(0.2 + 0.01 * w, rel=1e-12)
    for k in range(1000):  # the wheel turns steadily: nothing changes
        unit.step(H, w * k * H, w)
    out = unit.outputs()
    assert out["wheel.tau_load"] == pytest.approx(0.2 + 0.01 * w, rel=1e-9)
    assert out["vehicle.w"] == pytest.approx(w, rel=1e-12)


def twisted(p: DrivelineParameters, w: float = 0.0, twist: float = 1e-3) -> DrivelineUnit:
    """A driveline started in steady state behind a wheel at angle 0 turning at w, whose
    wheel then stands ``twist`` [rad] further on from the first step (the shaft is not
    started anew: init.settle_first_step false)."""
    unit = DrivelineUnit(p.with_public(settle_first_step=False), 0.0, w)
    unit.step(H, twist, w)
    return unit


def test_the_output_shaft_vibrates_freely_at_its_natural_frequency():
    # The wheel held still, the vehicle released from a twisted shaft: it oscillates at
    # sqrt(k / J_v) with the amplitude kept (no damping, no drag; no numerical damping).
    p = DrivelineParameters(c_shaft=0.0, drag=0.0, k_shaft=5000.0, J_vehicle=5.0)
    unit = twisted(p)
    taus = []
    for _ in range(20000):
        unit.step(H, 1e-3, 0.0)
        taus.append(unit.outputs()["wheel.tau_load"])
    crossings = np.where(np.diff(np.sign(taus)) != 0)[0]
    period = 2 * np.mean(np.diff(crossings)) * H
    assert period == pytest.approx(2 * math.pi / math.sqrt(5000 / 5.0), rel=1e-3)
    assert max(taus) == pytest.approx(5.0, rel=1e-3)


def shaft_run(p: DrivelineParameters, steps: int, w: float = 44.57):
    unit = twisted(p, w)
    taus = []
    for k in range(1, steps + 1):
        unit.step(H, 1e-3 + w * k * H, w)
        taus.append(unit.outputs()["wheel.tau_load"])
    return taus


@pytest.mark.parametrize("k, c, J, dv", [
    (1e5, 0.0, 1e-3, 0.0),  # undamped, 10^4 rad/s: rho h_max = 1
    (1e6, 2000.0, 1.0, 0.0),  # critically damped (c^2 = 4 k J): the series branch
    (1e6, 2100.0, 1.0, 0.0),  # just overdamped
    (1e6, 1900.0, 1.0, 3.0),  # just underdamped, with viscous drag
    (2.0, 50.0, 1e-3, 1.0),  # heavily overdamped
])
def test_the_exact_shaft_matches_a_fine_rk4(k, c, J, dv):
    """Where the default substep is too coarse for RK4 the library solves the shaft exactly;
    it must agree with its RK4 on substeps 1000 times finer (another integration)."""
    p = DrivelineParameters(k_shaft=k, c_shaft=c, J_vehicle=J, drag_viscous=dv)
    fine = p.with_public(h_max=p.h_max / 1000)
    rate = (c + dv) / J + math.sqrt(k / J)  # bound of the shaft's eigenvalues
    assert p.h_max * rate > 0.1 and fine.h_max * rate < 0.1  # the exact branch, and RK4
    exact, reference = shaft_run(p, 30), shaft_run(fine, 30)
    scale = max(abs(x) for x in reference)
    assert exact == pytest.approx(reference, rel=1e-9, abs=1e-9 * scale)


@pytest.mark.parametrize("changes", [
    {"c_shaft": 1e6, "J_vehicle": 1e-6},
    {"drag_viscous": 1e5, "J_vehicle": 1e-6},
    {"c_shaft": 1e6, "drag_viscous": 1e5, "J_vehicle": 1e-6, "k_shaft": 1e9},
    {"c_shaft": 1e3, "J_vehicle": 1e-6, "k_shaft": 1e6},
])
def test_extreme_damping_follows_the_quasi_static_closed_form(changes):
    """Damping times J/(c + c_v) of 1e-9..1e-12 s.  The vehicle's inertia is then negligible:
    J_v -> 0 turns the shaft into the first-order equation u' = (drag + c_v w)/(c + c_v)
    - k u/(c + c_v) for the wind-up u = phi_w - phi_v (wheel at constant speed w), with
    torque tau = k u + c (w - phi_v') (+ the O(J) inertia term), in closed form; from a
    twisted start the library follows it to the steady state tau = drag + c_v w."""
    p = DrivelineParameters(**changes)
    w = 44.57
    taus = shaft_run(p, 12, w=w)
    k, c, dv = p.k_shaft, p.c_shaft, p.drag_viscous
    steady = p.drag + dv * w
    u_inf = steady / k
    rate = k / (c + dv)
    eps = p.J_vehicle * k / (c + dv) ** 2  # relative size of the reduction's O(J^2) remainder
    # the twist of 1e-3 rad was applied one step before the first of taus
    u_twist = 1e-3 * math.exp(-rate * H)
    for n, tau in enumerate(taus, start=1):
        d = u_twist * math.exp(-rate * n * H)
        expected = k * (u_inf + d) - c * rate * d - p.J_vehicle * rate**2 * d
        assert math.isfinite(tau)
        rounding = 4.0 * (c + dv) * math.ulp(w)
        tolerance = 10 * eps * abs(expected - steady) + 1e-9 * abs(steady) + 1e-9 + rounding
        assert abs(tau - expected) <= tolerance, (n, tau, expected)


def test_the_constant_load_model_loads_the_wheel_with_the_drag_alone():
    # vehicle.model = 1, the paper's M_res: wheel.tau_load = vehicle.drag at the start and
    # after every step, whatever the wheel does; the "vehicle" moves with the wheel; a
    # restored unit continues; the coupled start settles the wheel in its flank equilibrium
    # for that load.

    p = DrivelineParameters(vehicle_model=1, drag=0.0667, k_shaft=50.0, c_shaft=3.0)
    unit = DrivelineUnit(p, 0.3, 44.0)
    assert unit.outputs()["wheel.tau_load"] == 0.0667
    saved = None
    rows = []
    for k in range(200):
        w = 44.0 + 5.0 * math.sin(k / 9)
        unit.step(H, 0.3 + 44.0 * k * H, w)
        out = unit.outputs()
        assert out["wheel.tau_load"] == 0.0667 and out["vehicle.w"] == w
        if k == 99:
            saved = unit.save()
        if k >= 100:
            rows.append(out)
    unit.restore(saved)
    for k in range(100, 200):
        unit.step(H, 0.3 + 44.0 * k * H, 44.0 + 5.0 * math.sin(k / 9))
        assert unit.outputs() == rows[k - 100]
    mesh_in, _ = coupled_start_inputs(MeshParameters(), p)
    assert mesh_in["wheel.tau_load"] == 0.0667
