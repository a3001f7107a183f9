"""Hertz contact functions against textbook closed forms (MODEL_NOTES section 4)."""

import math

import pytest
from scipy import integrate, optimize

from drive_rattle import hertz


def test_effective_modulus_steel_on_steel():
    assert hertz.effective_modulus(210e9, 0.3, 210e9, 0.3) == pytest.approx(115.385e9, rel=1e-5)


def test_sphere_impact_example_of_model_notes():
    E = hertz.effective_modulus(210e9, 0.3, 210e9, 0.3)
    R = 10e-3
    K = 4.0 / 3.0 * E * math.sqrt(R)
    assert hertz.stiffness(E, R, R) == pytest.approx(K)
    m = 0.032882
    imp = hertz.hertz_impact(m, K, 1.0)
    assert imp.delta_max == pytest.approx(23.481e-6, rel=1e-4)
    assert imp.t_contact == pytest.approx(69.11e-6, rel=1e-4)
    assert imp.W_max == pytest.approx(1750.5, rel=1e-4)
    assert imp.v_rebound == 1.0


def test_contact_duration_factor_is_the_integral():
    val, _ = integrate.quad(lambda x: 1.0 / math.sqrt(1.0 - x**2.5), 0.0, 1.0)
    assert pytest.approx(2.0 * val, rel=1e-9) == hertz.CONTACT_DURATION_FACTOR
    assert pytest.approx(2.9432, abs=1e-4) == hertz.CONTACT_DURATION_FACTOR


def test_energy_balance_delta_max_solves_eq7_with_eq8_mass():
    E = hertz.effective_modulus(210e9, 0.3, 210e9, 0.3)
    rx, ry, rho, v = 5e-3, 7.8, 7850.0, 4e-3
    K = hertz.stiffness(E, rx, ry)
    d = hertz.energy_balance_delta_max(v, K, rx, ry, E, rho)

    def residual(delta):
        W = K * delta**1.5
        m = rho * math.pi * rx**2 * hertz.footprint_length(W, ry, E)
        return 0.5 * m * v**2 - 0.4 * K * delta**2.5

    assert d == pytest.approx(optimize.brentq(residual, 1e-15, 1e-3, xtol=1e-20), rel=1e-10)


def test_contact_ellipse():
    E = hertz.effective_modulus(210e9, 0.3, 210e9, 0.3)
    rx, ry, W = 5e-3, 7.8, 10.0
    a, b = hertz.contact_semi_axes(W, rx, ry, E)
    assert a > b
    assert math.sqrt(a * b) == pytest.approx((3 * W * math.sqrt(rx * ry) / (4 * E)) ** (1 / 3))
    assert a / b == pytest.approx((ry / rx) ** (2 / 3))
    assert hertz.apparent_area(W, rx, ry, E) == pytest.approx(math.pi * a * b)
    # Circular contact: the classical radius (3 W R / 4 E*)^(1/3).
    a, b = hertz.contact_semi_axes(W, rx, rx, E)
    assert a == pytest.approx(b) and a == pytest.approx((3 * W * rx / (4 * E)) ** (1 / 3))
