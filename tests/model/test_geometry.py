"""geometry.c, the helical pair and the tooth pairs in its zone of action (paper eq. 3-6,
docs/model.md section 2), against the textbook identities, the reference pair of
MODEL_NOTES section 3 and the oracle's geometry (tests/oracle/geometry.py): the derived
quantities (rm_describe), a geometry the pair cannot have refused exactly when the oracle
refuses it, the pairs in the zone (rm_probe_pairs) and, on unmodified flanks (the
contact.geometry options 1, the paper's, and 2, the line contact), every pair in the zone
loaded at the shared approach along its contact line."""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from drive_rattle import (
    COAST,
    DRIVE,
    DrivelineParameters,
    DrivelineUnit,
    MeshParameters,
    MeshUnit,
    ModelError,
)
from drive_rattle.parameters import DEG
from drive_rattle.units import coupled_start_inputs, run_coupled
from tests.oracle.geometry import MAX_PAIR_SLOTS
from tests.oracle.mesh import MeshModel

from .helpers import LINE, PAPER, Probe, close, oracle_derived


# ------------------------------------------------------- textbook identities and the reference pair
@pytest.mark.parametrize("beta_deg", [0.0, 10.0, 27.75, 45.0])
def test_helical_identities(beta_deg):
    p = MeshParameters(beta=beta_deg * DEG, z_pinion=30, z_wheel=45)
    g = p.derived()
    assert math.isclose(math.tan(g["alpha_t"]), math.tan(p.alpha_n) / math.cos(p.beta))
    assert math.isclose(math.sin(g["beta_b"]), math.sin(p.beta) * math.cos(p.alpha_n),
                        abs_tol=1e-15)
    assert math.isclose(math.cos(g["alpha_t"]) * math.cos(g["beta_b"]),
                        math.cos(p.alpha_n) * math.cos(p.beta))
    assert math.isclose(g["r_pinion"], 0.5 * p.z_pinion * p.m_n / math.cos(p.beta))
    assert math.isclose(g["rb_pinion"], g["r_pinion"] * math.cos(g["alpha_t"]))
    assert math.isclose(g["rb_wheel"], g["r_wheel"] * math.cos(g["alpha_t"]))
    assert math.isclose(g["ratio"], p.z_pinion / p.z_wheel)
    # Base pitches: transverse and normal, p_bn = p_bt cos(beta_b) = pi m_n cos(alpha_n).
    assert math.isclose(g["base_pitch"] * math.cos(g["beta_b"]),
                        math.pi * p.m_n * math.cos(p.alpha_n))
    # Pitch point: roll lengths at the pitch point are in the ratio of the base radii.
    assert math.isclose(g["s_pitch"] / (g["line_length"] - g["s_pitch"]),
                        g["rb_pinion"] / g["rb_wheel"])
    assert math.isclose(g["eps_beta"], p.b * math.sin(p.beta) / (math.pi * p.m_n),
                        abs_tol=1e-15)
    assert g["eps_gamma"] == pytest.approx(g["eps_alpha"] + g["eps_beta"], rel=1e-15)
    # Arms of the normal force and the wheel's mass on the tooth normal.
    assert math.isclose(g["arm_wheel"], g["rb_wheel"] * math.cos(g["beta_b"]))
    assert math.isclose(g["normal_mass"], p.J_wheel / g["arm_wheel"] ** 2)


def test_reference_pair():
    # MODEL_NOTES section 3: centre distance 75.0 mm, eps_gamma ~ 3, 3-4 pairs in mesh.
    g = MeshParameters().derived()
    assert g["centre_distance"] == pytest.approx(75.0e-3, abs=0.01e-3)
    assert g["ratio"] == pytest.approx(20 / 39)
    assert g["eps_beta"] == pytest.approx(25 * math.sin(27.75 * DEG) / (math.pi * 2.25))
    assert g["eps_gamma"] == pytest.approx(3.0, abs=0.05)
    assert g["max_pairs"] == 4


def test_transverse_contact_ratio_from_the_path_of_contact():
    # Textbook form in terms of the tip and base radii and the centre distance.
    g = MeshParameters().derived()
    eps = (math.sqrt(g["ra_pinion"] ** 2 - g["rb_pinion"] ** 2)
           + math.sqrt(g["ra_wheel"] ** 2 - g["rb_wheel"] ** 2)
           - g["centre_distance"] * math.sin(g["alpha_t"])) / (
        math.pi * 2.25e-3 * math.cos(g["alpha_t"]) / math.cos(27.75 * DEG))
    assert g["eps_alpha"] == pytest.approx(eps, rel=1e-12)


