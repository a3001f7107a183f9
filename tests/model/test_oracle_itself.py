"""The oracle itself (tests/oracle) against independent closed forms, quadratures and scipy:
what makes the readable equations a reference for the library (MODEL_NOTES section 4;
Johnson, Contact Mechanics, 1985, section 3.5/4.2)."""

import math

import numpy as np
import pytest
from scipy import integrate, optimize, special

from tests.oracle import hertz, lubrication, roots

E = hertz.effective_modulus(210e9, 0.3, 210e9, 0.3)


def test_effective_modulus_steel_on_steel():
    assert pytest.approx(115.385e9, rel=1e-5) == E


def test_sphere_impact_example_of_model_notes():
    R = 10e-3
    K = 4.0 / 3.0 * E * math.sqrt(R)
    assert hertz.sphere_stiffness(E, R, R) == pytest.approx(K)
    imp = hertz.hertz_impact(0.032882, K, 1.0)
    assert imp.delta_max == pytest.approx(23.481e-6, rel=1e-4)
    assert imp.t_contact == pytest.approx(69.11e-6, rel=1e-4)
    assert imp.W_max == pytest.approx(1750.5, rel=1e-4)
    assert imp.v_rebound == 1.0


def test_contact_duration_factor_is_the_integral():
    val, _ = integrate.quad(lambda x: 1.0 / math.sqrt(1.0 - x**2.5), 0.0, 1.0)
    assert pytest.approx(2.0 * val, rel=1e-9) == hertz.CONTACT_DURATION_FACTOR
    assert pytest.approx(2.9432, abs=1e-4) == hertz.CONTACT_DURATION_FACTOR


@pytest.mark.parametrize("q", [0.999, 0.7, 0.2, 0.01, 1e-4])
def test_elliptic_integrals_match_scipy(q):
    K, S = hertz.elliptic_integrals(q)
    # ellipkm1 takes the complementary parameter q^2 = 1 - m exactly (m itself would round).
    assert pytest.approx(special.ellipkm1(q * q), rel=1e-14) == K
    assert pytest.approx(special.ellipe(1.0 - q * q), rel=1e-13) == K * (1.0 - S)


@pytest.mark.parametrize("law", [hertz.LAW_EXACT, hertz.LAW_EQUIVALENT_SPHERE])
def test_contact_law_tabulation_is_exact_to_rounding(law):
    r_y = 9.66
    r_lo, r_hi = 4.3e-3, 9.0e-3
    contact = hertz.ContactLaw(law, E, r_y, (math.log(r_y / r_hi), math.log(r_y / r_lo)))
    for r_x in np.linspace(r_lo, r_hi, 37):
        K, R, ka, kz = contact.coefficients(r_x)
        assert r_y == R
        if law == hertz.LAW_EXACT:
            ell = hertz.exact_ellipse(r_y / r_x)
            assert pytest.approx(E * math.sqrt(r_y) * ell.kappa, rel=1e-12) == K
            assert ka == pytest.approx((r_y / E) ** (1 / 3) * ell.alpha, rel=1e-12)
            assert kz == pytest.approx((r_y / E) ** (2 / 3) * ell.zeta, rel=1e-12)
        else:
            assert pytest.approx(hertz.sphere_stiffness(E, r_x, r_y)) == K


def test_film_delta_max_solves_eq7_with_the_ellipse_mass():
    rx, ry, rho, v = 5e-3, 7.8, 7850.0, 4e-3
    contact = hertz.ContactLaw(hertz.LAW_EXACT, E, ry, (math.log(ry / rx),) * 2)
    K, _, ka, _ = contact.coefficients(rx)
    d = hertz.film_delta_max(v, K, rx, ka, rho)

    def residual(delta):
        W = K * delta**1.5
        m = rho * math.pi * rx**2 * 2.0 * ka * W ** (1 / 3)  # l = 2a
        return 0.5 * m * v**2 - 0.4 * K * delta**2.5

    assert d == pytest.approx(optimize.brentq(residual, 1e-15, 1e-3, xtol=1e-22), rel=1e-10)


@pytest.mark.parametrize("alpha", [0.01, 0.3, 1.0, 3.0, 20.0])
def test_hunt_crossley_restitution_against_direct_integration(alpha):
    def rhs(t, y):
        x, u = y
        return [u, -max(max(x, 0.0) ** 1.5 * (1.0 + alpha * u), 0.0)]

    def release(t, y):
        return y[0]
    release.terminal, release.direction = True, -1
    sol = integrate.solve_ivp(rhs, (0.0, 100.0), [0.0, 1.0], rtol=1e-11, atol=1e-13,
                              events=release, first_step=1e-6)
    assert hertz.hunt_crossley_restitution(alpha) == pytest.approx(-sol.y_events[0][0][1],
                                                                   rel=2e-6)


@pytest.mark.parametrize("e", [0.99, 0.8, 0.5, 0.1, 0.02])
def test_hunt_crossley_factor_inverts_the_restitution(e):
    d = hertz.hunt_crossley_factor(e, 4e-3)
    assert hertz.hunt_crossley_restitution(d * 4e-3) == pytest.approx(e, rel=1e-12)
    assert hertz.hunt_crossley_factor(1.0, 4e-3) == 0.0


def test_dry_fraction_is_linear_between_the_limits():
    lams = np.linspace(0.0, 5.0, 501)
    psis = np.array([lubrication.dry_fraction(x) for x in lams])
    assert np.allclose(psis, np.clip((3.0 - lams) / 2.0, 0.0, 1.0), rtol=0, atol=1e-15)


def test_film_thickness_eq11():
    assert lubrication.film_thickness(1e-6, 2e-8) == pytest.approx(1.02e-6)
    assert lubrication.film_thickness(-1e-8, 2e-8) == pytest.approx(1e-8)
    assert lubrication.film_thickness(-3e-8, 2e-8) == 0.0


def test_bad_arguments_are_refused():
    with pytest.raises(ValueError, match="rho"):
        hertz.exact_ellipse(0.5)
    with pytest.raises(ValueError, match="restitution"):
        hertz.hunt_crossley_factor(0.0, 1.0)
    with pytest.raises(ValueError, match="alpha"):
        hertz.hunt_crossley_restitution(-1.0)
    with pytest.raises(ValueError, match="friction form 7"):
        lubrication.friction_force(7, 1.0, 1.0, 1.0, 1.0, 1.0)
    with pytest.raises(ValueError, match="viscous law 2"):
        lubrication.viscous_stress(2, 1.0, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0)


@pytest.mark.parametrize(
    "f, a, b",
    [
        (lambda x: x**3 - 2 * x - 5, 2.0, 3.0),
        (lambda x: math.cos(x) - x, 0.0, 1.0),
        (lambda x: (x - 1e-7) * 1e12, 0.0, 1e-6),
        (lambda x: math.expm1(x) - 1e-9, -1.0, 1.0),
        (lambda x: math.tanh(50.0 * (x - 0.3)), -0.3, 1.0),
    ],
)
def test_brent_matches_scipy(f, a, b):
    ours = roots.brent(f, a, b, xtol=1e-15, rtol=roots.BRENT_RTOL)
    assert ours == pytest.approx(optimize.brentq(f, a, b, xtol=1e-15), abs=1e-12)


def test_brent_rejects_a_non_bracketing_interval():
    with pytest.raises(ValueError, match="do not bracket"):
        roots.brent(lambda x: x * x + 1.0, -1.0, 1.0, xtol=1e-15, rtol=roots.BRENT_RTOL)
