"""The teeth's compliance in series with each pair's contact law (compliance.c, contact.c's
series law; docs/model.md section 3.7): the two springs' closed forms, a single impact
against the series law's quadrature, ISO 6336-1's mesh stiffness, the readable equations of
tests/oracle/compliance.py, and the model with rigid teeth unchanged bit for bit."""

from __future__ import annotations

import csv
import itertools
import math
from pathlib import Path

import numpy as np
import pytest
from scipy import integrate, optimize

from drive_rattle import COAST, DRIVE, MeshParameters, MeshUnit, ModelError
from drive_rattle.parameters import DEG, DrivelineParameters
from drive_rattle.units import DrivelineUnit, coupled_start_inputs, run_coupled
from drive_rattle_cosim.mesh_stiffness import (
    ISO_BAND,
    iso_mesh_stiffness,
    iso_single_stiffness,
    static_stiffness,
)
from tests.oracle.compliance import ToothCompliance
from tests.oracle.mesh import MeshModel

from .helpers import Probe, free_parameters, run_impact

DATA = Path(__file__).parent / "data"
SPUR = {"beta": 0.0, "b": 20e-3}  # no crown offsets: every pair touches at the same approach
PAPER_AS_PRINTED = {"contact_geometry": 1, "tooth_compliance": 0}
#: Parameter sets of the oracle comparison: the defaults, each contact geometry and
#: roughness, a spur pair, another helical pair, and a wheel body near the fit's ends.
SETS = {
    "defaults": {},
    "paper": {"contact_geometry": 1, "tooth_compliance": 1},
    "line": {"contact_geometry": 2},
    "rough": {"roughness": 1},
    "spur": SPUR,
    "30/45 teeth, 25 deg": {"z_pinion": 30, "z_wheel": 45, "alpha_n": 25 * DEG, "beta": 0.3,
                            "body_ratio_pinion": 1.4, "body_ratio_wheel": 7.0},
    "18/80 teeth, pointed tip": {"z_pinion": 18, "z_wheel": 80, "m_n": 5e-3,
                                 "alpha_n": 25 * DEG, "addendum": 1.2},
}


def close(a: float, b: float, rel: float) -> bool:
    return a == b or abs(a - b) <= rel * abs(b)


# ------------------------------------------------------------------ ISO 6336-1
def test_iso_stiffness_of_the_reference_pair_is_the_hand_values():
    # ISO 6336-1 method B by hand (MODEL_NOTES section 6): z_n = 27.95 and 54.50,
    # q' = 0.04723 + 0.15551/27.95 + 0.25791/54.50 = 0.05753, c' = 0.8 cos(27.75 deg)/q'
    # = 12.3 and c_gamma_alpha = c' (0.75 * 1.3846 + 0.25) = 15.9 N/(mm um): 3.96e8 N/m.
    p = MeshParameters()
    assert iso_single_stiffness(p) == pytest.approx(12.31, abs=0.005)
    assert iso_mesh_stiffness(p) / (1e9 * p.b) == pytest.approx(15.86, abs=0.005)
    assert iso_mesh_stiffness(p) == pytest.approx(3.965e8, rel=1e-3)


@pytest.mark.parametrize("load", [100.0, 200.0])
@pytest.mark.parametrize("changes", [{}, PAPER_AS_PRINTED, {"contact_geometry": 2}],
                         ids=["crowned", "paper as printed", "line"])
def test_static_mesh_stiffness_is_isos_where_iso_holds(changes, load):
    # Through the unit (two static equilibria 1 % apart at 8 pinion angles over a base
    # pitch): within 0.6-1.5 of c_gamma_alpha b at 100 and 200 N/mm, each contact at its
    # defaults (the paper's model as printed: rigid teeth).  With rigid teeth the crowned and
    # the line contact were 2.4-3.2 and 2.7-2.9 times ISO's.
    p = MeshParameters(**changes)
    ratio = static_stiffness(p, load) / iso_mesh_stiffness(p)
    assert ISO_BAND[0] <= ratio <= ISO_BAND[1], ratio


@pytest.mark.parametrize("changes", [{}, {"contact_geometry": 2}], ids=["crowned", "line"])
def test_the_teeth_make_the_stiff_contacts_isos(changes):
    # ... where the rigid teeth were stiffer than ISO allows (the test's reason: without the
    # teeth it fails).
    rigid = MeshParameters(tooth_compliance=0, **changes)
    assert static_stiffness(rigid, 100.0) / iso_mesh_stiffness(rigid) > ISO_BAND[1]


