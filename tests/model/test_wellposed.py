"""At the default load and above M* the default contact makes the rattle a property of the
operating point, not of the start (issue 10): smooth, kicked and free starts reach the same
statistics after the transient at 0.5 M* and 1.2 M*; the quasi-static separation threshold A*
holds.  (Not at every load: 0.4 M* has coexisting attractors, which the multistability study
finds, tests/analysis/test_multistability.py.)"""

import math
from dataclasses import replace

import numpy as np
import pytest

from drive_rattle import COAST, DRIVE, DrivelineParameters, DrivelineUnit, MeshParameters, MeshUnit
from tests.oracle.reference import EngineOrders

from .helpers import pinion_with_order

PARAMS = MeshParameters()
RATIO = PARAMS.z_pinion / PARAMS.z_wheel
#: Deepest deceleration of the default pinion (orders 2/4/6 at 300/200/150 rad/s^2), and the
#: load below which it separates the default wheel quasi-statically (MODEL_NOTES section 3).
DEEPEST_DECELERATION = 250.0
M_STAR = PARAMS.J_wheel * RATIO * DEEPEST_DECELERATION
#: One period of the default forcing: orders 2, 4, 6 and the mesh (order 20) of 830 rpm
#: repeat every half revolution.
PERIOD = 0.5 * 2 * math.pi / DrivelineParameters().w_mean
H = 1e-4


def test_m_star_is_the_deepest_deceleration_of_the_default_pinion():
    unit = DrivelineUnit(DrivelineParameters(a_over_step=False), 0.0, 0.0)
    deepest = 0.0
    for _ in range(round(PERIOD / 1e-5)):
        deepest = min(deepest, unit.outputs()["pinion.a"])
        unit.step(1e-5, 0.0, 0.0)
    assert -deepest == pytest.approx(DEEPEST_DECELERATION, rel=1e-4)


def mesh_run(load, start, periods_skip=14, periods_keep=7):
    """The mesh alone on the default pinion and a constant load (the paper's model): onset
    counts per flank, median onset speed and peak penetration over whole forcing periods
    after the transient."""
    kin = EngineOrders(DrivelineParameters())
    phi, w, _ = kin(0.0)
    p = PARAMS
    if start == "free":  # the wheel at the centre of the backlash, at the rigid speed
        p = replace(p, init_in_contact=False, phi_start=RATIO * phi, w_start=RATIO * w)
    elif start == "kicked":  # the equilibrium angle, 1 rad/s faster than the rigid speed
        with MeshUnit(p, phi, w, load) as smooth:
            phi_w, w_w = smooth.wheel()
        p = replace(p, init_in_contact=False, phi_start=phi_w, w_start=w_w + 1.0)
    unit = MeshUnit(p, phi, w, load)
    n_skip = round(periods_skip * PERIOD / H)
    n = n_skip + round(periods_keep * PERIOD / H)
    counts, speeds, d_peak = {DRIVE: 0, COAST: 0}, [], 0.0
    for k in range(n):
        report = unit.step(H, *kin(k * H), load)
        if k >= n_skip:
            for e in report.onsets:
                counts[e.flank] += 1
                speeds.append(e.speed)
            d_peak = max(d_peak, unit.get(["mesh.delta_peak"])["mesh.delta_peak"])
    return counts, (float(np.median(speeds)) if speeds else 0.0), d_peak


@pytest.mark.parametrize("load_fraction", [0.5, 1.2])
def test_starts_reach_the_same_statistics(load_fraction):
    load = load_fraction * M_STAR
    runs = {start: mesh_run(load, start) for start in ("smooth", "kicked", "free")}
    ref = runs["smooth"]
    for start, (counts, median, d_peak) in runs.items():
        # Once on the same periodic orbit only an onset at a window edge may fall on the
        # other side of it.
        for flank in (DRIVE, COAST):
            assert abs(counts[flank] - ref[0][flank]) <= max(1, 0.03 * ref[0][flank]), start
        assert median == pytest.approx(ref[1], rel=0.02, abs=1e-5), start
        assert d_peak == pytest.approx(ref[2], rel=0.02), start
    if load_fraction < 1.0:
        assert ref[0][DRIVE] > 0  # it rattles below M*


def separates(amplitude, load, friction=True, T=0.1):
    """A pinion oscillating about a fixed angle (no mesh rotation, so no load transfer
    between pairs) with angular acceleration amplitude ``amplitude`` against ``load``."""
    unit = MeshUnit(MeshParameters(friction_enabled=friction), 0.0, 0.0, load)
    for k in range(round(T / H)):
        report = unit.step(H, *pinion_with_order(k * H, 0.0, amplitude, 2 * 830 / 60), load)
        if any(e.kind == "release" for e in report.events):
            return True
    return False


@pytest.mark.parametrize("friction", [True, False])
def test_the_separation_threshold_is_the_quasi_static_one(friction):
    # The wheel leaves the drive flank when the pinion decelerates faster than the load
    # alone decelerates the wheel: A* = load / (J_w z_p/z_w).  The damped contact follows
    # quasi-statically up to a few per cent of it (measured 2.6 % below).
    load = 0.5 * M_STAR
    a_star = load / (PARAMS.J_wheel * RATIO)
    lo, hi = 0.8, 1.1
    assert not separates(lo * a_star, load, friction)
    assert separates(hi * a_star, load, friction)
    for _ in range(6):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if separates(mid * a_star, load, friction) else (mid, hi)
    assert 0.95 < 0.5 * (lo + hi) < 1.01


def test_the_paper_scenario_rattles_with_the_papers_magnitudes():
    # Orders 2/4/6 of MODEL_NOTES section 3 at half the separation load M* (the default
    # scenario's drag): creep rattle with the paper's magnitudes within a factor of two --
    # impact speeds of order 4 mm/s, penetrations of order 1 um -- on the drive flank mostly,
    # a few coast impacts per engine cycle.
    kin = EngineOrders(DrivelineParameters())
    load = 0.5 * M_STAR
    unit = MeshUnit(PARAMS, *kin(0.0)[:2], load)
    d_peak, speeds, flanks = 0.0, [], []
    transient = 1000  # 0.1 s
    for k in range(transient + 2000):
        report = unit.step(H, *kin(k * H), load)
        if k >= transient:
            d_peak = max(d_peak, unit.get(["mesh.delta_peak"])["mesh.delta_peak"])
            speeds += [e.speed for e in report.onsets]
            flanks += [e.flank for e in report.onsets]
    assert len(speeds) > 30
    assert 0.5e-6 < d_peak < 2e-6
    assert 2e-3 < np.median(speeds) < 8e-3
    assert flanks.count(DRIVE) > 2 * flanks.count(COAST) > 0
