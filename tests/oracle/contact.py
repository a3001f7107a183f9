"""The contact of one tooth pair: its load-approach laws (Hertz, exact and eq. 2;
Palmgren's line contact; the Greenwood-Tripp asperity layer in series) and Hunt-Crossley's
dissipation (paper eq. 1, 2, 7, 8, 14; docs/model.md section 3): the readable equations the
model library's contact.c is held against.

Hertzian point contact of two crowned flanks and its dissipation (Johnson, *Contact
Mechanics*, 1985, section 4.2; Hunt and Crossley 1975).

Plain functions and a small law object on SI floats.  The closed-form solutions (undamped Hertz
impact, exact elliptical contact, Hunt-Crossley restitution) are code here too, so that tests
hold the integrated motion against them (MODEL_NOTES section 4).

Two load-approach laws for the contact of radii ``r_x`` (across the contact line) and ``r_y``
(along it), both of the form ``W = K delta^(3/2)``:

* law 0, **exact** elliptical Hertz contact: the ellipse's aspect ratio ``q = b/a`` follows from
  the curvature ratio through complete elliptic integrals, and K, the semi-major axis ``a`` and
  the area ``pi a b`` from ``q`` (Johnson eq. 3.x/4.x, written out in :func:`exact_ellipse`);
* law 1, the paper's **equivalent sphere** (eq. 2), ``K = 4/3 E* (r_x r_y)^(1/4)``, with the
  ellipse ``sqrt(ab) = (3 W sqrt(r_x r_y) / (4 E*))^(1/3)``, ``a/b = (R/r)^(2/3)`` (Johnson's
  approximation).  For the elongated contacts of crowned teeth (``r_y/r_x ~ 1000``) it is about
  2x softer than the exact law.

The exact law depends on the radii only through ``rho = R/r >= 1`` (larger over smaller radius):
``K = E* sqrt(R) kappa(rho)``, ``a = (W R / E*)^(1/3) alpha(rho)``, ``A = (W R / E*)^(2/3)
zeta(rho)``.  A gear pair's contact points span a fixed range of ``rho``, so :class:`ContactLaw`
fits the three dimensionless functions once, as Chebyshev series in ``ln rho`` accurate to
rounding (checked when the law is built), and evaluates them with Clenshaw's recurrence.

The load-approach law of one tooth pair (:class:`ApproachLaw`):

from . import roots

* **Smooth point contact** (contact.geometry 0 and 1): Hertz, ``W = K delta^(3/2)``, K from
  the contact law at the pair's radii (:class:`ContactLaw`).
* **Smooth line contact** (contact.geometry 2): Palmgren's empirical law for a roller on a
  raceway (A. Palmgren, *Ball and Roller Bearing Engineering*, 3rd ed., 1959),
  ``delta = 3.84e-5 mm (Q/N)^0.9 (l/mm)^-0.8`` for steel.  Made dimensionless with the contact
  modulus of the steel it holds for and scaled with ``(W/E*)^0.9`` for other moduli:
  ``delta = C_P (W/E*)^0.9 L^-0.8``, so ``W = K delta^(10/9)`` with
  ``K = E* (L^0.8 / C_P)^(10/9)``, L the length of the pair's engaged contact line.
* **Rough flanks** (contact.roughness 1): the Greenwood-Tripp asperity pressure
  ``p = K' E* F_5/2(h/sigma)``, ``K' = (16 sqrt 2 / 15) pi (eta gamma sigma)^2 sqrt(sigma/gamma)``
  (Greenwood and Tripp 1970, in the form of Gohar and Rahnejat, *Fundamentals of Tribology*,
  2008) with the fit ``F_5/2(l) = 4.4086e-5 (4 - l)^6.804`` (l < 4), integrated over the pair's
  rigid nominal gap from first asperity contact (mean planes 4 sigma apart at the contact
  centre):

  - ellipsoid (r_x, r_y): ``W = 2 pi sqrt(r_x r_y) P sigma / (n+1) t^(n+1)``,
  - cylinder (r_x, length L): ``W = L sqrt(2 r_x sigma) P B(1/2, n+1) t^(n+1/2)``,

  ``t = delta_a / sigma``, ``P = K' E* 4.4086e-5``, ``n = 6.804``: ``W = W_r t^(1/q)``.  The
  layer is in series with the smooth law (the bulk): one load W, the approaches add,
  ``delta = (W/K)^(1/p) + sigma (W/W_r)^q``, solved for W by Newton's method in ``ln W``.
* **The teeth** (tooth.compliance 1, compliance.py): a linear spring of compliance c_t in
  series with either, ``delta = (W/K)^(1/p) [+ sigma (W/W_r)^q] + c_t W``, solved for W by
  Brent's method in ``ln W`` (the approach is increasing in W); the flanks' own approach is
  ``delta - c_t W``, the stiffness ``1 / (d(flanks)/dW + c_t)``, the energy gains
  ``c_t W^2 / 2``.
"""

