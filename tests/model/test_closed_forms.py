"""The model library's units against closed forms (MODEL_NOTES section 4): the undamped Hertz
impact, the Hunt-Crossley restitution (exact for any stiffness law and mass), the helical
geometry's textbook identities and the static load sharing of a steady drive."""

import math

import numpy as np
import pytest

from drive_rattle import COAST, DRIVE, MeshParameters, MeshUnit
from drive_rattle.parameters import DEG
from tests.oracle import hertz
from tests.oracle.mesh import MeshModel

from .helpers import (
    approach_unit,
    free_parameters,
    pinion_with_order,
    rest_step,
    restitution,
    run_impact,
)

SPUR = {"beta": 0.0, "b": 20e-3}  # no crown offsets: every pair touches at the same approach
W_PINION = 86.92  # rad/s, 830 rpm


# ------------------------------------------------------------------ single impacts
@pytest.mark.parametrize("flank", [DRIVE, COAST])
@pytest.mark.parametrize("v", [1e-3, 4e-3, 0.05])
def test_single_undamped_impact_matches_the_hertz_closed_form(flank, v):
    # Spur pair, friction and dissipation off, pinion at rest, rigid teeth (the Hertz law
    # alone; with the teeth in series: tests/model/test_compliance.py): the pairs in mesh share
    # one penetration, W = sum K_i delta^1.5 with K_i from the oracle's contact law.
    p = free_parameters(v, flank, dissipation=0, tooth_compliance=0, **SPUR)
    unit = MeshUnit(p, 0.0, 0.0, 0.0)
    oracle = MeshModel(p)
    K = oracle.stiffness_sum(flank, 0.0)
    assert K > 0.0
    ref = hertz.hertz_impact(oracle.normal_mass, K, v)
    events, d_peak, W_peak = run_impact(unit)
    (t_on, on), (t_off, off) = events
    assert (on.kind, on.flank, off.kind, off.flank) == ("onset", flank, "release", flank)
    assert on.speed == pytest.approx(v, rel=1e-12)
    # RK4 loses order next to the onset and the release, where W ~ t^(3/2); at the default
    # solver.h_max = 1e-5 s the measured errors are below 5e-5 for these speeds (the
    # convergence test below), so 1e-4 is ten times tighter than the 0.1 % asked for.
    assert d_peak == pytest.approx(ref.delta_max, rel=1e-4)
    assert W_peak == pytest.approx(ref.W_max, rel=1e-4)
    assert t_off - t_on == pytest.approx(ref.t_contact, rel=1e-4)
    assert -off.speed == pytest.approx(v, rel=1e-4)  # rebound = approach


@pytest.mark.parametrize("v", [1e-3, 4e-3, 2e-2, 0.1, 0.5])
@pytest.mark.parametrize("d", [0.0, 30.0, 300.0, 1000.0])
def test_hunt_crossley_restitution_matches_the_closed_form(d, v):
    # Helical pair with crown offsets (several pairs engage at different penetrations): the
    # restitution depends only on d v (oracle hertz.hunt_crossley_restitution).  Up to 0.5 m/s
    # and d = 1000 s/m the contact's own time scales shrink to ~1e-7 s; the substeps follow.
    e = restitution(v, dissipation=2, damping=d)
    assert e == pytest.approx(hertz.hunt_crossley_restitution(d * v), abs=1e-4)


def test_hunt_crossley_option_has_its_stated_restitution():
    p = MeshParameters(dissipation=1)
    v = p.restitution_speed
    assert p.derived()["damping"] == pytest.approx(
        hertz.hunt_crossley_factor(p.restitution, v), rel=1e-12)
    assert restitution(v, dissipation=1) == pytest.approx(p.restitution, abs=1e-4)
    # ...and it dissipates more at higher speed (Hunt-Crossley: e falls with d v), where the
    # default squeeze-film law rises (tests/model/test_dissipation.py).
    assert restitution(10 * v, dissipation=1) < p.restitution - 0.1


def test_friction_dissipates_in_an_impact():
    v = 4e-3
    e_none = restitution(v, dissipation=0)
    e_friction = restitution(v, dissipation=0, friction_enabled=True)
    assert e_none == pytest.approx(1.0, abs=1e-4)
    assert e_friction < e_none - 1e-6


def test_reference_impact_magnitudes():
    # The paper: deflection of order 1 um at impact speeds of order 4 mm/s.
    _, d_peak, _ = run_impact(approach_unit(4e-3))
    assert 0.1e-6 < d_peak < 3e-6


