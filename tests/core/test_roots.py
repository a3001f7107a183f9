"""Event-location numerics against scipy and closed forms."""

import math

import numpy as np
import pytest
from scipy import optimize

from drive_rattle.roots import BRENT_RTOL, brent, first_crossing


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
    ours = brent(f, a, b, xtol=1e-15, rtol=BRENT_RTOL)
    ref = optimize.brentq(f, a, b, xtol=1e-15)
    assert ours == pytest.approx(ref, abs=1e-12)


def test_brent_rejects_non_bracketing_interval():
    with pytest.raises(ValueError, match="do not bracket"):
        brent(lambda x: x * x + 1.0, -1.0, 1.0, xtol=1e-15, rtol=BRENT_RTOL)


@pytest.mark.parametrize("seed", range(20))
def test_first_crossing_against_numpy_roots(seed):
    rng = np.random.default_rng(seed)
    c0, c1, c2 = rng.normal(size=3) * [1e-7, 1e-3, 10.0]
    t_max = 1e-4
    for rising in (True, False):
        got = first_crossing(c0, c1, c2, t_max, rising)
        cands = [r.real for r in np.roots([c2, c1, c0]) if abs(r.imag) < 1e-20]
        cands = sorted(t for t in cands if 0 < t <= t_max
                       and ((c1 + 2 * c2 * t > 0) if rising else (c1 + 2 * c2 * t < 0)))
        if cands:
            assert got == pytest.approx(cands[0], rel=1e-9)
        else:
            assert got is None


def test_first_crossing_rejects_wrong_direction_root_at_start():
    # Sitting on the boundary and moving away: no crossing at t = 0+.
    assert first_crossing(0.0, -1.0, 0.0, 1.0, rising=True) is None
    assert first_crossing(-1e-20, -1.0, 1e4, 1.0, rising=True) == pytest.approx(1e-4, rel=1e-9)