from __future__ import annotations

import math
import sys
from typing import NamedTuple

from . import roots

#: Contact duration of an undamped Hertz impact in units of delta_max / v:
#: t_c = 2 delta_max / v * integral_0^1 (1 - x^(5/2))^(-1/2) dx = (4/5) B(2/5, 1/2) delta_max / v.
CONTACT_DURATION_FACTOR = 0.8 * math.gamma(0.4) * math.gamma(0.5) / math.gamma(0.9)

LAW_EXACT = 0
LAW_EQUIVALENT_SPHERE = 1

#: Largest number of Chebyshev coefficients of a fitted function of ln(rho).
MAX_CHEBYSHEV_TERMS = 32
#: Relative accuracy a fitted series must reach at the points between its nodes.
CHEBYSHEV_TOLERANCE = 1e-13
#: Curvature ratio below which an ellipse counts as a circle (q = 1 to rounding).
CIRCLE_RATIO = 1.0 + 1e-9
#: Convergence of the arithmetic-geometric mean (relative difference of the two means).
AGM_TOLERANCE = 1e-16
AGM_MAX_ITERATIONS = 60
#: Absolute tolerances of Brent's method on ln(q) of the exact ellipse and on the
#: Hunt-Crossley factor d v (both dimensionless), and on the coefficient of restitution.
ROOT_XTOL = 1e-15
RESTITUTION_XTOL = 1e-16


def effective_modulus(E1: float, nu1: float, E2: float, nu2: float) -> float:
    """Johnson's contact modulus E* [Pa]: 1/E* = (1-nu1^2)/E1 + (1-nu2^2)/E2.

    The paper prints 2/(...) (the "reduced modulus" E' = 2E*), which with K = 4/3 E* sqrt(R)
    would double the stiffness (MODEL_NOTES section 2).
    """
    return 1.0 / ((1.0 - nu1 * nu1) / E1 + (1.0 - nu2 * nu2) / E2)


def sphere_stiffness(E_star: float, r_x: float, r_y: float) -> float:
    """Stiffness non-linearity K [N/m^1.5] of the equivalent sphere, eq. (2):
    K = 4/3 E* (r_x r_y)^(1/4)."""
    return (4.0 / 3.0) * E_star * math.sqrt(math.sqrt(r_x * r_y))


# ---------------------------------------------------------------- exact elliptical contact
def elliptic_integrals(q: float) -> tuple[float, float]:
    """Complete elliptic integrals for the ellipse of axis ratio ``q = b/a`` in (0, 1]
    (modulus e = sqrt(1 - q^2)): returns ``(K(e), S)`` with ``E(e) = K(e) (1 - S)``.

    Arithmetic-geometric mean (Abramowitz and Stegun 17.6): K = pi / (2 AGM(1, q)) and
    S = sum_n 2^(n-1) c_n^2 with c_0 = e, so that K - E = K S carries no cancellation."""
    a, b = 1.0, q
    c = math.sqrt((1.0 - q) * (1.0 + q))
    S = 0.5 * c * c
    weight = 0.5
    for _ in range(AGM_MAX_ITERATIONS):
        if a - b <= AGM_TOLERANCE * a:
            break
        c = 0.5 * (a - b)
        a, b = 0.5 * (a + b), math.sqrt(a * b)
        weight *= 2.0
        S += weight * c * c
    return math.pi / (2.0 * a), S


