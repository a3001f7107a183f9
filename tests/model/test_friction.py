"""friction.c, the regime of lubrication and the flank friction (paper eq. 11-17, docs/model.md
section 4), against the oracle's friction.py: the default boundary coefficient, the friction
forms' limits and continuity, the friction's direction at the pitch point and its torque,
Barus' viscosity with a limiting shear stress, Hamrock and Dowson's EHL film; friction's
dissipation in an impact; and the oracle's regime and film against their definitions."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drive_rattle import COAST, DRIVE, MeshParameters, MeshUnit
from tests.oracle import friction
from tests.oracle.mesh import MeshModel

from .helpers import Probe, restitution


# ------------------------------------------------------------------ the oracle itself
def test_dry_fraction_is_linear_between_the_limits():
    lams = np.linspace(0.0, 5.0, 501)
    psis = np.array([friction.dry_fraction(x) for x in lams])
    assert np.allclose(psis, np.clip((3.0 - lams) / 2.0, 0.0, 1.0), rtol=0, atol=1e-15)


def test_film_thickness_eq11():
    assert friction.film_thickness(1e-6, 2e-8) == pytest.approx(1.02e-6)
    assert friction.film_thickness(-1e-8, 2e-8) == pytest.approx(1e-8)
    assert friction.film_thickness(-3e-8, 2e-8) == 0.0


def test_bad_arguments_are_refused():
    with pytest.raises(ValueError, match="friction form 7"):
        friction.friction_force(7, 1.0, 1.0, 1.0, 1.0, 1.0)
    with pytest.raises(ValueError, match="viscous law 2"):
        friction.viscous_stress(2, 1.0, 0.0, 1.0, 0.0, 1.0, 1.0, 1.0)


# ----------------------------------------------------------- the friction forms, against the oracle
def pair_at_lambda(probe, lam, delta=0.05e-6, flank=DRIVE):
    """The loads of the most loaded pair at film parameter ``lam`` (set through the impact
    speed of eq. 7: h = delta_max(v) - x_i, delta_max linear in v, x_i the flanks' own
    approach: the pair's penetration less its teeth's deflection)."""
    d = probe.derived
    phi_p, w_p = 0.0, 86.92
    phi_w = (d["arm_pinion"] * phi_p - flank * (d["half_backlash"] + delta)) / d["arm_wheel"]
    w_w = w_p * d["ratio"]

    def top(v):
        loads = probe.loads(flank, phi_p, w_p, phi_w, w_w, v)
        return max(loads.pairs, key=lambda r: r["W"])

    unit = top(1.0)  # (h > 0 at 1 m/s: x_i = delta_max - h)
    surface = unit["delta_max_eq7"] - unit["h"]
    v = (lam * probe.params.sigma + surface) / unit["delta_max_eq7"]
    return top(v)


def areas(probe, row):
    """(A_e, A): the asperity area of eq. 13 and the apparent area of the contact ellipse."""
    p, E = probe.params, probe.derived["E_star"]
    A_e = 3.2 * row["W"] / E * math.sqrt(p.gamma / p.sigma)
    A = probe.contact_law(row["r_x"])[3] * row["W"] ** (2.0 / 3.0)
    return A_e, A


def test_default_boundary_friction_coefficient_is_0_1():
    row = pair_at_lambda(Probe(), 0.0)
    assert row["dry_fraction"] == 1.0
    assert row["F"] / row["W"] == pytest.approx(0.1, rel=0.01)


@pytest.mark.parametrize("form", [0, 1, 2])
@pytest.mark.parametrize("shear_speed", [0, 1])
def test_friction_forms_limits_and_continuity(form, shear_speed):
    # (rigid teeth: lambda is set to its limits exactly through the pair's penetration; with
    # the teeth the film is the flanks' own approach's, held against the oracle at random
    # states above)
    p = MeshParameters(friction_form=form, shear_speed=shear_speed, tooth_compliance=0)
    probe = Probe(p)
    for lam in (0.0, 0.3, 1.0):  # boundary: psi = 1, asperity (or apparent) shear
        row = pair_at_lambda(probe, lam)
        A_e, A = areas(probe, row)
        assert row["dry_fraction"] == 1.0
        assert row["F"] == pytest.approx((A if form == 1 else A_e) * p.tau_s, rel=1e-12)
    for lam in (3.0, 4.0, 100.0):  # full film: psi = 0, viscous shear of the film
        row = pair_at_lambda(probe, lam)
        A_e, A = areas(probe, row)
        U = row["entrainment_speed"] if shear_speed == 0 else row["sliding_speed"]
        assert row["film_parameter"] == pytest.approx(lam, rel=1e-9)
        assert row["dry_fraction"] == 0.0
        assert row["F"] == pytest.approx((A_e if form == 2 else A) * p.eta * abs(U) / row["h"],
                                         rel=1e-12)
    for lam in (1.5, 2.0, 2.9):  # mixed: psi linear between the limits
        row = pair_at_lambda(probe, lam)
        assert row["dry_fraction"] == pytest.approx((3.0 - row["film_parameter"]) / 2.0,
                                                    rel=1e-12)
    # Continuous across the regime limits: no jump beyond the smooth slope.
    for limit in (friction.LAMBDA_BOUNDARY, friction.LAMBDA_FULL_FILM):
        eps = 1e-7
        below, above = (pair_at_lambda(probe, limit + s)["F"] for s in (-eps, eps))
        slope = abs(pair_at_lambda(probe, limit + 1e-3)["F"]
                    - pair_at_lambda(probe, limit - 1e-3)["F"]) / 2e-3
        assert abs(above - below) <= 4 * eps * slope + 1e-9 * abs(below)


@pytest.mark.parametrize("flank", [DRIVE, COAST])
def test_friction_reverses_at_the_pitch_point_and_dissipates(flank):
    probe = Probe()
    d = probe.derived
    w_p = 86.92
    w_w = w_p * d["ratio"]
    seen = set()
    for phi_p in np.linspace(0.0, 2 * d["base_pitch"] / d["rb_pinion"], 201):
        # Penetrate the flank by 0.2 um.
        phi_w = (d["arm_pinion"] * phi_p - flank * (d["half_backlash"] + 0.2e-6)) / d[
            "arm_wheel"]
        loads = probe.loads(flank, phi_p, w_p, phi_w, w_w, 0.0)
        for row in loads.pairs:
            if row["W"] == 0.0 or abs(row["sliding_speed"]) < 1e-9:
                continue
            before_pitch = row["s"] < d["s_pitch"]
            # At the rigid speed ratio the wheel flank slides faster before the pitch point.
            assert (row["sliding_speed"] < 0) == before_pitch
            seen.add(before_pitch)
            assert row["F"] == pytest.approx(0.1 * row["W"], rel=0.01)  # boundary regime
        # Friction power on the pair of shafts is never positive.
        normal_w = flank * loads.W * d["arm_wheel"]
        normal_p = -flank * loads.W * d["arm_pinion"]
        power = (loads.tau_wheel - normal_w) * w_w + (loads.tau_pinion - normal_p) * w_p
        assert power <= 1e-12
    assert seen == {True, False}


def test_friction_torque_on_the_wheel_follows_the_sliding():
    on, off = Probe(), Probe(MeshParameters(friction_enabled=False))
    d = on.derived
    phi_w = -(d["half_backlash"] + 0.2e-6) / d["arm_wheel"]
    w_p = 86.92
    with_f = on.loads(DRIVE, 0.0, w_p, phi_w, w_p * d["ratio"], 0.0)
    without = off.loads(DRIVE, 0.0, w_p, phi_w, w_p * d["ratio"], 0.0)
    expected = sum(math.copysign(r["F"], r["sliding_speed"]) * (d["line_length"] - r["s"])
                   for r in with_f.pairs)
    assert with_f.tau_wheel - without.tau_wheel == pytest.approx(expected, rel=1e-12)
    assert with_f.W == without.W
    assert all(r["F"] == 0.0 for r in without.pairs)


def test_film_thickness_and_regime_of_a_penetrating_pair_at_rest():
    # eq. 11 without an impact speed: h = max(0, -delta_i) = 0 for a penetrating pair, so the
    # contact is in boundary lubrication (lambda = 0, psi = 1).
    row = pair_at_lambda(Probe(), 0.0)
    assert row["delta_max_eq7"] > 0.0
    loads = Probe().loads(DRIVE, 0.0, 0.0, -(5e-5 + 1e-7) / Probe().derived["arm_wheel"],
                          0.0, 0.0)
    for r in loads.pairs:
        if r["W"] > 0.0:
            assert (r["h"], r["film_parameter"], r["dry_fraction"]) == (0.0, 0.0, 1.0)
            assert r["delta_max_eq7"] == 0.0


def test_friction_dissipates_in_an_impact():
    v = 4e-3
    e_none = restitution(v, dissipation=0)
    e_friction = restitution(v, dissipation=0, friction_enabled=True)
    assert e_none == pytest.approx(1.0, abs=1e-4)
    assert e_friction < e_none - 1e-6


# ---------------------------------------------------- Barus' viscosity with a limiting shear stress
BARUS = {"viscous_law": 1, "shear_speed": 1}


@pytest.mark.parametrize("form", [0, 1, 2])
@pytest.mark.parametrize("lam", [1.5, 2.5, 3.0, 5.0])
def test_barus_friction_equals_the_oracle(form, lam):
    p = MeshParameters(friction_form=form, **BARUS)
    probe = Probe(p)
    row = pair_at_lambda(probe, lam)
    A_e, A = areas(probe, row)
    tau = friction.viscous_stress(1, p.eta, p.alpha_pv, p.tau_limit_0, p.tau_limit_slope,
                                     row["W"] / A, row["sliding_speed"], row["h"])
    assert row["dry_fraction"] < 1.0
    assert row["F"] == pytest.approx(
        friction.friction_force(form, row["dry_fraction"], A_e, A, p.tau_s, tau), rel=1e-12)


def test_barus_friction_tends_to_the_isoviscous_one_and_is_bounded_by_the_limiting_shear():
    # alpha -> 0 with the limiting shear stress out of reach: eta |U| / h of the paper (form 0,
    # full film, sliding speed); with the default alpha the film is exp(alpha p) more viscous
    # (about 3-20 at these loads) and at a high shear rate its stress is the limiting shear
    # stress tau_L0 + gamma_L p.
    for delta in (0.05e-6, 0.3e-6):
        iso = Probe(MeshParameters(shear_speed=1))
        limitless = Probe(MeshParameters(alpha_pv=0.0, tau_limit_0=1e12, **BARUS))
        barus = Probe(MeshParameters(**BARUS))
        thick = Probe(MeshParameters(eta=1000.0, **BARUS))
        for lam in (3.0, 6.0):
            a, b = pair_at_lambda(iso, lam, delta), pair_at_lambda(limitless, lam, delta)
            assert b["F"] == pytest.approx(a["F"], rel=1e-6)
            row = pair_at_lambda(barus, lam, delta)
            p = row["W"] / areas(barus, row)[1]
            piezo = math.exp(barus.params.alpha_pv * p)
            assert 3.0 < piezo < 30.0
            assert 0.9 * piezo * a["F"] < row["F"] < piezo * a["F"]
            row = pair_at_lambda(thick, lam, delta)
            A = areas(thick, row)[1]
            tau_L = thick.params.tau_limit_0 + thick.params.tau_limit_slope * row["W"] / A
            assert 0.999 * A * tau_L < row["F"] <= A * tau_L


@settings(max_examples=200, deadline=None)
@given(alpha=st.floats(0.0, 1e-7), tau0=st.floats(1e3, 1e12), slope=st.floats(0.0, 1.0),
       p=st.floats(0.0, 1e10),
       U=st.one_of(st.just(0.0), st.floats(1e-9, 10.0), st.floats(-10.0, -1e-9)),
       h=st.floats(1e-9, 1e-4),
       eta=st.floats(1e-5, 1e3))
def test_the_limited_shear_stress_is_bounded_and_below_the_newtonian(alpha, tau0, slope, p, U,
                                                                      h, eta):
    tau = friction.viscous_stress(1, eta, alpha, tau0, slope, p, U, h)
    newtonian = eta * math.exp(min(alpha * p, 700.0)) * abs(U) / h
    assert 0.0 <= tau <= tau0 + slope * p
    assert tau <= newtonian * (1 + 1e-12)


# ------------------------------------------------------------------ the elastohydrodynamic film
def steady_drive_pairs(probe: Probe, load: float = 0.0833):
    """The loaded pairs of the drive flank at the static equilibrium for ``load`` [N.m]
    (rigid speed ratio, 830 rpm) over one base pitch of roll."""

    d = probe.derived
    rows = []
    for phi_p in [k * d["base_pitch"] / d["rb_pinion"] / 20 for k in range(20)]:
        unit = MeshUnit(probe.params, phi_p, 86.92, load)
        out = unit.outputs()
        unit.close()
        loads = probe.loads(DRIVE, phi_p, 86.92, out["wheel.phi"], out["wheel.w"], 0.0)
        rows += [r for r in loads.pairs if r["W"] > 0.0]
    return rows


def test_the_ehl_film_is_hamrock_and_dowsons_and_reaches_the_mixed_regime():
    # In steady drive at the scenario's load the eq. 11 film is zero (the pairs penetrate)
    # while the entrainment builds an EHL film of 0.3-0.5 um: with the default 0.4 um
    # roughness about the boundary of the mixed regime, partly in it.
    p = MeshParameters(film=1, viscous_law=1, shear_speed=1)
    probe, m = Probe(p), MeshModel(p)
    paper = steady_drive_pairs(Probe(MeshParameters()))
    rows = steady_drive_pairs(probe)
    assert all(r["h"] == 0.0 and r["dry_fraction"] == 1.0 for r in paper)
    for r in rows:
        assert r["h"] == pytest.approx(friction.central_film_thickness(
            r["entrainment_speed"], r["W"], r["r_x"], m.geometry.r_y, m.E_star, p.eta,
            p.alpha_pv), rel=1e-12)
    lam = [r["film_parameter"] for r in rows]
    assert min(r["h"] for r in rows) > 0.2e-6 and max(r["h"] for r in rows) < 0.6e-6
    assert min(lam) < 1.0 < max(lam)
    mixed = [r for r in rows if r["dry_fraction"] < 1.0]
    assert mixed and all(r["F"] < 0.1 * r["W"] for r in mixed)  # the film carries part
    # no piezoviscosity, no EHL film (G = 0): the paper's eq. 11
    flat = steady_drive_pairs(Probe(MeshParameters(film=1, alpha_pv=0.0)))
    assert all(r["h"] == 0.0 for r in flat)
