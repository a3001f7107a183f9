"""The teeth's own compliance (docs/model.md section 3.7): the readable equations the model
library's compliance.c is held against, and ISO 6336-1's mesh stiffness the whole pair is
checked with.

**A tooth** is the tooth of its virtual spur gear in the normal section (z_n = z / (cos^2
beta_b cos beta), module m_n, pressure angle alpha_n; ISO 6336-1's virtual gear), cut by the
ISO 53 basic rack (dedendum 1.25 m_n, tip radius 0.38 m_n), per unit length of contact line.
Loaded at the point of its involute whose roll length (radius of curvature) is rho, along the
line of action, it deflects by q F with

* **bending, shear and radial compression** of the tooth as a cantilever of the actual section
  from the root circle to the load (Weber's energy method: W. Weber, *The deformation of loaded
  gears and the effect on their load-carrying capacity*, DSIR Sponsored Research 3, 1949;
  Weber and Banaschek 1953; in the form of Yang and Lin, *J. Mech. Transm. Autom. Des.* 109,
  1987), plane strain (E' = E / (1 - nu^2)), shear factor 1.2:

      q_beam = integral over the tooth's height y of
               m(y)^2 / (E' I) + 1.2 cos^2(a1) / (G A) + sin^2(a1) / (E' A),
      m(y) = cos(a1) (y_c - y) - sin(a1) x_c,   I = (2x)^3 / 12,   A = 2x,

  (x, y) the half thickness and height of the section along the tooth centreline, (x_c, y_c)
  the load point, a1 the angle of the load to the normal of the centreline.  The involute is
  x = R sin(theta), y = R cos(theta), R = r_b sqrt(1 + t^2), theta = theta_b - (t - atan t)
  (theta_b the half angle of the tooth at the base circle), t the tangent of its pressure
  angle; below the base circle, down to the root circle, the tooth keeps its base-circle
  thickness (the fillet is not modelled);
* **the gear body** under the tooth (Sainsot, Velex and Duverger, *J. Mech. Des.* 126, 2004):

      q_f = cos^2(a1) / E [L (u_f/S_f)^2 + M (u_f/S_f) + P (1 + Q tan^2(a1))],

  u_f the height above the root circle at which the load's line crosses the centreline,
  S_f = 2 r_f theta_f the root's arc, theta_f the tooth's half angle at the root circle where
  the rack's tip radius leaves it, and each of L, M, P, Q a fit
  A/theta_f^2 + B h^2 + C h/theta_f + D/theta_f + E h + F in h = r_f / r_bore (the body held at
  its bore; fitted for 1.4 <= h <= 7, 0.01 <= theta_f <= 0.12: theta_f outside is taken at
  the nearer end of the fit).

**A pair**: both teeth in series at the pair's contact point (roll coordinate s: the pinion's
normal roll length s / cos(beta_b), the wheel's (L - s) / cos(beta_b)), q(s) = q_pinion +
q_wheel per unit length of contact line; the load bends the teeth over the pair's engaged
contact line of length L_n, so the pair's tooth compliance is c_t = q(s) / L_n, in series with
its contact law: pen = a(W) + c_t W.

(ISO 6336-1's mesh stiffness, the check of the whole pair, is drive_rattle_cosim.mesh_stiffness.)
"""

from __future__ import annotations

import math

from .contact import chebyshev_fit, chebyshev_value

#: ISO 53 basic rack profile A: dedendum and tip radius of the cutter, over m_n.
RACK_DEDENDUM = 1.25
RACK_TIP_RADIUS = 0.38
#: Shear correction factor of a rectangular section.
SHEAR_FACTOR = 1.2
#: Sainsot, Velex and Duverger (2004), Table 1: A, B, C, D, E, F of each coefficient.
SAINSOT = {
    "L": (-5.574e-5, -1.9986e-3, -2.3015e-4, 4.7702e-3, 0.0271, 6.8045),
    "M": (60.111e-5, 28.100e-3, -83.431e-4, -9.9256e-3, 0.1624, 0.9086),
    "P": (-50.952e-5, 185.50e-3, 0.0538e-4, 53.300e-3, 0.2895, 0.9236),
    "Q": (-6.2042e-5, 9.0889e-3, -4.0964e-4, 7.8297e-3, -0.1472, 0.6904),
}
#: The fit's range of theta_f [rad].
THETA_F_RANGE = (0.01, 0.12)
#: The 15-point Gauss-Kronrod rule (nodes x >= 0, Kronrod weights) with its embedded 7-point
#: Gauss rule (weights of the odd-numbered nodes), as in QUADPACK's qk15.
KRONROD_NODES = (0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
                 0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
                 0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
                 0.207784955007898467600689403773245, 0.0)