def test_crowning_gives_the_flank_radius_along_the_contact_line():
    # r_y from the crown: a crown drop C_b at the face end, l = b / (2 cos beta_b) along the
    # contact line, is l^2 / (2 r_y).
    p = MeshParameters()
    g = p.derived()
    half_line = 0.5 * p.b / math.cos(g["beta_b"])
    assert half_line**2 / (2 * g["r_y"]) == pytest.approx(p.crowning, rel=1e-12)


def test_eq6_radius_of_the_reference_pair():
    # docs/model.md: r_y = R_p R_w / (R_w - R_p) with the gears' radii at the contact point;
    # at the pitch point they are the pitch radii: 25.424 and 49.577 mm give 52.19 mm.
    d = MeshParameters().derived()
    assert d["r_y_eq6_pitch"] == pytest.approx(
        d["r_pinion"] * d["r_wheel"] / (d["r_wheel"] - d["r_pinion"]), rel=1e-12)
    assert d["r_y_eq6_pitch"] == pytest.approx(52.19e-3, abs=0.01e-3)
    rows = Probe(MeshParameters(**PAPER)).pair_laws(DRIVE, 0.0)
    assert all(44.4e-3 < r["r_y"] < 65.5e-3 for r in rows)  # along the path of contact
    assert all(7.3 < r["r_y"] / r["r_x"] < 10.8 for r in rows)


# -------------------------------------- the derived quantities and the refusals, against the oracle
def test_describe_equals_the_oracle(pair):
    probe, m = pair
    derived, expected = probe.derived, oracle_derived(m)
    assert set(derived) == set(expected)
    for name, value in expected.items():
        assert close(derived[name], value, abs_=1e-300), (name, derived[name], value)


geometry = st.fixed_dictionaries({
    "z_pinion": st.integers(8, 120), "z_wheel": st.integers(8, 200),
    "m_n": st.floats(1e-4, 0.1), "alpha_n": st.floats(10 * DEG, 35 * DEG),
    "beta": st.one_of(st.just(0.0), st.floats(0.0, 45 * DEG)),
    "addendum": st.floats(0.5, 1.5), "b": st.floats(1e-3, 0.1),
    "backlash": st.floats(0.0, 5e-3), "crowning": st.floats(1e-6, 1e-3),
    "hertz_law": st.integers(0, 1), "contact_geometry": st.integers(0, 2)})
#: The reason of a refused geometry: a phrase of the oracle's message and of the library's.
REASONS = ("undercuts", "tip interference", "transverse contact ratio", "pair slots",
           "cannot be tabulated", "too large for an elliptical contact",
           "needs the wheel's radius at every contact point", "pointed below its contact",
           "compliance is not positive")


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(changes=geometry)
def test_the_library_refuses_a_geometry_exactly_when_the_oracle_does(changes):
    # ... for the same reason, and accepts the others with the oracle's derived quantities.
    try:
        p = MeshParameters(**changes)
    except ModelError as err:
        with pytest.raises(ValueError) as oracle_err:
            MeshModel(_Plain(changes))
        reason = next(r for r in REASONS if r in str(oracle_err.value))
        assert reason in str(err), (str(err), str(oracle_err.value))
        # what is allowed, or (the law's fit) what to use instead
        assert "allowed" in str(err) or "use contact.hertz_law = 1" in str(err)
        event(f"refused by both: {reason}")
        return
    m = MeshModel(p)
    derived, expected = p.derived(), oracle_derived(m)
    for name, value in expected.items():
        assert close(derived[name], value, rel=1e-11, abs_=1e-300), (name, changes)


class _Plain:
    """The defaults with ``changes``, as plain attributes (no library check)."""

    def __init__(self, changes):
        from dataclasses import fields

        for f in fields(MeshParameters):
            setattr(self, f.name, f.default)
        for k, v in changes.items():
            setattr(self, k, v)


