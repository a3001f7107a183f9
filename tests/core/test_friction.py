"""Film and friction (eq. 11-17): regime limits, continuity, direction, dissipation."""

import math

import numpy as np
import pytest

from drive_rattle import hertz, lubrication
from drive_rattle.geometry import COAST, DRIVE
from drive_rattle.mesh import MeshModel
from drive_rattle.parameters import MeshParameters

E = hertz.effective_modulus(210e9, 0.3, 210e9, 0.3)
RX, RY, W, SIGMA, GAMMA, TAU, ETA, U = 5e-3, 7.8125, 10.0, 0.4e-6, 1e-4, 2.28e8, 0.05, 1.7
FORMS = (lubrication.FORM_LOAD_SHARING, lubrication.FORM_APPARENT_AREA,
         lubrication.FORM_AS_PRINTED)


def apparent_area():
    law = hertz.ContactLaw(hertz.LAW_EXACT, E, RY, (math.log(RY / RX),) * 2)
    return law.coefficients(RX)[3] * W ** (2.0 / 3.0)


def force(form, lam):
    h = lam * SIGMA
    A_e = lubrication.asperity_area(W, E, GAMMA, SIGMA)
    psi = lubrication.dry_fraction(lam)
    return lubrication.friction_force(form, psi, A_e, apparent_area(), TAU, ETA, U, h)


def test_default_boundary_friction_coefficient_is_0_1():
    A_e = lubrication.asperity_area(W, E, GAMMA, SIGMA)
    assert A_e * TAU / W == pytest.approx(0.1, rel=0.01)


@pytest.mark.parametrize("lam", [0.0, 0.3, 1.0])
def test_boundary_limit(lam):
    A_e = lubrication.asperity_area(W, E, GAMMA, SIGMA)
    A = apparent_area()
    assert force(lubrication.FORM_LOAD_SHARING, lam) == pytest.approx(A_e * TAU)
    assert force(lubrication.FORM_AS_PRINTED, lam) == pytest.approx(A_e * TAU)
    assert force(lubrication.FORM_APPARENT_AREA, lam) == pytest.approx(A * TAU)


@pytest.mark.parametrize("lam", [3.0, 4.0, 100.0])
def test_full_film_limit(lam):
    h = lam * SIGMA
    A_e = lubrication.asperity_area(W, E, GAMMA, SIGMA)
    A = apparent_area()
    assert force(lubrication.FORM_LOAD_SHARING, lam) == pytest.approx(A * ETA * U / h)
    assert force(lubrication.FORM_APPARENT_AREA, lam) == pytest.approx(A * ETA * U / h)
    assert force(lubrication.FORM_AS_PRINTED, lam) == pytest.approx(A_e * ETA * U / h)


@pytest.mark.parametrize("form", FORMS)
def test_every_form_is_continuous_across_the_regime_limits(form):
    # The boundary (lambda <= 1), mixed and full-film (lambda >= 3) readings agree at the
    # limits: the friction changes by no more than its smooth slope allows across them (the
    # paper's psi = A_e/A of eq. 15 jumped 38-fold at lambda = 1).
    for limit in (lubrication.LAMBDA_BOUNDARY, lubrication.LAMBDA_FULL_FILM):
        eps = 1e-9
        below, at, above = force(form, limit - eps), force(form, limit), force(form, limit + eps)
        slope = abs(force(form, limit + 1e-3) - force(form, limit - 1e-3)) / 2e-3
        assert abs(above - below) <= 4 * eps * slope + 1e-12 * at
        assert abs(at - below) <= 2 * eps * slope + 1e-12 * at


def test_dry_fraction_is_linear_between_the_limits():
    lams = np.linspace(0.0, 5.0, 501)
    psis = np.array([lubrication.dry_fraction(x) for x in lams])
    expected = np.clip((3.0 - lams) / 2.0, 0.0, 1.0)
    assert np.array_equal(psis, expected) or np.allclose(psis, expected, rtol=0, atol=1e-15)
    forces = np.array([force(lubrication.FORM_LOAD_SHARING, x) for x in lams[lams > 0]])
    assert np.all(np.isfinite(forces)) and np.all(forces > 0)


def test_film_thickness_eq11():
    assert lubrication.film_thickness(1e-6, 2e-8) == pytest.approx(1.02e-6)
    assert lubrication.film_thickness(-1e-8, 2e-8) == pytest.approx(1e-8)
    assert lubrication.film_thickness(-3e-8, 2e-8) == 0.0


def test_unknown_form_is_rejected():
    with pytest.raises(ValueError, match="friction form 7"):
        lubrication.friction_force(7, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0)


@pytest.mark.parametrize("flank", [DRIVE, COAST])
def test_friction_reverses_at_pitch_point_and_dissipates(flank):
    mesh = MeshModel(MeshParameters())
    g = mesh.geometry
    w_p = 86.92
    w_w = w_p * g.ratio
    seen = set()
    for phi_p in np.linspace(0.0, 2 * g.base_pitch / g.rb_pinion, 401):
        # Penetrate the flank by 0.2 um.
        phi_w = (mesh.arm_pinion * phi_p - flank * (g.half_backlash + 0.2e-6)) / mesh.arm_wheel
        loads = mesh.loads(flank, phi_p, w_p, phi_w, w_w, 0.0)
        for pair in loads.pairs:
            if pair.W == 0.0 or abs(pair.sliding_speed) < 1e-9:
                continue
            rho_w = g.line_length - pair.s
            before_pitch = pair.s < g.s_pitch
            # At the rigid speed ratio the wheel flank slides faster before the pitch point.
            assert (pair.sliding_speed < 0) == before_pitch
            seen.add(before_pitch)
            assert pytest.approx(0.1 * pair.W, rel=0.01) == pair.F  # boundary regime
            assert rho_w > 0
        # Friction power on the pair of shafts is never positive.
        normal_w = flank * loads.W * mesh.arm_wheel
        normal_p = -flank * loads.W * mesh.arm_pinion
        friction_power = (loads.tau_wheel - normal_w) * w_w + (loads.tau_pinion - normal_p) * w_p
        assert friction_power <= 1e-12
    assert seen == {True, False}


def test_friction_torque_on_wheel_sign_follows_sliding():
    # A single pair just after the pitch point on the drive flank: the faster pinion flank
    # drags the wheel flank forward, so friction adds to the wheel torque.
    p = MeshParameters()
    mesh = MeshModel(p)
    off = MeshModel(MeshParameters(friction_enabled=False))
    g = mesh.geometry
    phi_p = 0.0
    phi_w = (mesh.arm_pinion * phi_p - (g.half_backlash + 0.2e-6)) / mesh.arm_wheel
    w_p = 86.92
    on = mesh.loads(DRIVE, phi_p, w_p, phi_w, w_p * g.ratio, 0.0)
    ref = off.loads(DRIVE, phi_p, w_p, phi_w, w_p * g.ratio, 0.0)
    expected = sum(math.copysign(pp.F, pp.sliding_speed) * (g.line_length - pp.s)
                   for pp in on.pairs)
    assert on.tau_wheel - ref.tau_wheel == pytest.approx(expected, rel=1e-12)
    assert pytest.approx(ref.W) == on.W