KRONROD_WEIGHTS = (0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
                   0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
                   0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
                   0.204432940075298892414161999234649, 0.209482141084727828012999174891714)
GAUSS_WEIGHTS = (0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
                 0.381830050505118944950369775488975, 0.417959183673469387755102040816327)
#: Relative accuracy of the adaptive quadrature, and its cap on subdivisions.
QUADRATURE_TOLERANCE = 1e-13
MAX_INTERVALS = 2000
#: The teeth's stiffness per unit length 1/q(s) is tabulated as a Chebyshev series over the
#: path of contact to this relative accuracy at FIT_CHECKS points between the nodes (8, 12, ...
#: terms), as the library does: the monolithic reference evaluates the loads too often for
#: quadratures.
FIT_TOLERANCE = 1e-10
FIT_CHECKS = 23
MAX_TERMS = 64
#: ... and evaluated as quintic Hermite pieces between the nodes of a grid (the series' value
#: and two derivatives at each), within GRID_TOLERANCE of the series at the middle of every
#: step, the grid doubled from GRID_STEPS steps until it is.
GRID_TOLERANCE = 1e-12
GRID_STEPS = 64
MAX_GRID_STEPS = 1024


def involute(a: float) -> float:
    return math.tan(a) - a


def chebyshev_derivative(c: list[float]) -> list[float]:
    """The coefficients of d/dt of sum_j c_j T_j(t) (c_0 the plain first coefficient): with
    a_0 = 2 c_0, a_j = c_j the usual primed series, a'_(j-1) = a'_(j+1) + 2 j a_j."""
    n = len(c)
    a = [0.0] * (n + 1)  # a'_j, a'_n = a'_(n-1) = 0
    for j in range(n - 1, 0, -1):
        a[j - 1] = a[j + 1] + 2.0 * j * c[j]
    return [0.5 * a[0], *a[1:n]]


def quintic_hermite(t: float, h: float, a0, a1) -> float:
    """The quintic through the values and first two derivatives a0, a1 at the ends of a step
    h, at the fraction t of the step."""
    t2, t3, t4, t5 = t * t, t**3, t**4, t**5
    return ((1 - 10 * t3 + 15 * t4 - 6 * t5) * a0[0] + (t - 6 * t3 + 8 * t4 - 3 * t5) * h * a0[1]
            + (0.5 * t2 - 1.5 * t3 + 1.5 * t4 - 0.5 * t5) * h * h * a0[2]
            + (10 * t3 - 15 * t4 + 6 * t5) * a1[0] + (-4 * t3 + 7 * t4 - 3 * t5) * h * a1[1]
            + (0.5 * t3 - t4 + 0.5 * t5) * h * h * a1[2])