def test_an_undercutting_pinion_is_refused_with_the_minimum():
    with pytest.raises(ModelError) as err:
        MeshParameters.from_public({"gear.z_pinion": 10, "gear.beta": 0.0})
    message = str(err.value)
    assert "'gear.z_pinion' = 10" in message and "undercut" in message
    assert "allowed: gear.z_pinion >= 18" in message


def test_a_contact_ratio_below_one_is_refused():
    # Stub teeth on a spur pair: the path of contact is shorter than the base pitch.
    with pytest.raises(ModelError) as err:
        MeshParameters.from_public({"gear.h_a": 0.5, "gear.beta": 0.0})
    message = str(err.value)
    assert "eps_alpha = 0.88" in message and "gear.h_a = 0.5" in message
    assert "allowed: eps_alpha >= 1" in message


def test_a_face_width_needing_too_many_pair_slots_is_refused():
    with pytest.raises(ModelError) as err:
        MeshParameters.from_public({"gear.b": 0.2})
    message = str(err.value)
    assert "'gear.b' = 0.2" in message and "needing 15 pair slots" in message
    assert "at most 8" in message and "allowed: gear.b < 0.1004 m" in message


def test_the_paper_option_refuses_a_wheel_not_larger_than_the_pinion():
    with pytest.raises(ModelError) as err:
        MeshParameters(contact_geometry=1, z_pinion=30, z_wheel=30)
    text = str(err.value)
    assert "'contact.geometry' = 1" in text and "allowed: contact.geometry = 0 or 2" in text


# ------------------------------------------------------------------ pairs in the zone of action
@pytest.mark.parametrize("flank", [DRIVE, COAST])
def test_pairs_in_the_zone_of_action_equal_the_oracle(pair, flank):
    probe, m = pair
    rng = np.random.default_rng(7)
    angles = np.concatenate([rng.uniform(-3.0, 3.0, 300), rng.uniform(-1e3, 1e3, 100)])
    for phi in angles:
        got, want = probe.pairs(flank, phi), m.geometry.pairs(flank, phi)
        assert [p[0] for p in got] == [p[0] for p in want], phi
        for (_, s, g, dg), (_, s_o, g_o, dg_o) in zip(got, want, strict=True):
            assert close(s, s_o, abs_=1e-15) and close(g, g_o, abs_=1e-21)
            assert close(dg, dg_o, abs_=1e-15)


@pytest.mark.parametrize("flank", [DRIVE, COAST])
def test_pairs_in_the_zone_average_to_the_contact_ratios(flank):
    # Over one base pitch of roll the mean number of pairs in the zone of action is
    # eps_gamma, and of those touching at zero crown offset (face centre inside the path of
    # contact) eps_alpha; since eps_alpha >= 1 there is always at least one.
    probe = Probe()
    d = probe.derived
    phis = np.linspace(0.0, d["base_pitch"] / d["rb_pinion"], 4001)[:-1]
    counts, centred = [], []
    for phi in phis:
        pairs = probe.pairs(flank, phi)
        counts.append(len(pairs))
        centred.append(sum(1 for _, _, g, _ in pairs if g == 0.0))
        assert len({slot for slot, _, _, _ in pairs}) == len(pairs)
        assert all(0 <= slot < MAX_PAIR_SLOTS for slot, _, _, _ in pairs)
        assert all(d["s_start"] <= s <= d["s_end"] for _, s, _, _ in pairs)
    assert np.mean(counts) == pytest.approx(d["eps_gamma"], abs=2e-3)
    assert np.mean(centred) == pytest.approx(d["eps_alpha"], abs=2e-3)
    assert min(counts) == 3 and max(counts) == 4
    assert min(centred) >= 1


def test_drive_contacts_travel_towards_the_pinion_tip_coast_towards_its_root():
    probe = Probe()
    for flank, sign in ((DRIVE, 1), (COAST, -1)):
        slot0, s0, _, _ = next(p for p in probe.pairs(flank, 0.0) if p[2] == 0.0)
        s1 = dict((slot, s) for slot, s, _, _ in probe.pairs(flank, 1e-4))[slot0]
        assert sign * (s1 - s0) > 0


# ------------------------------------------------- unmodified flanks: every pair in the zone loaded
def base_pitch_angles(probe, n=4000):
    d = probe.derived
    return np.linspace(0.0, d["base_pitch"] / d["rb_pinion"], n + 1)[:-1]


