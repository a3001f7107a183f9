"""mesh.c, the loads of every tooth pair and the torques they put on both gears (paper
eq. 1-2, 10-17), against the oracle's mesh.py: the loads with their per-pair detail
(rm_probe_loads) at random states (the pairs' laws themselves: test_pairs.py); in steady
drive the mesh carries the load and, without friction, loses no power;
a film law the contact geometry does not have is refused."""

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from drive_rattle import COAST, DRIVE, MeshParameters, MeshUnit, ModelError
from drive_rattle.parameters import DEG
from tests.oracle.mesh import MeshModel

from .helpers import LINE, PAIR_FIELDS, PAPER, REL, W_PINION, Probe, close


# ---------------------------------------------------------- loads, against the oracle
def assert_loads_equal(got, want):
    """The library's loads (helpers.Loads) against the oracle's (oracle.mesh.MeshLoads)."""
    assert got.delta == want.delta
    assert len(got.pairs) == len(want.pairs)
    for row, oracle in zip(got.pairs, want.pairs, strict=True):
        for name in PAIR_FIELDS:
            value, expected = row[name], getattr(oracle, name)
            assert close(value, expected, abs_=1e-300 if name != "h" else 1e-22), (
                name, value, expected)
    arm_w, arm_p = 1.0, 1.0  # torques: compared against the sum of the pairs' magnitudes
    W_sum = sum(p.W for p in want.pairs)
    F_sum = sum(p.F for p in want.pairs)
    for name, scale in (("W", W_sum), ("F", F_sum),
                        ("tau_wheel", W_sum * arm_w + F_sum),
                        ("tau_pinion", W_sum * arm_p + F_sum)):
        assert abs(getattr(got, name) - getattr(want, name)) <= REL * scale + 1e-300, name


parameters = st.fixed_dictionaries({
    "friction_enabled": st.booleans(),
    "friction_form": st.integers(0, 2),
    "shear_speed": st.integers(0, 1),
    "viscous_law": st.integers(0, 1),
    "film": st.integers(0, 1),
    "alpha_pv": st.floats(0.0, 1e-7),
    "tau_limit_0": st.floats(1e3, 1e8),
    "tau_limit_slope": st.floats(0.0, 1.0),
    "hertz_law": st.integers(0, 1),
    "dissipation": st.integers(0, 4),
    "restitution": st.floats(0.05, 1.0),
    "damping": st.floats(0.0, 1000.0),
    "stokes_critical": st.floats(0.0, 30.0),
    "restitution_dry": st.floats(0.05, 1.0),
    "squeeze_fraction": st.floats(1e-4, 1.0),
    "damping_ratio": st.floats(0.0, 1.0),
    "crowning": st.floats(1e-6, 1e-4),
    "beta": st.one_of(st.just(0.0), st.floats(0.5 * DEG, 30.0 * DEG)),
    "backlash": st.floats(0.0, 2e-4),
    "sigma": st.floats(2e-8, 2e-6),
    "b": st.floats(5e-3, 40e-3),
    "contact_geometry": st.integers(0, 2),
    "roughness": st.integers(0, 1),
    "asperity_density": st.floats(1e8, 1e11),
})
states = st.tuples(st.sampled_from([DRIVE, COAST]), st.floats(-50.0, 50.0),
                   st.floats(-300.0, 300.0), st.floats(-1e-7, 5e-6), st.floats(-2.0, 2.0),
                   st.one_of(st.just(0.0), st.floats(0.0, 1.0)))


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(changes=parameters, samples=st.lists(states, min_size=20, max_size=20))
@pytest.mark.slow
def test_mesh_loads_equal_the_oracle_at_random_states(changes, samples):
    try:
        p = MeshParameters(**changes)
    except ModelError:
        assume(False)
    probe, m = Probe(p), MeshModel(p)
    try:
        for flank, phi_p, w_p, delta, dw, v_impact in samples:
            phi_w = m.wheel_angle(flank, phi_p, delta)
            w_w = w_p * m.geometry.ratio + dw
            got = probe.loads(flank, phi_p, w_p, phi_w, w_w, v_impact)
            want = m.loads(flank, phi_p, w_p, phi_w, w_w, v_impact)
            assert_loads_equal(got, want)
    finally:
        probe.close()