def _kronrod(f, a: float, b: float) -> tuple[float, float]:
    """(K15, |K15 - G7|) of f on [a, b]."""
    mid, half = 0.5 * (a + b), 0.5 * (b - a)
    kronrod = KRONROD_WEIGHTS[7] * f(mid)
    gauss = GAUSS_WEIGHTS[3] * f(mid)
    for i in range(7):
        pair = f(mid - half * KRONROD_NODES[i]) + f(mid + half * KRONROD_NODES[i])
        kronrod += KRONROD_WEIGHTS[i] * pair
        if i % 2 == 1:
            gauss += GAUSS_WEIGHTS[i // 2] * pair
    return kronrod * half, abs(kronrod - gauss) * half


def integrate(f, a: float, b: float) -> float:
    """integral_a^b f by adaptive Gauss-Kronrod (the interval of largest error halved until
    the errors' sum is below QUADRATURE_TOLERANCE of the integral)."""
    parts = [(a, b, *_kronrod(f, a, b))]
    while len(parts) < MAX_INTERVALS:
        total = math.fsum(p[2] for p in parts)
        error = math.fsum(p[3] for p in parts)
        if error <= QUADRATURE_TOLERANCE * abs(total):
            return total
        worst = max(range(len(parts)), key=lambda i: parts[i][3])
        lo, hi, _, _ = parts.pop(worst)
        mid = 0.5 * (lo + hi)
        parts += [(lo, mid, *_kronrod(f, lo, mid)), (mid, hi, *_kronrod(f, mid, hi))]
    raise ValueError(f"the quadrature on [{a!r}, {b!r}] did not converge")


def virtual_teeth(z: int, beta: float, beta_b: float) -> float:
    """z_n = z / (cos^2(beta_b) cos(beta)): ISO 6336-1's virtual number of teeth."""
    return z / (math.cos(beta_b) ** 2 * math.cos(beta))


class VirtualTooth:
    """The tooth of a virtual spur gear (normal section), per unit length of contact line."""

    def __init__(self, z_n: float, m_n: float, alpha_n: float, addendum: float, E: float,
                 nu: float, body_ratio: float):
        self.z_n = z_n
        self.r = 0.5 * z_n * m_n
        self.r_base = self.r * math.cos(alpha_n)
        self.r_tip = self.r + addendum * m_n
        self.r_root = self.r - RACK_DEDENDUM * m_n
        self.theta_base = math.pi / (2.0 * z_n) + involute(alpha_n)
        # the rack's tip radius leaves the root circle at the angle theta_f from the tooth
        # centreline: the cutter tooth's flat tip ends X_c = pi m/4 - (h_f - rho) tan(alpha)
        # - rho / cos(alpha) from the space's centre, pi/z_n from the tooth's
        self.theta_root = (math.pi / 2.0 + 2.0 * (RACK_DEDENDUM - RACK_TIP_RADIUS)
                           * math.tan(alpha_n) + 2.0 * RACK_TIP_RADIUS / math.cos(alpha_n)) / z_n
        self.E, self.nu = E, nu
        self.E_plane = E / (1.0 - nu * nu)
        self.G = E / (2.0 * (1.0 + nu))
        theta = min(max(self.theta_root, THETA_F_RANGE[0]), THETA_F_RANGE[1])
        h = body_ratio
        self.body = {key: A / theta**2 + B * h * h + C * h / theta + D / theta + E_ * h + F
                     for key, (A, B, C, D, E_, F) in SAINSOT.items()}

    def point(self, t: float) -> tuple[float, float]:
        """(x, y) of the involute at t = tan(pressure angle)."""
        R = self.r_base * math.sqrt(1.0 + t * t)
        theta = self.theta_base - (t - math.atan(t))
        return R * math.sin(theta), R * math.cos(theta)

    def slope(self, t: float) -> float:
        """dy/dt of the involute."""
        R = self.r_base * math.sqrt(1.0 + t * t)
        theta = self.theta_base - (t - math.atan(t))
        dR = self.r_base * t / math.sqrt(1.0 + t * t)
        dtheta = -t * t / (1.0 + t * t)
        return dR * math.cos(theta) - R * math.sin(theta) * dtheta

    def parts(self, rho: float) -> tuple[float, float]:
        """(beam, body) compliance [m^2/N] of the tooth loaded at normal roll length rho;
        ValueError where the tooth is pointed below the load."""
        t_c = rho / self.r_base
        x_c, y_c = self.point(t_c)
        if not x_c > 0.0:
            raise ValueError(
                f"parameter 'tooth.compliance' = 1: the virtual spur tooth is pointed below its "
                f"contact at roll length {rho * 1e3:.6g} mm; allowed: tooth.compliance = 0, or "
                "a smaller gear.h_a")
        a1 = math.atan(t_c) - (self.theta_base - (t_c - math.atan(t_c)))
        ca, sa = math.cos(a1), math.sin(a1)

        def density(x: float, y: float) -> float:
            arm = ca * (y_c - y) - sa * x_c
            return (arm * arm * 12.0 / (self.E_plane * (2.0 * x) ** 3)
                    + SHEAR_FACTOR * ca * ca / (self.G * 2.0 * x)
                    + sa * sa / (self.E_plane * 2.0 * x))

        beam = 0.0
        if self.r_root < self.r_base:  # the base-circle thickness down to the root circle
            x_b, y_b = self.point(0.0)
            y_f = math.sqrt(self.r_root**2 - x_b * x_b)
            beam += integrate(lambda y: density(x_b, y), y_f, y_b)
            t_0 = 0.0
        else:
            t_0 = math.sqrt((self.r_root / self.r_base) ** 2 - 1.0)
        beam += integrate(lambda t: density(*self.point(t)) * self.slope(t), t_0, t_c)
        u_f = y_c - x_c * math.tan(a1) - self.r_root
        S_f = 2.0 * self.r_root * self.theta_root
        X = self.body
        body = ca * ca / self.E * (X["L"] * (u_f / S_f) ** 2 + X["M"] * u_f / S_f
                                   + X["P"] * (1.0 + X["Q"] * math.tan(a1) ** 2))
        return beam, body

    def compliance(self, rho: float) -> float:
        """q [m^2/N]: the deflection along the line of action per load per unit length."""
        beam, body = self.parts(rho)
        q = beam + body
        if not (q > 0.0 and math.isfinite(q)):
            raise ValueError(f"parameter 'tooth.compliance' = 1: the teeth's compliance is not "
                             f"positive (q = {q!r} m^2/N) at roll length {rho * 1e3:.6g} mm; "
                             "allowed: tooth.compliance = 0")
        return q


class ToothCompliance:
    """Both teeth of a pair in series, for the parameters (``MeshParameters`` or any object
    with its field names) and their geometry (geometry.HelicalPairGeometry): q(s) by the
    quadratures (:meth:`exact`) and, from the Chebyshev series of 1/q over the path of
    contact, :meth:`per_length`."""

    def __init__(self, params, geometry):
        g = geometry
        self.geometry = g
        beta_b = g.beta_b
        self.pinion = VirtualTooth(virtual_teeth(params.z_pinion, params.beta, beta_b),
                                   params.m_n, params.alpha_n, params.addendum,
                                   params.E_pinion, params.nu_pinion,
                                   params.body_ratio_pinion)
        self.wheel = VirtualTooth(virtual_teeth(params.z_wheel, params.beta, beta_b),
                                  params.m_n, params.alpha_n, params.addendum,
                                  params.E_wheel, params.nu_wheel, params.body_ratio_wheel)
        self.t_mid = 0.5 * (g.s_start + g.s_end)
        self.t_scale = 1.0 / (0.5 * (g.s_end - g.s_start))
        self.coefficients = self._fit()
        self.grid, self.step = self._grid()
        self.pitch = self.exact(g.s_pitch)

    def _fit(self) -> list[float]:
        lo, hi = self.geometry.s_start, self.geometry.s_end
        checks = [lo + (hi - lo) * (k + 0.5) / FIT_CHECKS for k in range(FIT_CHECKS)]
        exact = [1.0 / self.exact(s) for s in checks]
        worst = math.inf
        for terms in range(8, MAX_TERMS + 1, 4):
            c = chebyshev_fit(lambda s: 1.0 / self.exact(s), lo, hi, terms)
            worst = max(abs(chebyshev_value(c, (s - self.t_mid) * self.t_scale) - k) / k
                        for s, k in zip(checks, exact, strict=True))
            if worst <= FIT_TOLERANCE:
                return c
        raise ValueError(
            "parameter 'tooth.compliance' = 1: the teeth's compliance along the path of contact "
            f"cannot be tabulated to {FIT_TOLERANCE:g} (reached {worst:.3g}); allowed: "
            "tooth.compliance = 0")

    def _series(self, c, s: float) -> float:
        return chebyshev_value(c, (s - self.t_mid) * self.t_scale)

    def _grid(self):
        lo, hi = self.geometry.s_start, self.geometry.s_end
        c = self.coefficients
        d1 = chebyshev_derivative(c)
        d2 = chebyshev_derivative(d1)
        steps, worst = GRID_STEPS, math.inf
        while steps <= MAX_GRID_STEPS:
            h = (hi - lo) / steps
            grid = [(self._series(c, lo + h * k), self.t_scale * self._series(d1, lo + h * k),
                     self.t_scale**2 * self._series(d2, lo + h * k)) for k in range(steps + 1)]
            worst = max(abs(quintic_hermite(0.5, h, grid[k], grid[k + 1])
                            - self._series(c, lo + h * (k + 0.5)))
                        / self._series(c, lo + h * (k + 0.5)) for k in range(steps))
            if worst <= GRID_TOLERANCE:
                return grid, h
            steps *= 2
        raise ValueError(
            "parameter 'tooth.compliance' = 1: the teeth's compliance along the path of contact "
            f"cannot be tabulated on a grid to {GRID_TOLERANCE:g} (reached {worst:.3g}); "
            "allowed: tooth.compliance = 0")

    def stiffness(self, s: float) -> float:
        """1/q(s) [N/m^2] from the grid."""
        x = (s - self.geometry.s_start) / self.step
        k = min(max(int(x), 0), len(self.grid) - 2)
        return quintic_hermite(x - k, self.step, self.grid[k], self.grid[k + 1])

    def exact(self, s: float) -> float:
        """q(s) [m^2/N] of both teeth at roll coordinate s, by quadrature."""
        g = self.geometry
        c = g.normal_factor
        return self.pinion.compliance(s / c) + self.wheel.compliance((g.line_length - s) / c)

    def per_length(self, s: float) -> float:
        """q(s) [m^2/N] as tabulated."""
        return 1.0 / self.stiffness(s)

    def pair(self, s: float, length: float) -> float:
        """c_t = q(s) / L_n [m/N] of a pair touching at s over an engaged line of length L_n
        (infinite for none)."""
        return 1.0 / (self.stiffness(s) * length) if length > 0.0 else math.inf