def test_substep_refinement_converges():
    # The W ~ delta^(3/2) onset of the Hertz law (rigid teeth) limits RK4 to about order 2.5
    # (5.7-fold per halving); where the onset falls on the substep grid makes single errors
    # erratic, so the worst rebound error over four onset phases must fall at least threefold
    # per halving of solver.h_max.
    v = 4e-3

    def worst(h):
        return max(abs(restitution(v, dissipation=0, h_max=h, gap=gap, tooth_compliance=0,
                                   **SPUR) - 1.0)
                   for gap in (13e-9, 20e-9, 29e-9, 37e-9))

    errs = [worst(h) for h in (1e-5, 5e-6, 2.5e-6)]
    assert errs[1] < errs[0] / 3 and errs[2] < errs[1] / 3


def test_free_wheel_crosses_the_backlash_and_hits_both_flanks():
    # Pinion at rest, the wheel drifting forward at 0.05 rad/s without friction or dissipation.
    p = MeshParameters(init_in_contact=False, friction_enabled=False, w_start=0.05,
                       dissipation=0)
    unit = MeshUnit(p, 0.0, 0.0, 0.0)
    events = []
    for k in range(2000):
        events += [(k * 1e-4 + e.time, e) for e in rest_step(unit, 1e-4).events]
    onsets = [(t, e) for t, e in events if e.kind == "onset"]
    # Moving forward, the wheel closes the coast flank first, rebounds to the drive flank...
    assert [e.flank for _, e in onsets[:4]] == [COAST, DRIVE, COAST, DRIVE]
    # ...with the approach speed conserved.
    v0 = 0.05 * p.derived()["arm_wheel"]
    for _, e in onsets:
        assert e.speed == pytest.approx(v0, rel=1e-4)
    # Between onsets on opposite flanks: the backlash crossing plus the contact duration.
    assert onsets[1][0] - onsets[0][0] > p.backlash / v0
    out = unit.outputs()
    assert out["mesh.impacts_coast"] >= 2 and out["mesh.impacts_drive"] >= 2


# ------------------------------------------------------------------ geometry identities
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


def test_effective_modulus_steel_on_steel():
    assert MeshParameters().derived()["E_star"] == pytest.approx(115.385e9, rel=1e-5)


# ------------------------------------------------------------------ static load sharing
@pytest.mark.parametrize("load", [0.02, 0.15, 1.0, -0.3])
@pytest.mark.parametrize("friction", [False, True])
def test_static_load_sharing_of_the_start(load, friction):
    # init.in_contact: the wheel at the rigid ratio, in the flank equilibrium for the load --
    # sum W_i arm_w = load without friction, the mesh torque (friction included) = load with,
    # at the penetration the oracle's equilibrium finds.
    p = MeshParameters(friction_enabled=friction)
    g = p.derived()
    phi_p = 0.3
    unit = MeshUnit(p, phi_p, W_PINION, load)
    out = unit.outputs()
    flank = DRIVE if load > 0 else COAST
    assert out["wheel.w"] == W_PINION * g["ratio"]
    assert out["mesh.n_contact"] >= 1
    W = sum(out[f"pair[{k}].W"] for k in range(8))
    assert pytest.approx(out["mesh.W"], rel=1e-14) == W
    if not friction:
        assert flank * W * g["arm_wheel"] == pytest.approx(load, rel=1e-9)
        assert out["mesh.F"] == 0.0
    oracle = MeshModel(p)
    delta = oracle.equilibrium_penetration(phi_p, W_PINION, load)
    assert out["mesh.delta"] == pytest.approx(delta, rel=1e-9)
    loads = oracle.loads(flank, phi_p, W_PINION, out["wheel.phi"], out["wheel.w"], 0.0)
    assert loads.tau_wheel == pytest.approx(load, rel=1e-9)
    assert pytest.approx(out["mesh.W"], rel=1e-9) == loads.W


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


@pytest.mark.parametrize("amp, expect_coast", [(0.0, False), (2000.0, True)])
def test_speed_fluctuation_produces_coast_impacts(amp, expect_coast):
    load, H = 0.2, 1e-4
    k0 = pinion_with_order(0.0, W_PINION, amp, 2 * 830 / 60)
    unit = MeshUnit(MeshParameters(), k0[0], k0[1], load)
    for k in range(1500):
        unit.step(H, *pinion_with_order(k * H, W_PINION, amp, 2 * 830 / 60), load)
    out = unit.outputs()
    assert (out["mesh.impacts_coast"] > 0) == expect_coast
    if expect_coast:
        assert out["mesh.impacts_drive"] > 0 and out["mesh.v_impact"] > 0