def _curvature_ratio(q: float) -> float:
    """B/A = R/r of the ellipse with axis ratio q (Johnson eq. 3.x):
    R/r = ((a/b)^2 E - K) / (K - E) = (e^2 - S) / (q^2 S)."""
    _, S = elliptic_integrals(q)
    e2 = (1.0 - q) * (1.0 + q)
    return (e2 - S) / (q * q * S)


class ExactEllipse(NamedTuple):
    """Dimensionless exact elliptical Hertz contact for the radius ratio rho = R/r >= 1."""

    q: float  # axis ratio b/a
    kappa: float  # K = E* sqrt(R) kappa
    alpha: float  # a = (W R / E*)^(1/3) alpha  (a along the larger radius R)
    zeta: float  # area pi a b = (W R / E*)^(2/3) zeta


def exact_ellipse(rho: float) -> ExactEllipse:
    """Exact elliptical Hertz contact of two bodies with principal relative radii R >= r,
    rho = R/r (Johnson 1985, section 4.2):

    * the axis ratio q = b/a solves R/r = ((a/b)^2 E(e) - K(e)) / (K(e) - E(e));
    * from A = 1/(2R) = 3W (K - E) / (2 pi E* e^2 a^3):  a^3 = 3 W R K S / (pi E* e^2);
    * the approach delta = 3 W K(e) / (2 pi a E*) then gives W = K_H delta^(3/2) with
      K_H = (2 sqrt(2) pi / 3) E* sqrt(R) sqrt(S) / (K e).
    For rho -> 1 these tend to the sphere: K_H = 4/3 E* sqrt(R), a = (3 W R / (4 E*))^(1/3)."""
    if not rho >= 1.0:
        raise ValueError(f"radius ratio rho = {rho!r} must be >= 1 (larger over smaller)")
    if rho <= CIRCLE_RATIO:
        third = (3.0 / 4.0) ** (1.0 / 3.0)
        return ExactEllipse(1.0, 4.0 / 3.0, third, math.pi * third * third)
    target = math.log(rho)

    def residual(y: float) -> float:  # y = ln q
        return math.log(_curvature_ratio(math.exp(y))) - target

    y_lo = -1.0
    while residual(y_lo) < 0.0:
        y_lo *= 2.0
        if y_lo < -200.0:
            raise ValueError(f"radius ratio rho = {rho!r} too large for an elliptical contact")
    y_hi = -1e-9
    y = (roots.brent(residual, y_lo, y_hi, xtol=ROOT_XTOL, rtol=roots.BRENT_RTOL)
         if residual(y_hi) < 0.0 else y_hi)
    q = math.exp(y)
    K, S = elliptic_integrals(q)
    e2 = (1.0 - q) * (1.0 + q)
    e = math.sqrt(e2)
    kappa = (2.0 * math.sqrt(2.0) * math.pi / 3.0) * math.sqrt(S) / (K * e)
    alpha = (3.0 * K * S / (math.pi * e2)) ** (1.0 / 3.0)
    return ExactEllipse(q, kappa, alpha, math.pi * q * alpha * alpha)


def chebyshev_fit(f, lo: float, hi: float, terms: int) -> list[float]:
    """Coefficients c_0..c_{n-1} of the Chebyshev interpolant of ``f`` on [lo, hi] at the n
    Chebyshev points of the first kind (c_0 halved, ready for :func:`chebyshev_value`)."""
    n = terms
    mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    values = [f(mid + half * math.cos(math.pi * (k + 0.5) / n)) for k in range(n)]
    coeffs = []
    for j in range(n):
        acc = 0.0
        for k in range(n):
            acc += values[k] * math.cos(math.pi * j * (k + 0.5) / n)
        coeffs.append(2.0 * acc / n)
    coeffs[0] *= 0.5
    return coeffs


def chebyshev_value(coeffs, t: float) -> float:
    """Clenshaw's recurrence for sum_j c_j T_j(t), t in [-1, 1]."""
    b1 = 0.0
    b2 = 0.0
    j = len(coeffs) - 1
    while j > 0:
        b1, b2 = 2.0 * t * b1 - b2 + coeffs[j], b1
        j -= 1
    return t * b1 - b2 + coeffs[0]


