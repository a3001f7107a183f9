"""The load-approach law of one tooth pair (docs/model.md section 3): the readable equations
the model library's contact.c is held against.

* **Smooth point contact** (contact.geometry 0 and 1): Hertz, ``W = K delta^(3/2)``, K from
  the contact law at the pair's radii (hertz.py).
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

from . import roots

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
        """eq. 7's delta_max [m] of the smooth law: the ellipsoid's (hertz.film_delta_max), or
        for a line the solid of mass m = rho pi r_x^2 L on W = K delta^(10/9):
        1/2 m v^2 = 9/19 K delta^(19/9)."""
        from . import hertz

        if not self.line:
            return hertz.film_delta_max(v, K, r_x, ka, density)
        if not K > 0.0:
            return 0.0
        p = self.exponent
        m = density * math.pi * r_x * r_x * length
        return ((p + 1.0) * m * v * v / (2.0 * K)) ** (1.0 / (p + 1.0))


def palmgren_approach_mm(load_N: float, length_mm: float) -> float:
    """Palmgren's law as published, in its own units: the approach [mm] of a steel line contact
    of length ``length_mm`` [mm] under ``load_N`` [N]."""
    return 3.84e-5 * load_N**0.9 / length_mm**0.8