# ------------------------------------------------------------------ the two springs
@pytest.mark.parametrize("changes", [{}, {"contact_geometry": 2}, {"roughness": 1},
                                     {"contact_geometry": 2, "roughness": 1}],
                         ids=["Hertz", "Palmgren", "Hertz, rough", "Palmgren, rough"])
def test_the_series_law_is_the_two_springs_closed_forms(changes):
    # For every pair in the zone and approaches from 1 pm to 0.1 mm (the Hertz law's tabulated
    # root and, beyond its table, Newton's method): the load W and the flanks' own approach x
    # of rm_probe_approach solve the series to rounding and satisfy the two springs -- the
    # contact's x = (W/K)^(1/p) [+ sigma (W/W_r)^q], the teeth's pen - x = c_t W -- and the
    # stiffness and energy are the series' 1/(dx/dW + c_t) and integral W dx + c_t W^2/2.
    p = MeshParameters(**changes)
    probe, a = Probe(p), MeshModel(p).approach
    rows = [r for r in probe.pair_laws(DRIVE, 0.05) if r["K"] > 0.0]
    assert rows and all(r["c_t"] > 0.0 for r in rows)
    for r in rows:
        K, W_r, c_t = r["K"], r["W_r"], r["c_t"]
        for pen in np.geomspace(1e-12, 1e-4, 25):
            W, k, energy, _, x = probe.approach(K, W_r, r["kz"], pen, c_t)
            assert abs(x + c_t * W - pen) <= 1e-14 * pen  # the series solved to rounding
            bulk, layer = a.flanks(K, W_r, W)
            assert close(x, bulk + layer, 1e-12), (pen, x, bulk + layer)
            # (the teeth's share to 1e-9, or to pen's rounding where it is below it)
            assert close(pen - x, c_t * W, 1e-9) or abs(pen - x - c_t * W) < 1e-14 * pen
            dx = bulk / (a.exponent * W) + (a.rough_exponent * layer / W if a.rough else 0.0)
            assert close(k, 1.0 / (dx + c_t), 1e-10)
            contact = W * bulk / (a.exponent + 1.0) + (
                W * layer * a.rough_exponent / (a.rough_exponent + 1.0) if a.rough else 0.0)
            assert close(energy, contact + 0.5 * c_t * W * W, 1e-10)


def test_a_statically_loaded_pair_deflects_as_the_two_springs():
    # The unit in its static equilibrium under load, spur pair: the pairs share the approach
    # delta, each carries W_i with delta = (W_i / K_i)^(2/3) + c_t,i W_i, and the loads balance
    # the torque.
    p = MeshParameters(friction_enabled=False, **SPUR)
    probe = Probe(p)
    d = probe.derived
    laws = {r["slot"]: r for r in probe.pair_laws(DRIVE, 0.01)}
    for torque in (0.0833, 5.0, 100.0):
        with MeshUnit(p, 0.01, 0.0, torque) as unit:
            phi_w = unit.wheel()[0]
        loads = probe.loads(DRIVE, 0.01, 0.0, phi_w, 0.0, 0.0)
        loaded = [r for r in loads.pairs if r["W"] > 0.0]
        assert len(loaded) >= 1
        for r in loaded:
            K, c_t = laws[r["slot"]]["K"], laws[r["slot"]]["c_t"]
            series = (r["W"] / K) ** (2.0 / 3.0) + c_t * r["W"]
            assert series == pytest.approx(r["delta"], rel=1e-12)
            assert c_t * r["W"] > 0.01 * r["delta"]  # the teeth take a share
        assert sum(r["W"] for r in loaded) * d["arm_wheel"] == pytest.approx(torque, rel=1e-9)


# ------------------------------------------------------------------ a single impact
def series_impact(model: MeshModel, flank: int, v: float):
    """The undamped impact of the wheel's normal mass on the pairs of ``flank`` at the pinion
    angle 0, from the energy balance 1/2 m (v^2 - u^2) = E(delta) (E the pairs' elastic energy,
    each pair's series law): (delta_max, W_max, contact duration
    2 integral_0^delta_max d(delta) / u, by quadrature with delta = delta_max (1 - s^2), which
    takes the integrand's 1/sqrt at the turning point out)."""
    m = model.normal_mass

    def energy(delta):
        return model.elastic_energy(flank, 0.0, delta)

    e0 = 0.5 * m * v * v
    hi = 1e-9
    while energy(hi) < e0:
        hi *= 2.0
    d_max = optimize.brentq(lambda x: energy(x) - e0, 0.0, hi, xtol=1e-22, rtol=1e-15)

    def integrand(s):
        delta = d_max * (1.0 - s * s)
        u2 = v * v - 2.0 * energy(delta) / m
        if s > 0.0:
            return 2.0 * d_max * s / math.sqrt(max(u2, 0.0))
        # s -> 0: u^2 -> 2 W(delta_max) delta_max s^2 / m
        return 2.0 * d_max / math.sqrt(2.0 * model.static_force(flank, 0.0, d_max) * d_max / m)

    half, _ = integrate.quad(integrand, 0.0, 1.0, epsabs=0.0, epsrel=1e-12, limit=200)
    return d_max, model.static_force(flank, 0.0, d_max), 2.0 * half