class LawCoefficients(NamedTuple):
    """The contact law at one contact radius (``ContactLaw.coefficients``)."""

    K: float  # stiffness non-linearity of W = K delta^(3/2) [N/m^1.5]
    R: float  # the larger principal radius [m]
    ka: float  # semi-major axis a = ka W^(1/3) [m / N^(1/3)]
    kz: float  # contact area A = kz W^(2/3) [m^2 / N^(2/3)]


class ContactLaw:
    """Load-approach law, contact ellipse and energy-balance film term of one pair's crowned
    point contact, for radii r_x (varying along the path of contact) and a fixed r_y.

    ``x_range`` bounds ln(R/r) over the contact points the geometry can produce; the exact
    law's dimensionless functions are fitted over it (and checked against the direct
    evaluation between the nodes)."""

    def __init__(self, law: int, E_star: float, r_y: float, x_range: tuple[float, float]):
        self.law = law
        self.E_star = E_star
        self.r_y = r_y
        self.x_lo, self.x_hi = x_range
        self.kappa = self.alpha = self.zeta = ()
        self.t_mid = 0.5 * (self.x_lo + self.x_hi)
        half = 0.5 * (self.x_hi - self.x_lo)
        self.t_scale = 1.0 / half if half > 0.0 else 0.0
        if law == LAW_EXACT:
            self.kappa, self.alpha, self.zeta = self._fit()
        elif law != LAW_EQUIVALENT_SPHERE:
            raise ValueError(f"contact law {law!r} unknown; allowed: 0, 1")

    def _fit(self):
        lo, hi = self.x_lo, self.x_hi
        if hi - lo < 1e-12:  # a single ratio: constant series
            ell = exact_ellipse(math.exp(lo))
            return [ell.kappa], [ell.alpha], [ell.zeta]
        cache: dict[float, ExactEllipse] = {}

        def ell(x):
            if x not in cache:
                cache[x] = exact_ellipse(math.exp(x))
            return cache[x]

        checks = [lo + (hi - lo) * (k + 0.5) / 23.0 for k in range(23)]
        for terms in range(8, MAX_CHEBYSHEV_TERMS + 1, 4):
            fits = [chebyshev_fit(lambda x, i=i: ell(x)[i], lo, hi, terms) for i in (1, 2, 3)]
            worst = 0.0
            for x in checks:
                t = (x - self.t_mid) * self.t_scale
                for i, c in zip((1, 2, 3), fits, strict=True):
                    exact = ell(x)[i]
                    worst = max(worst, abs(chebyshev_value(c, t) - exact) / exact)
            if worst <= CHEBYSHEV_TOLERANCE:
                return fits
        raise ValueError(
            f"the exact Hertz law cannot be tabulated for ln(R/r) in [{lo:.4g}, {hi:.4g}] to "
            f"{CHEBYSHEV_TOLERANCE:g} (reached {worst:.3g}); use contact.hertz_law = 1")

    # ------------------------------------------------------------------ evaluation
    def coefficients(self, r_x: float) -> LawCoefficients:
        """``(K, R, ka, kz)`` at the contact radius r_x: the stiffness non-linearity K
        [N/m^1.5], the larger radius R [m] and the coefficients of the semi-major axis
        a = ka W^(1/3) [m] and of the area A = kz W^(2/3) [m^2]."""
        return self.coefficients_at(r_x, self.r_y)

    def coefficients_at(self, r_x: float, r_y: float) -> LawCoefficients:
        """As :meth:`coefficients` for a pair whose r_y is its own (the paper's eq. 6)."""
        E = self.E_star
        if self.law == LAW_EXACT:
            if r_y >= r_x:
                R, rho = r_y, r_y / r_x
            else:
                R, rho = r_x, r_x / r_y
            t = (math.log(rho) - self.t_mid) * self.t_scale
            K = E * math.sqrt(R) * chebyshev_value(self.kappa, t)
            c = (R / E) ** (1.0 / 3.0)
            return LawCoefficients(K, R, c * chebyshev_value(self.alpha, t),
                                   c * c * chebyshev_value(self.zeta, t))
        # Equivalent sphere (eq. 2) with Johnson's approximate ellipse: sqrt(ab) from Hertz,
        # a/b = (R/r)^(2/3) with a along the larger radius.
        K = (4.0 / 3.0) * E * math.sqrt(math.sqrt(r_x * r_y))
        g = (3.0 * math.sqrt(r_x * r_y) / (4.0 * E)) ** (1.0 / 3.0)  # sqrt(ab) / W^(1/3)
        if r_y >= r_x:
            R, stretch = r_y, (r_y / r_x) ** (1.0 / 3.0)
        else:
            R, stretch = r_x, (r_x / r_y) ** (1.0 / 3.0)
        return LawCoefficients(K, R, g * stretch, math.pi * g * g)


