"""Bracketing root finding for the readable equations: Brent's method (zeroin: bisection
safeguarding secant and inverse quadratic steps) written out, as the model library's roots.c
has it; tests/model/test_roots.py holds it against ``scipy.optimize.brentq``.
(The library's event location, quadratic crossings included, is the stepper's: it is tested
through the located events, not copied here.)
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

    Converges to within ``xtol + rtol*|x|`` (both named by every caller).  Raises
    :func:`bracket_error` if the interval does not bracket a root.
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
    root."""
    return ValueError(f"brent: f({a!r}) = {fa!r} and f({b!r}) = {fb!r} do not bracket a root")

