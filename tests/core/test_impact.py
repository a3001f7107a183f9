"""Integrated impacts against the Hertz closed form (MODEL_NOTES section 4)."""

import pytest

from drive_rattle import COAST, DRIVE, hertz

from .helpers import approach_stepper


def run_impact(st, H=1e-5, t_max=3e-3):
    events, d_peak, W_peak, t = [], 0.0, 0.0, 0.0
    k = 0
    while k * H < t_max:
        t = k * H
        r = st.step(H, 0.0, 0.0, 0.0, 0.0)
        events += [(t + e.time, e) for e in r.events]
        d_peak, W_peak = max(d_peak, r.delta_peak), max(W_peak, r.W_peak)
        k += 1
        if any(e.kind == "release" for _, e in events):
            break
    return events, d_peak, W_peak


@pytest.mark.parametrize("flank", [DRIVE, COAST])
@pytest.mark.parametrize("v", [1e-3, 4e-3, 0.05])
def test_single_impact_matches_hertz_closed_form(flank, v):
    st = approach_stepper(v, flank)
    K = st.mesh.stiffness_sum(flank, 0.0)
    ref = hertz.hertz_impact(st.mesh.normal_mass, K, v)
    events, d_peak, W_peak = run_impact(st)
    (t_on, on), (t_off, off) = events
    assert (on.kind, on.flank, off.kind, off.flank) == ("onset", flank, "release", flank)
    assert on.speed == pytest.approx(v, rel=1e-12)
    # RK4 loses order next to the onset and the release, where W ~ t^(3/2); at the default
    # h_max = 1e-5 s the measured errors are below 2e-5 for these speeds (see the
    # convergence test), so 1e-4 is ten times tighter than the 0.1 % asked for.
    assert d_peak == pytest.approx(ref.delta_max, rel=1e-4)
    assert W_peak == pytest.approx(ref.W_max, rel=1e-4)
    assert t_off - t_on == pytest.approx(ref.t_contact, rel=1e-4)
    # Rebound speed equals approach speed with friction off.
    assert -off.speed == pytest.approx(v, rel=1e-4)


def test_reference_impact_magnitudes():
    # The paper: deflection of order 1 um at impact speeds of order 4 mm/s.
    st = approach_stepper(4e-3)
    _, d_peak, _ = run_impact(st)
    assert 0.1e-6 < d_peak < 3e-6


def test_friction_and_damping_dissipate():
    v = 4e-3
    speeds = {}
    for label, changes in {"none": {}, "friction": {"friction_enabled": True},
                           "damping": {"damping": 50.0}}.items():
        events, _, _ = run_impact(approach_stepper(v, **changes))
        speeds[label] = -events[-1][1].speed
    assert speeds["none"] == pytest.approx(v, rel=1e-4)
    assert speeds["damping"] < v * 0.999
    assert speeds["friction"] != pytest.approx(v, rel=1e-9)


def test_substep_refinement_converges():
    # The W ~ delta^(3/2) onset limits RK4 to about order 2.5 overall: halving h_max must
    # cut the rebound-speed error at least fourfold.
    v = 0.05
    errs = []
    for h in (2e-5, 1e-5, 5e-6):
        events, _, _ = run_impact(approach_stepper(v, h_max=h), H=1e-4)
        errs.append(abs(-events[-1][1].speed - v))
    assert errs[1] < errs[0] / 4 and errs[2] < errs[1] / 4