@pytest.mark.parametrize("flank", [DRIVE, COAST])
@pytest.mark.parametrize("v", [1e-3, 4e-3, 0.05])
def test_single_undamped_impact_matches_the_series_laws_quadrature(flank, v):
    # Spur pair, friction and dissipation off, pinion at rest, the teeth in series: peak
    # penetration, peak load, contact duration and rebound as the energy balance of the series
    # law gives them (the same tolerances as the Hertz law's closed form); and the teeth make
    # the impact softer and longer than the rigid teeth's.
    p = free_parameters(v, flank, dissipation=0, **SPUR)
    oracle = MeshModel(p)
    d_max, W_max, t_c = series_impact(oracle, flank, v)
    events, d_peak, W_peak = run_impact(MeshUnit(p, 0.0, 0.0, 0.0))
    (t_on, on), (t_off, off) = events
    assert (on.kind, off.kind) == ("onset", "release")
    assert d_peak == pytest.approx(d_max, rel=1e-4)
    assert W_peak == pytest.approx(W_max, rel=1e-4)
    assert t_off - t_on == pytest.approx(t_c, rel=1e-4)
    assert -off.speed == pytest.approx(v, rel=1e-4)
    rigid = series_impact(MeshModel(free_parameters(v, flank, dissipation=0,
                                                     tooth_compliance=0, **SPUR)), flank, v)
    assert W_max < rigid[1] and t_c > rigid[2]


def test_the_series_quadrature_is_the_hertz_closed_form_with_rigid_teeth():
    # The quadrature of series_impact itself, on the Hertz law alone: t_c = 2.9432 delta_max/v.
    from tests.oracle import contact

    v = 4e-3
    model = MeshModel(free_parameters(v, DRIVE, dissipation=0, tooth_compliance=0, **SPUR))
    ref = contact.hertz_impact(model.normal_mass, model.stiffness_sum(DRIVE, 0.0), v)
    d_max, W_max, t_c = series_impact(model, DRIVE, v)
    assert (d_max, W_max, t_c) == pytest.approx((ref.delta_max, ref.W_max, ref.t_contact),
                                                rel=1e-9)


# ------------------------------------------------------------------ the oracle
@pytest.mark.parametrize("changes", SETS.values(), ids=SETS)
def test_the_teeth_compliance_equals_the_oracle(changes):
    # Every pair's c_t (rm_probe_pair_laws) against the oracle's at random pinion angles, and
    # the tabulated q(s) against the oracle's quadratures within the fit's 1e-10.
    p = MeshParameters(**changes)
    probe, m = Probe(p), MeshModel(p)
    assert probe.derived["tooth_stiffness_pitch"] == pytest.approx(1.0 / m.tooth.pitch,
                                                                   rel=1e-12)
    rng = np.random.default_rng(5)
    for phi in rng.uniform(-3.0, 3.0, 60):
        for flank in (DRIVE, COAST):
            got, want = probe.pair_laws(flank, phi), m.pair_laws(flank, phi)
            assert [r["slot"] for r in got] == [w.slot for w in want]
            for r, w in zip(got, want, strict=True):
                assert close(r["length"], w.length, 1e-13)
                assert close(r["c_t"], w.c_t, 1e-12), (phi, r["c_t"], w.c_t)
                if r["length"] > 0.0:
                    assert close(r["c_t"] * r["length"], m.tooth.exact(r["s"]), 1e-10)


def test_the_oracles_quadrature_is_scipys(monkeypatch):
    # The oracle's adaptive Gauss-Kronrod quadrature of the teeth's beam integrals against
    # scipy's QUADPACK, from the root to the tips.
    from tests.oracle import compliance as oracle

    m = MeshModel(MeshParameters())
    loads = [(m.tooth.pinion, rho) for rho in (4.9e-3, 10.75e-3, 16.2e-3)] + [
        (m.tooth.wheel, rho) for rho in (15.6e-3, 20e-3, 26.5e-3)]  # (normal roll lengths)
    ours = [t.parts(rho)[0] for t, rho in loads]
    monkeypatch.setattr(oracle, "integrate", lambda f, a, b: integrate.quad(
        f, a, b, epsabs=0.0, epsrel=1e-12, limit=200)[0])
    theirs = [t.parts(rho)[0] for t, rho in loads]
    assert ours == pytest.approx(theirs, rel=1e-11)