@pytest.mark.parametrize("flank", [DRIVE, COAST])
@pytest.mark.parametrize("changes", [PAPER, LINE], ids=["paper", "line"])
def test_every_pair_in_the_zone_carries_load_at_the_shared_approach(changes, flank):
    # At any penetration every pair in the zone of action is loaded: 3 or 4 pairs, eps_gamma
    # on average over a base pitch of roll (MODEL_NOTES section 5).
    probe = Probe(MeshParameters(**changes))
    d = probe.derived
    counts = []
    for phi_p in base_pitch_angles(probe):
        phi_w = (d["arm_pinion"] * phi_p - flank * (d["half_backlash"] + 0.1e-6)) / d[
            "arm_wheel"]
        loads = probe.loads(flank, phi_p, 0.0, phi_w, 0.0, 0.0)
        counts.append(sum(1 for r in loads.pairs if r["W"] > 0.0))
        assert all(r["offset"] == 0.0 for r in loads.pairs)
    assert min(counts) == 3 and max(counts) == 4
    assert np.mean(counts) == pytest.approx(d["eps_gamma"], abs=2e-3)
    assert d["eps_gamma"] == pytest.approx(3.03, abs=0.005)


@pytest.mark.parametrize("beta_deg", [0.0, 10.0, 27.75])
def test_contact_lines_of_the_helical_pair(beta_deg):
    # The mean total length of the contact lines is b eps_alpha / cos(beta_b) (the overlap of
    # a line's roll span w with the path, averaged over a base pitch: w eps_alpha of roll,
    # 1/sin(beta_b) of line per roll); each line at most b / cos(beta_b).
    p = MeshParameters(beta=beta_deg * math.pi / 180.0, **LINE)
    probe = Probe(p)
    d = probe.derived
    totals = []
    for phi_p in base_pitch_angles(probe):
        rows = probe.pair_laws(DRIVE, phi_p)
        assert all(0.0 < r["length"] <= p.b / math.cos(d["beta_b"]) * (1 + 1e-12)
                   for r in rows)
        assert all(d["s_start"] <= r["s"] <= d["s_end"] for r in rows)
        totals.append(sum(r["length"] for r in rows))
    assert np.mean(totals) == pytest.approx(p.b * d["eps_alpha"] / math.cos(d["beta_b"]),
                                            rel=1e-3)


def coupled_run(changes: dict, stop_time: float = 11.0, step: float = 1e-4,
                record=("GearMeshRattle.mesh.n_contact",)):
    """The paper scenario (default driveline: engine orders 2/4/6, 0.5 M*) with the mesh
    parameters changed, in the compiled co-simulation loop: time and the recorded columns."""
    mp, dp = MeshParameters(**changes), DrivelineParameters()
    steps = round(stop_time / step)
    mesh_in, wheel = coupled_start_inputs(mp, dp)
    with MeshUnit(mp, mesh_in["pinion.phi"], mesh_in["pinion.w"], mesh_in["wheel.tau_load"],
                  mesh_in["pinion.a"]) as mesh, \
            DrivelineUnit(dp, wheel["wheel.phi"], wheel["wheel.w"]) as drive:
        run = run_coupled(mesh, drive, round(step * 1e9), steps, list(record))
    t = np.arange(steps + 1) * step
    return t, {name.split(".", 1)[1]: np.asarray(run.column_buffer(name)) for name in record}


@pytest.mark.parametrize("hertz_law", [0, 1], ids=["exact law", "eq. 2"])
def test_paper_scenario_loads_three_to_four_pairs_under_the_paper_option(hertz_law):
    # The paper scenario, 11 s at 1e-4 s; mesh.n_contact (pairs with W > 0) at every
    # communication point after the 1 s start transient where it is positive: 3 or 4 at every
    # such sample, and on average eps_gamma = 3.03 within 0.05 ("3-4 teeth pairs in
    # simultaneous impact").
    t, s = coupled_run({**PAPER, "hertz_law": hertz_law})
    n = s["mesh.n_contact"][t > 1.0]
    loaded = n[n > 0]
    assert loaded.size > 2000  # (in contact a tenth to a fifth of the time, by the dissipation)
    assert set(np.unique(loaded)) <= {3.0, 4.0}
    eps_gamma = MeshParameters().derived()["eps_gamma"]
    assert abs(np.mean(loaded) - eps_gamma) <= 0.05, np.mean(loaded)
