"""roots.c's Brent method as the oracle writes it out (tests/oracle/roots.py), against
scipy.optimize.brentq.  (The library's own root finding -- Brent's method and the exact
quadratic crossings -- is tested through the events it locates: test_stepper.py.)"""

import math

import pytest
from scipy import optimize

from tests.oracle import roots


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