def test_the_pair_compliance_is_both_teeth_over_the_engaged_line():
    # c_t = (q_pinion + q_wheel) / L_n: a pair's teeth are twice as stiff over twice the line,
    # on equal bodies the wheel's tooth is stiffer than the pinion's at the pitch point (more
    # teeth), and crowned pairs carry their engaged contact line's length like the paper's.
    p = MeshParameters(body_ratio_pinion=2.0, body_ratio_wheel=2.0)
    m = MeshModel(p)
    g, t = m.geometry, m.tooth
    s = g.s_pitch
    q_p = t.pinion.compliance(s / g.normal_factor)
    q_w = t.wheel.compliance((g.line_length - s) / g.normal_factor)
    assert t.exact(s) == pytest.approx(q_p + q_w, rel=1e-15)
    assert q_w < q_p
    assert t.pair(s, 0.02) == pytest.approx(2.0 * t.pair(s, 0.04), rel=1e-15)
    probe = Probe(p)
    paper = Probe(MeshParameters(contact_geometry=1))
    for phi in (0.0, 0.05, 0.1):
        crowned = {r["slot"]: r["length"] for r in probe.pair_laws(DRIVE, phi)}
        lines = {r["slot"]: r["length"] for r in paper.pair_laws(DRIVE, phi)}
        assert crowned == pytest.approx(lines, rel=1e-15)


def test_the_body_ratio_stiffens_thin_rims_less_than_solid_bodies():
    # Sainsot et al.'s body held at its bore: the more body between bore and root, the more it
    # gives (h = r_f / r_bore from 1.4 to 7): the teeth's stiffness at the pitch point falls.
    stiff = [MeshParameters(body_ratio_pinion=h, body_ratio_wheel=h).derived()[
        "tooth_stiffness_pitch"] for h in (1.4, 2.0, 4.0, 7.0)]
    assert all(a > b for a, b in itertools.pairwise(stiff))


def test_a_pointed_virtual_tooth_is_refused_naming_the_option():
    # A geometry whose normal-section tooth is pointed below its contact: one sentence naming
    # tooth.compliance and what is allowed; with rigid teeth the same geometry is accepted.
    changes = {"z_pinion": 10, "z_wheel": 40, "alpha_n": 30 * DEG, "addendum": 1.2,
               "beta": 0.0, "b": 10e-3}
    with pytest.raises(ModelError) as err:
        MeshParameters(**changes)
    message = str(err.value)
    assert "'tooth.compliance' = 1" in message and "pointed below its contact" in message
    assert "allowed: tooth.compliance = 0" in message
    rigid = MeshParameters(tooth_compliance=0, **changes)  # accepted
    with pytest.raises(ValueError) as oracle_err:  # and the oracle agrees
        ToothCompliance(rigid, MeshModel(rigid).geometry)
    assert "pointed below its contact" in str(oracle_err.value)


# ------------------------------------------------------------------ rigid teeth
RIGID_RUNS = {
    "crowned": ({}, "rigid_teeth_crowned.csv"),
    "paper": ({"contact_geometry": 1}, "rigid_teeth_paper.csv"),
    "line, rough": ({"contact_geometry": 2, "roughness": 1}, "rigid_teeth_line_rough.csv"),
}


@pytest.mark.parametrize("case", RIGID_RUNS.values(), ids=RIGID_RUNS)
def test_rigid_teeth_give_the_previous_models_numbers_bit_for_bit(case):
    # The coupled paper scenario for 1 s with tooth.compliance = 0 against the doubles the
    # model before the teeth's compliance (commit 89268b2) gave, every 25 ms.
    changes, name = case
    with open(DATA / name, newline="") as f:
        rows = list(csv.reader(f))
    header, want = rows[0], [[float(x) for x in r] for r in rows[1:]]
    mp, dp = MeshParameters(tooth_compliance=0, **changes), DrivelineParameters()
    m_in, wheel = coupled_start_inputs(mp, dp)
    mesh = MeshUnit(mp, m_in["pinion.phi"], m_in["pinion.w"], m_in["wheel.tau_load"],
                    m_in["pinion.a"])
    drive = DrivelineUnit(dp, wheel["wheel.phi"], wheel["wheel.w"])
    names = [n if n.startswith("Driveline.") else f"GearMeshRattle.{n}" for n in header[1:]]
    run = run_coupled(mesh, drive, 100_000, 10_000, names)
    got = [[run.time[k], *(run.columns[n][k] for n in names)] for k in range(0, 10_001, 250)]
    assert got == want
