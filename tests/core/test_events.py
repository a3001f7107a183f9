"""Event location: onsets and releases are located, not stepped over."""

import math

import numpy as np
import pytest

from drive_rattle import COAST, DRIVE, MeshParameters, WheelStepper

from .helpers import approach_stepper, set_state


def test_onset_between_substeps_located_within_1ns():
    v, gap = 3e-3, 41.3e-9
    st = approach_stepper(v, DRIVE, gap=gap)
    H = 1e-4  # ten substeps of 1e-5 s; the onset falls between two of them
    r = st.step(H, 0.0, 0.0, 0.0, 0.0)
    onset = r.events[0]
    assert onset.kind == "onset"
    t_exact = gap / v
    assert (t_exact * 1e5) % 1 > 0.1  # not on a substep boundary
    assert abs(onset.time - t_exact) < 1e-9


def test_onset_with_load_and_pinion_acceleration_matches_quadratic():
    p = MeshParameters(init_in_contact=False, friction_enabled=False)
    st = WheelStepper(p, 0.0, 0.0, 0.0)
    m = st.mesh
    set_state(st, phi=st._wheel_angle(DRIVE, 0.0, -50e-9), w=0.0)
    a_p, tau = 40.0, -0.05  # pinion accelerates forward, load pulls the wheel forward
    r = st.step(2e-4, 0.0, 0.0, a_p, tau)
    a_w = -tau / p.J_wheel
    # delta(t) = -gap + 1/2 (arm_p a_p - arm_w a_w) t^2
    acc = m.arm_pinion * a_p - m.arm_wheel * a_w
    if acc > 0:
        t_exact = math.sqrt(2 * 50e-9 / acc)
        assert abs(r.events[0].time - t_exact) < 1e-9
    else:  # moving apart: no onset
        assert not r.events


def test_release_is_at_zero_penetration():
    st = approach_stepper(4e-3, COAST)
    for _k in range(400):
        r = st.step(1e-5, 0.0, 0.0, 0.0, 0.0)
        if any(e.kind == "release" for e in r.events):
            break
    rel = next(e for e in r.events if e.kind == "release")
    assert st.state.flank == 0
    # The state at the step end is in free flight; back-propagate to the release time.
    phi_rel = st.state.phi - st.state.w * (1e-5 - rel.time)
    assert abs(st.mesh.penetration(COAST, 0.0, phi_rel)) < 1e-15


def test_time_grid_is_not_accumulated():
    # Many steps with a step size that is not a binary fraction: the substep grid inside
    # each step ends exactly at h, so nothing drifts.
    st = approach_stepper(0.0, DRIVE, gap=1e-9)
    h = 1e-4 / 3
    for _ in range(3000):
        st.step(h, 0.0, 0.0, 0.0, 0.0)
    assert st.state.w == 0.0 and st.state.flank == 0


def test_rejected_step_leaves_state_unchanged():
    st = approach_stepper(4e-3)
    before = st.state.as_tuple()
    for bad in [dict(phi_p=float("nan")), dict(w_p=float("inf")), dict(tau_load=float("-inf")),
                dict(a_p=float("nan"))]:
        args = dict(phi_p=0.0, w_p=0.0, a_p=0.0, tau_load=0.0) | bad
        with pytest.raises(ValueError, match="not a finite number"):
            st.step(1e-4, **args)
        assert st.state.as_tuple() == before
    for h in (0.0, -1e-4, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="step size"):
            st.step(h, 0.0, 0.0)
        assert st.state.as_tuple() == before
    assert np.isfinite(st.state.phi)