def film_delta_max(v: float, K: float, r_x: float, ka: float, density: float) -> float:
    """delta_max [m] of eq. (7)-(8): the equivalent ellipsoid of mass m = rho pi r_x^2 l, with
    l = 2a its contact ellipse's long diameter at the peak load W = K delta_max^(3/2),
    striking at speed v [m/s]: 1/2 m v^2 = 2/5 K delta_max^(5/2).

    With a = ka W^(1/3), m = C sqrt(delta_max) where C = 2 rho pi r_x^2 ka K^(1/3), and the
    balance has the closed form delta_max = |v| sqrt(5 C / (4 K))."""
    C = 2.0 * density * math.pi * r_x * r_x * ka * K ** (1.0 / 3.0)
    return abs(v) * math.sqrt(5.0 * C / (4.0 * K))


# ---------------------------------------------------------------- closed-form impacts
class HertzImpact(NamedTuple):
    """Closed-form undamped Hertz impact of a mass on W = K delta^(3/2)."""

    delta_max: float  # m
    W_max: float  # N
    t_contact: float  # s
    v_rebound: float  # m/s


def hertz_impact(m: float, K: float, v: float) -> HertzImpact:
    """Closed-form impact of mass m [kg] at approach speed v [m/s] on stiffness K [N/m^1.5]:
    delta_max = (5 m v^2 / (4 K))^(2/5), W_max = K delta_max^(3/2),
    t_c = 2.9432 delta_max / v, rebound speed = v (MODEL_NOTES section 4)."""
    v = abs(v)
    d = (5.0 * m * v * v / (4.0 * K)) ** 0.4
    return HertzImpact(d, K * d**1.5, CONTACT_DURATION_FACTOR * d / v, v)


def _x_minus_log1p(x: float) -> float:
    """x - ln(1 + x) for x > -1; for |x| < 0.1, where the two terms cancel, its Taylor series
    sum over k >= 2 of (-x)^k / k, summed with math.fsum."""
    if abs(x) >= 0.1:
        return x - math.log1p(x)
    return math.fsum((-x) ** k / k for k in range(2, 24))


def _hunt_crossley_balance(alpha: float, e: float) -> float:
    """G(alpha, e) = alpha - ln(1 + alpha) + alpha e + ln(1 - alpha e); zero on the
    restitution curve of the Hunt-Crossley impact (see :func:`hunt_crossley_restitution`).
    Written as phi(alpha) - phi(-alpha e), phi(x) = x - ln(1 + x), so that for a nearly
    elastic impact (small alpha) the four terms do not cancel to rounding."""
    return _x_minus_log1p(alpha) - _x_minus_log1p(-alpha * e)


def hunt_crossley_restitution(alpha: float) -> float:
    """Coefficient of restitution e of an impact on W = K delta^n (1 + d delta_dot) at approach
    speed v, alpha = d v >= 0 (any n, K and mass).

    With the speed u = delta_dot as variable, m u du = -K delta^n (1 + d u) d delta separates:
    u/d - ln(1 + d u)/d^2 changes by -(K/m) integral delta^n d delta, which is zero from the
    onset back to the release, so alpha - ln(1 + alpha) = -alpha e - ln(1 - alpha e), with
    0 <= e < 1/alpha (the force never turns tensile).  Exact, solved by Brent's method."""
    if not (alpha >= 0.0 and math.isfinite(alpha)):
        raise ValueError(f"alpha = d v = {alpha!r} must be finite and >= 0")
    if alpha == 0.0:
        return 1.0
    # G falls in e from G(alpha, 0) > 0 towards -inf at e = 1/alpha; at e = 1 it is
    # 2 alpha - 2 artanh(alpha) < 0.  Past alpha ~ 40 the root is 1/alpha to rounding.
    hi = min(1.0, 1.0 / alpha) * (1.0 - 1e-15)
    if _hunt_crossley_balance(alpha, hi) >= 0.0:
        return hi
    return roots.brent(lambda e: _hunt_crossley_balance(alpha, e), 0.0, hi,
                       xtol=RESTITUTION_XTOL, rtol=roots.BRENT_RTOL)


