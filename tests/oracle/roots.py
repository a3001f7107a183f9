"""Bracketing root finding and exact quadratic roots for event location.

The FMU's runtime needs nothing beyond the standard library, so the bracketing solver is
Brent's method (zeroin: bisection safeguarding secant and inverse quadratic steps) written out
here; tests hold it against ``scipy.optimize.brentq``.
"""

from __future__ import annotations

import math
from collections.abc import Callable

#: Iteration cap of :func:`brent`; Brent's method needs at most ~log2(range/xtol)^2 steps.
MAX_ITERATIONS = 200
#: The usual relative tolerance of :func:`brent`: four units of roundoff (2**-52).
BRENT_RTOL = 4.0 * 2.220446049250313e-16


def brent(
    f: Callable[[float], float],
    a: float,
    b: float,
    fa: float | None = None,
    fb: float | None = None,
    *,
    xtol: float,
    rtol: float,
) -> float:
    """Root of ``f`` in ``[a, b]`` where ``f(a)`` and ``f(b)`` differ in sign (or one is 0).

    Converges to within ``xtol + rtol*|x|`` (both named by every caller: no default hides a
    tolerance the compiled kernel must repeat).  Raises :func:`bracket_error` if the interval
    does not bracket a root.
    """
    fa = f(a) if fa is None else fa
    fb = f(b) if fb is None else fb
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    if (fa > 0.0) == (fb > 0.0):
        raise bracket_error(a, fa, b, fb)
    c, fc = a, fa
    d = e = b - a
    for _ in range(MAX_ITERATIONS):
        if (fb > 0.0) == (fc > 0.0):
            c, fc = a, fa
            d = e = b - a
        if abs(fc) < abs(fb):
            a, fa, b, fb, c, fc = b, fb, c, fc, b, fb
        tol = 2.0 * rtol * abs(b) + 0.5 * xtol
        m = 0.5 * (c - b)
        if abs(m) <= tol or fb == 0.0:
            return b
        if abs(e) >= tol and abs(fa) > abs(fb):
            s = fb / fa
            if a == c:  # secant
                p = 2.0 * m * s
                q = 1.0 - s
            else:  # inverse quadratic interpolation
                q = fa / fc
                r = fb / fc
                p = s * (2.0 * m * q * (q - r) - (b - a) * (r - 1.0))
                q = (q - 1.0) * (r - 1.0) * (s - 1.0)
            if p > 0.0:
                q = -q
            else:
                p = -p
            if 2.0 * p < min(3.0 * m * q - abs(tol * q), abs(e * q)):
                e, d = d, p / q
            else:
                d = e = m
        else:
            d = e = m
        a, fa = b, fb
        b += d if abs(d) > tol else math.copysign(tol, m)
        fb = f(b)
    return b


def bracket_error(a: float, fa: float, b: float, fb: float) -> ValueError:
    """The refusal of :func:`brent` for an interval ``[a, b]`` whose ends do not bracket a
    root (the compiled kernel reports it with the same four numbers)."""
    return ValueError(f"brent: f({a!r}) = {fa!r} and f({b!r}) = {fb!r} do not bracket a root")


def first_crossing(c0: float, c1: float, c2: float, t_max: float, rising: bool) -> float | None:
    """Smallest ``t`` in ``[0, t_max]`` where ``q(t) = c0 + c1 t + c2 t^2`` crosses zero
    upwards (``rising``) or downwards, or None.

    Roots come from the cancellation-free form of the quadratic formula; a root is accepted
    only where the slope ``c1 + 2 c2 t`` has the requested sign, which gives the event its
    direction and rejects the root a state sits on right after the opposite event.  A state
    exactly on the zero (``c0 == 0``) crosses at ``t = 0`` when it moves the requested way: its
    slope has the requested sign, or the slope is zero and the curvature has it (exact touch).
    """
    sign = 1.0 if rising else -1.0
    if c0 == 0.0 and (sign * c1 > 0.0 or (c1 == 0.0 and sign * c2 > 0.0)):
        return 0.0
    roots: list[float] = []
    if c2 == 0.0:
        if c1 != 0.0:
            roots.append(-c0 / c1)
    else:
        disc = c1 * c1 - 4.0 * c2 * c0
        if disc >= 0.0:
            sq = math.sqrt(disc)
            qq = -0.5 * (c1 + math.copysign(sq, c1))
            if qq != 0.0:
                roots.append(qq / c2)
                roots.append(c0 / qq)
            else:  # c1 == 0 and disc == 0: double root at 0
                roots.append(0.0)
    best = None
    for t in roots:
        if 0.0 < t <= t_max:
            slope = c1 + 2.0 * c2 * t
            right_way = (slope > 0.0) if rising else (slope < 0.0)
            if right_way and (best is None or t < best):
                best = t
    return best
