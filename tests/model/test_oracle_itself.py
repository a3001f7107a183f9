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


# ------------------------------------------------------------------ the contact options
def test_palmgren_law_is_the_published_formula_for_steel():
    # delta = 3.84e-5 mm (Q/N)^0.9 (l/mm)^-0.8 at the steel's contact modulus, in SI; and a
    # softer material approaches more, as (W/E*)^0.9.
    from tests.oracle.approach import PALMGREN_STEEL_MODULUS, ApproachLaw, palmgren_approach_mm

    law = ApproachLaw(True, False, PALMGREN_STEEL_MODULUS, 0.4e-6, 1e-4, 1e9)
    for Q, l_mm in ((1.0, 1.0), (1000.0, 10.0), (2.0, 25.0), (5e4, 40.0)):
        delta = palmgren_approach_mm(Q, l_mm) * 1e-3
        K = law.line_coefficient(l_mm * 1e-3)
        assert law.force(K, 0.0, delta) == pytest.approx(Q, rel=1e-13)
    soft = ApproachLaw(True, False, PALMGREN_STEEL_MODULUS / 3.0, 0.4e-6, 1e-4, 1e9)
    K_soft = soft.line_coefficient(0.02)
    assert soft.force(K_soft, 0.0, 1e-6) == pytest.approx(
        law.force(law.line_coefficient(0.02), 0.0, 1e-6) / 3.0, rel=1e-13)


def _asperity_pressure(law, gap):
    """The Greenwood-Tripp pressure [Pa] at the nominal gap ``gap`` above first contact
    (gap < 0: asperities touching): P (-gap / sigma)^n."""
    from tests.oracle.approach import GT_FIT_EXPONENT

    return law.asperity_pressure * (-gap / law.sigma) ** GT_FIT_EXPONENT if gap < 0 else 0.0


@pytest.mark.parametrize("t", [0.3, 1.0, 2.5, 4.0])
def test_asperity_layer_of_a_rigid_ellipsoid_is_the_integrated_pressure(t):
    # W_r t^(n+1) against the pressure integrated over the rigid ellipsoid's nominal gap,
    # x^2/(2 r_x) + y^2/(2 r_y) - delta_a, by quadrature in elliptic polar coordinates.
    from tests.oracle.approach import ApproachLaw

    law = ApproachLaw(False, True, E, 0.4e-6, 1e-4, 1e9)
    r_x, r_y = 7e-3, 0.05
    delta_a = t * law.sigma
    # x = sqrt(2 r_x) rho cos(th), y = sqrt(2 r_y) rho sin(th): gap = rho^2 - delta_a,
    # dA = 2 sqrt(r_x r_y) rho drho dth
    radial, _ = integrate.quad(lambda rho: _asperity_pressure(law, rho * rho - delta_a) * rho,
                               0.0, math.sqrt(delta_a), epsabs=0.0, epsrel=1e-12)
    W = 2.0 * math.pi * 2.0 * math.sqrt(r_x * r_y) * radial
    expected = law.asperity_scale(r_x, r_y, 0.0) * t ** (1.0 / law.rough_exponent)
    assert expected == pytest.approx(W, rel=1e-9)


@pytest.mark.parametrize("t", [0.3, 1.0, 2.5, 4.0])
def test_asperity_layer_of_a_rigid_cylinder_is_the_integrated_pressure(t):
    from tests.oracle.approach import ApproachLaw

    law = ApproachLaw(True, True, E, 0.4e-6, 1e-4, 1e9)
    r_x, length = 7e-3, 0.02
    delta_a = t * law.sigma
    x_max = math.sqrt(2.0 * r_x * delta_a)
    per_length, _ = integrate.quad(
        lambda x: _asperity_pressure(law, x * x / (2.0 * r_x) - delta_a), -x_max, x_max,
        epsabs=0.0, epsrel=1e-12)
    expected = law.asperity_scale(r_x, 0.0, length) * t ** (1.0 / law.rough_exponent)
    assert expected == pytest.approx(length * per_length, rel=1e-9)
    assert law.line_beta == pytest.approx(special.beta(0.5, 6.804 + 1.0), rel=1e-13)


def test_greenwood_tripp_fit_follows_the_gaussian_integral_where_documented():
    # F_5/2(l) = int_l^inf (s - l)^(5/2) phi(s) ds against the fit 4.4086e-5 (4 - l)^6.804:
    # within 11 % for 0 <= l <= 2 (docs/model.md); the fit falls below the Gaussian tail
    # towards first contact (35 % low at l = 2.5, 4x at l = 3).
    def F52(lam):
        return integrate.quad(lambda s: (s - lam) ** 2.5 * math.exp(-s * s / 2.0)
                              / math.sqrt(2.0 * math.pi), lam, math.inf, epsrel=1e-12)[0]

    for lam in np.linspace(0.0, 2.0, 9):
        assert 4.4086e-5 * (4.0 - lam) ** 6.804 == pytest.approx(F52(lam), rel=0.11)
    assert 4.4086e-5 * 1.5**6.804 / F52(2.5) == pytest.approx(0.654, abs=0.01)


@pytest.mark.parametrize("line", [False, True])
def test_series_law_solves_its_equation(line):
    # The load of the series law reproduces its approach, bulk plus layer, to rounding.
    from tests.oracle.approach import ApproachLaw

    law = ApproachLaw(line, True, E, 0.4e-6, 1e-4, 1e9)
    K, W_r = (3e9, 2e-4) if line else (2e10, 1.5e-5)
    for pen in np.geomspace(1e-12, 1e-4, 33):
        W, bulk, layer = law.series(K, W_r, pen)
        assert (W / K) ** (1.0 / law.exponent) == pytest.approx(bulk, rel=1e-14)
        assert law.sigma * (W / W_r) ** law.rough_exponent == pytest.approx(layer, rel=1e-14)
        assert bulk + layer == pytest.approx(pen, rel=1e-13)
        # energy: the integral of the law (quadrature in the load, W dδ = d(Wδ) - δ dW)
        inner, _ = integrate.quad(lambda w: (w / K) ** (1.0 / law.exponent)
                                  + law.sigma * (w / W_r) ** law.rough_exponent, 0.0, W,
                                  epsabs=0.0, epsrel=1e-11, limit=200)
        assert law.energy(K, W_r, pen) == pytest.approx(W * pen - inner, rel=1e-8)