def hunt_crossley_factor(e: float, v: float) -> float:
    """Hunt-Crossley damping factor d [s/m] for which an impact at speed v [m/s] rebounds with
    the coefficient of restitution e in (0, 1] (the inverse of
    :func:`hunt_crossley_restitution`; e = 1 gives d = 0)."""
    if not (0.0 < e <= 1.0) or not (v > 0.0):
        raise ValueError(f"restitution e = {e!r} must be in (0, 1] and speed v = {v!r} > 0")
    if e == 1.0:
        return 0.0
    # Bracket: e(alpha) falls from 1 (alpha = 0) towards 0 and stays below 1/alpha.
    hi = 1.0
    while hunt_crossley_restitution(hi) > e:
        hi *= 2.0
    alpha = roots.brent(lambda a: hunt_crossley_restitution(a) - e, 0.0, hi, xtol=ROOT_XTOL,
                        rtol=roots.BRENT_RTOL)
    return alpha / v


# ---------------------------------------------------------------- load-approach laws
#: Palmgren: the approach [m] at Q = 1 N and l = 1 mm, and the exponents of Q and l.
PALMGREN_APPROACH = 3.84e-8
PALMGREN_LENGTH = 1e-3
PALMGREN_LOAD_EXPONENT = 0.9
PALMGREN_LENGTH_EXPONENT = 0.8
#: The contact modulus E* of the bearing steel Palmgren's constant holds for (E = 207 GPa,
#: nu = 0.3, steel on steel) [Pa].
PALMGREN_STEEL_MODULUS = 207e9 / (1.0 - 0.3 * 0.3) * 0.5
#: Greenwood-Tripp's F_5/2 fit: c (4 - lambda)^n.
GT_FIT_COEFFICIENT = 4.4086e-5
GT_FIT_EXPONENT = 6.804
#: Newton's iteration cap on the series law (never reached).
SERIES_MAX_ITERATIONS = 100