@pytest.mark.parametrize("flank", [DRIVE, COAST])
def test_mesh_loads_of_the_parameter_sets(pair, flank):
    probe, m = pair
    rng = np.random.default_rng(3)
    for _ in range(200):
        phi_p, w_p = rng.uniform(-20, 20), rng.uniform(-200, 200)
        phi_w = m.wheel_angle(flank, phi_p, rng.uniform(-5e-8, 3e-6))
        w_w = w_p * m.geometry.ratio + rng.uniform(-1, 1)
        v = rng.choice([0.0, rng.uniform(0, 0.5)])
        assert_loads_equal(probe.loads(flank, phi_p, w_p, phi_w, w_w, v),
                           m.loads(flank, phi_p, w_p, phi_w, w_w, v))


# ------------------------------------------------------------------ steady drive
@pytest.mark.parametrize("friction", [True, False])
def test_steady_drive_kinematics_and_torque_balance(friction):
    # Hunt-Crossley damping (d = 93 s/m): it damps the start's oscillation and takes no
    # measurable share of the power in steady drive; the default squeeze film's damping of a
    # contact at rest (6 pi eta phi A / sigma per pair) would take its share of the load's
    # passage between the pairs
    p = MeshParameters(friction_enabled=friction, dissipation=1)
    load, H, n = 0.2, 1e-4, 4000  # 0.4 s: 110 mesh cycles
    unit = MeshUnit(p, 0.0, W_PINION, load)
    ratio = p.z_pinion / p.z_wheel
    phi0 = unit.wheel()[0]
    taus, tau_p = [], []
    for k in range(n):
        report = unit.step(H, W_PINION * k * H, W_PINION, 0.0, load)
        out = unit.get(("wheel.tau_mesh", "pinion.tau_mesh", "mesh.delta"))
        taus.append(out["wheel.tau_mesh"])
        tau_p.append(out["pinion.tau_mesh"])
        assert out["mesh.delta"] > 0.0 and not report.onsets  # never separates
    mean_speed = (unit.wheel()[0] - phi0) / (n * H)
    assert mean_speed == pytest.approx(W_PINION * ratio, rel=1e-6)
    assert np.mean(taus) == pytest.approx(load, rel=1e-4)
    # Without friction the mesh is lossless: pinion power in = wheel power out.
    power_in = -np.mean(tau_p) * W_PINION
    power_out = np.mean(taus) * W_PINION * ratio
    if friction:
        assert 0.95 * power_in < power_out < power_in
    else:
        assert power_out == pytest.approx(power_in, rel=1e-4)
    out = unit.outputs()
    assert out["mesh.impacts_drive"] == out["mesh.impacts_coast"] == 0


@pytest.mark.parametrize("changes", [PAPER, LINE, {"roughness": 1},
                                     {"roughness": 1, **PAPER}],
                         ids=["paper", "line", "rough", "paper, rough"])
def test_steady_drive_kinematics_and_power_balance(changes):
    # Constant pinion speed and load, friction off: the wheel turns at the rigid ratio, the
    # mean mesh torque carries the load and the mesh is lossless (pinion power in = wheel
    # power out), although the loads jump where a pair enters or leaves the zone (paper).
    p = MeshParameters(friction_enabled=False, **changes)
    load, H, n = 0.2, 1e-4, 4000  # 0.4 s: 110 mesh cycles
    unit = MeshUnit(p, 0.0, W_PINION, load)
    ratio = p.z_pinion / p.z_wheel
    phi0 = unit.wheel()[0]
    taus, tau_p = [], []
    for k in range(n):
        report = unit.step(H, W_PINION * k * H, W_PINION, 0.0, load)
        out = unit.get(("wheel.tau_mesh", "pinion.tau_mesh", "mesh.delta"))
        taus.append(out["wheel.tau_mesh"])
        tau_p.append(out["pinion.tau_mesh"])
        assert out["mesh.delta"] > 0.0 and not report.onsets  # never separates
    assert (unit.wheel()[0] - phi0) / (n * H) == pytest.approx(W_PINION * ratio, rel=1e-6)
    assert np.mean(taus) == pytest.approx(load, rel=1e-4)
    power_in = -np.mean(tau_p) * W_PINION
    power_out = np.mean(taus) * W_PINION * ratio
    assert power_out == pytest.approx(power_in, rel=1e-4)


# ------------------------------------------------------------------ refusals
def test_line_contact_refuses_the_point_contact_ehl_film():
    # Hamrock and Dowson's film is a point-contact law: with the line contact it is refused,
    # naming both parameters and what is allowed; with the paper's point contacts accepted.
    with pytest.raises(ValueError) as err:
        MeshParameters(contact_geometry=2, film=1)
    message = str(err.value)
    assert ("'contact.geometry' = 2" in message and "lubricant.film = 1 (EHL film)" in message
            and "allowed:" in message)
    MeshParameters(contact_geometry=1, film=1)
