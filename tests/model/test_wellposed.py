"""At the default load and above M* the default contact makes the rattle a property of the
operating point, not of the start: smooth, kicked and free starts reach one attractor after
their transients at 0.5 M* and 1.2 M* (the multistability study's criterion); the
quasi-static separation threshold A* holds.  (Not at every load and dissipation: with
Hunt-Crossley dissipation 0.4 M* has coexisting attractors, which the multistability study
finds, tests/analysis/test_multistability.py.)"""

import math
from dataclasses import replace

import numpy as np
import pytest

from drive_rattle import COAST, DRIVE, DrivelineParameters, DrivelineUnit, MeshParameters, MeshUnit
from drive_rattle_cosim.multistability import STARTS, study_point
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


START_SET = [s for s in STARTS if s.name in ("smooth", "kick +1", "free")]


def test_starts_reach_one_attractor_at_the_default_load():
    # The paper's model (a constant load) at 0.5 M* (the default drag) from the smooth start,
    # a kick of +1 rad/s and the free start: after each start's transient the windows'
    # statistics agree beyond their scatter (the multistability study's criterion,
    # drive_rattle_cosim.multistability), and it rattles.  Rattle at 0.5 M* is chaotic under
    # the default squeeze film: the statistics are compared by their window scatter, not
    # onset by onset.
    point = study_point(0.5, starts=START_SET, workers=2, min_time=20.0, max_time=40.0)
    assert point.verdict == "single-valued", point.attractors
    assert point.attractors[0].mean["drive_rate"] > 10.0


def test_above_the_separation_load_no_start_rattles():
    # At 1.2 M* every start ends loaded on the drive flank without rattle (at most one touch
    # below 1 mm/s per forcing period, no coast impact).  The loaded states need not be one:
    # measured, the smooth start keeps one 0.32 mm/s touch per period, kicked and free starts
    # none, and their mean loaded pairs differ by up to 2 % (1.49-1.52) -- states held by the
    # sticking friction, which the study reports as separate attractors (docs/model.md 6.2).
    point = study_point(1.2, starts=START_SET, workers=2, min_time=20.0, max_time=40.0)
    assert point.attractors
    for a in point.attractors:
        assert a.mean["coast_rate"] == 0.0
        assert a.mean["energy_rate"] < 1e-5  # [W]
        assert not a.mean["drive_rate"] > 0.0 or a.mean["drive_p90"] < 1e-3


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