class ApproachLaw:
    """The load-approach law of the pairs of one parameter set: ``line`` (Palmgren) or point
    (Hertz) bulk, optionally ``rough`` (the asperity layer in series)."""

    def __init__(self, line: bool, rough: bool, E_star: float, sigma: float, gamma: float,
                 asperity_density: float):
        n = GT_FIT_EXPONENT
        self.line, self.rough = bool(line), bool(rough)
        self.E_star, self.sigma = E_star, sigma
        #: p of the bulk law W = K delta^p
        self.exponent = 1.0 / PALMGREN_LOAD_EXPONENT if line else 1.5
        #: Palmgren's constant made dimensionless: delta = C_P (W/E*)^0.9 L^-0.8
        self.palmgren = (PALMGREN_APPROACH * PALMGREN_LENGTH**PALMGREN_LENGTH_EXPONENT
                         * PALMGREN_STEEL_MODULUS**PALMGREN_LOAD_EXPONENT)
        roughness = asperity_density * gamma * sigma
        k_prime = (16.0 * math.sqrt(2.0) / 15.0) * math.pi * roughness * roughness * math.sqrt(
            sigma / gamma)
        #: P = K' E* c [Pa]
        self.asperity_pressure = k_prime * E_star * GT_FIT_COEFFICIENT
        #: q of the layer's approach sigma (W/W_r)^q
        self.rough_exponent = 1.0 / (n + 0.5) if line else 1.0 / (n + 1.0)
        #: B(1/2, n + 1)
        self.line_beta = math.gamma(0.5) * math.gamma(n + 1.0) / math.gamma(n + 1.5)

    # ------------------------------------------------------------------ coefficients
    def line_coefficient(self, length: float) -> float:
        """K [N/m^(10/9)] of Palmgren's W = K delta^(10/9) for a line of ``length`` [m]."""
        return self.E_star * (length**PALMGREN_LENGTH_EXPONENT / self.palmgren) ** self.exponent

    def line_area_coefficient(self, r_x: float, length: float) -> float:
        """kz of the line contact's area A = 2 b L = kz sqrt(W), b = sqrt(4 W r_x / (pi L E*))
        its Hertz half-width (Johnson eq. 4.43)."""
        return 4.0 * math.sqrt(r_x * length / (math.pi * self.E_star))

    def asperity_scale(self, r_x: float, r_y: float, length: float) -> float:
        """W_r [N] of the asperity layer: W = W_r (delta_a / sigma)^(1/q)."""
        P = self.asperity_pressure
        if self.line:
            return length * math.sqrt(2.0 * r_x * self.sigma) * P * self.line_beta
        return 2.0 * math.pi * math.sqrt(r_x * r_y) * P * self.sigma / (GT_FIT_EXPONENT + 1.0)

    # ------------------------------------------------------------------ the law
    def smooth(self, K: float, delta: float) -> float:
        """W = K delta^p of the smooth (bulk) law."""
        if self.line:
            return K * delta**self.exponent
        return K * (delta * math.sqrt(delta))

    def series(self, K: float, W_r: float, delta: float) -> tuple[float, float, float]:
        """``(W, bulk, layer)`` of the series law at approach ``delta``: W solves
        delta = bulk + layer = (W/K)^(1/p) + sigma (W/W_r)^q.  Newton's method on y = ln W
        (the approach is convex and increasing in y) from the smaller one-sided solution,
        which lies above the root: the iterates fall monotonically to it."""
        p, q, sigma = self.exponent, self.rough_exponent, self.sigma
        ln_K, ln_r, ln_d = math.log(K), math.log(W_r), math.log(delta)
        y = min(ln_K + p * ln_d, ln_r + (ln_d - math.log(sigma)) / q)
        bulk, layer = math.exp((y - ln_K) / p), sigma * math.exp(q * (y - ln_r))
        for _ in range(SERIES_MAX_ITERATIONS):
            excess = bulk + layer - delta
            if not excess > 0.0:
                break
            y_new = y - excess / (bulk / p + q * layer)
            if not y_new < y:
                break
            y = y_new
            bulk, layer = math.exp((y - ln_K) / p), sigma * math.exp(q * (y - ln_r))
        return math.exp(y), bulk, layer

    def flanks(self, K: float, W_r: float, W: float) -> tuple[float, float]:
        """``(bulk, layer)`` approaches of the flanks under the load W: (W/K)^(1/p) and, rough,
        sigma (W/W_r)^q."""
        bulk = (W / K) ** (1.0 / self.exponent)
        layer = self.sigma * (W / W_r) ** self.rough_exponent if self.rough else 0.0
        return bulk, layer

    def with_teeth(self, K: float, W_r: float, c_t: float, delta: float
                   ) -> tuple[float, float, float]:
        """``(W, bulk, layer)`` with the teeth in series: W solves
        delta = bulk(W) + layer(W) + c_t W, by Brent's method on y = ln W between a load
        whose approach falls short of delta and the smallest one-sided load (above it)."""
        candidates = [math.log(K) + self.exponent * math.log(delta),
                      math.log(delta / c_t)]
        if self.rough:
            candidates.append(math.log(W_r) + (math.log(delta / self.sigma))
                              / self.rough_exponent)

        def excess(y: float) -> float:
            W = math.exp(y)
            bulk, layer = self.flanks(K, W_r, W)
            return bulk + layer + c_t * W - delta

        hi = min(candidates)
        if excess(hi) <= 0.0:  # the one-sided load is the root to rounding
            y = hi
        else:
            lo = hi - 1.0
            while excess(lo) > 0.0:
                lo -= 2.0 * (hi - lo)
            y = roots.brent(excess, lo, hi, xtol=1e-15, rtol=roots.BRENT_RTOL)
        W = math.exp(y)
        return (W, *self.flanks(K, W_r, W))

    def solve(self, K: float, W_r: float, c_t: float, delta: float
              ) -> tuple[float, float, float]:
        """``(W, bulk, layer)`` of the pair's law at approach ``delta`` (layer 0 when smooth;
        the teeth's share is delta - bulk - layer)."""
        if c_t > 0.0:
            return self.with_teeth(K, W_r, c_t, delta)
        if self.rough:
            return self.series(K, W_r, delta)
        return self.smooth(K, delta), delta, 0.0

    def force(self, K: float, W_r: float, delta: float, c_t: float = 0.0) -> float:
        """The elastic load W [N] at approach ``delta`` > 0 with the teeth's compliance
        ``c_t`` in series (0 for a line of zero length or infinite c_t, and below the smallest
        normal double: a subnormal load is known to a few bits at most, and whether a pair is
        loaded must not turn on them)."""
        if not (K > 0.0 and c_t < math.inf):
            return 0.0
        load = self.solve(K, W_r, c_t, delta)[0]
        return load if load >= sys.float_info.min else 0.0

    def surface(self, K: float, W_r: float, delta: float, c_t: float = 0.0) -> float:
        """The flanks' own approach [m]: ``delta`` less the teeth's deflection c_t W."""
        if not (K > 0.0 and c_t < math.inf) or not c_t > 0.0:
            return delta
        _, bulk, layer = self.solve(K, W_r, c_t, delta)
        return bulk + layer

    def stiffness(self, K: float, W_r: float, delta: float, c_t: float = 0.0) -> float:
        """dW/d(delta) [N/m]: p W / delta (smooth), W / (bulk/p + q layer) (series), the
        teeth's c_t added to the compliance dW/d(delta)^-1."""
        if not (K > 0.0 and c_t < math.inf):
            return 0.0
        if not self.rough and not c_t > 0.0:
            return self.exponent * self.smooth(K, delta) / delta
        W, bulk, layer = self.solve(K, W_r, c_t, delta)
        if not W > 0.0:
            return 0.0
        return W / (bulk / self.exponent + self.rough_exponent * layer + c_t * W)

    def energy(self, K: float, W_r: float, delta: float, c_t: float = 0.0) -> float:
        """integral_0^delta W [J]: W delta / (p + 1) (smooth); for the series law
        W bulk / (p + 1) + W layer q / (q + 1); the teeth's spring adds c_t W^2 / 2."""
        if not (K > 0.0 and c_t < math.inf):
            return 0.0
        p = self.exponent
        if not self.rough and not c_t > 0.0:
            return self.smooth(K, delta) * delta / (p + 1.0)
        W, bulk, layer = self.solve(K, W_r, c_t, delta)
        q = self.rough_exponent
        return W * bulk / (p + 1.0) + W * layer * q / (q + 1.0) + 0.5 * c_t * W * W

    def area(self, kz: float, W: float) -> float:
        """The apparent contact area [m^2] at load W: kz W^(2/3) (ellipse), kz W^(1/2) (line)."""
        if self.line:
            return kz * math.sqrt(W)
        return kz * W ** (2.0 / 3.0)

    def film_delta_max(self, v: float, K: float, r_x: float, ka: float, length: float,
                       density: float) -> float:
        """eq. 7's delta_max [m] of the smooth law: the ellipsoid's (:func:`film_delta_max`), or
        for a line the solid of mass m = rho pi r_x^2 L on W = K delta^(10/9):
        1/2 m v^2 = 9/19 K delta^(19/9)."""
        if not self.line:
            return film_delta_max(v, K, r_x, ka, density)
        if not K > 0.0:
            return 0.0
        p = self.exponent
        m = density * math.pi * r_x * r_x * length
        return ((p + 1.0) * m * v * v / (2.0 * K)) ** (1.0 / (p + 1.0))


def palmgren_approach_mm(load_N: float, length_mm: float) -> float:
    """Palmgren's law as published, in its own units: the approach [mm] of a steel line contact
    of length ``length_mm`` [mm] under ``load_N`` [N]."""
    return 3.84e-5 * load_N**0.9 / length_mm**0.8
