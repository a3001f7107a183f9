"""dissipation.c, the contact's dissipation set at each onset (docs/model.md section 3.3),
through the model library: the squeeze-film (Stokes number) impact law against the readable
equations (tests/oracle/dissipation.py) and realized by single impacts, its area on the line
contact; the mesh damping ratio's speed-independent restitution against a direct
integration and its linearized damping."""

import ctypes
import itertools
import math

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st
from scipy import integrate

from drive_rattle import COAST, DRIVE, MeshParameters, ModelError
from drive_rattle.parameters import DEG
from tests.oracle import contact, dissipation
from tests.oracle.mesh import MeshModel

from .helpers import Probe, free_parameters, restitution

SQUEEZE = {"dissipation": 3}


def squeeze_probe(probe: Probe, flank: int, phi_p: float, v: float) -> dissipation.Onset:
    """rm_probe_squeeze: (area, Stokes number, e, d, sticks)."""
    out = (ctypes.c_double * 5)()
    probe.unit.call("rm_probe_squeeze", int(flank), float(phi_p), float(v), out)
    return dissipation.Onset(out[0], out[1], out[2], out[3], out[4] == 1.0)


def critical_speed(p: MeshParameters, flank: int = DRIVE, phi_p: float = 0.0) -> float:
    m = MeshModel(p)
    return dissipation.critical_speed(m, dissipation.flank_area(m, flank, phi_p))


# ------------------------------------------------------------------ the law, against the oracle
def test_squeeze_pair_area_is_the_spheres_and_the_elongated_contacts():
    # A = R^2 for a sphere; 2 sqrt(r_x^3 r_y) for r_y >> r_x (Reynolds' squeeze film of the
    # paraboloidal gap).
    assert dissipation.pair_area(3e-3, 3e-3) == pytest.approx(9e-6, rel=1e-14)
    assert dissipation.pair_area(5e-3, 5e3) == pytest.approx(2 * math.sqrt(5e-3**3 * 5e3), rel=1e-6)


def test_squeeze_film_force_of_the_paraboloidal_gap_by_quadrature():
    # Independent of the closed form: the Reynolds pressure p = 6 eta (-dh/dt) R_e / h^2 of the
    # gap h = h0 + x^2/(2 r_x) + y^2/(2 r_y) integrated over the plane gives 6 pi eta A (-dh/dt)
    # / h0.
    r_x, r_y, h0, eta, rate = 4e-3, 0.3, 1e-6, 0.05, 1e-3
    R_e = r_x * r_y / (r_x + r_y)

    def pressure(y, x):
        h = h0 + x * x / (2 * r_x) + y * y / (2 * r_y)
        return 6 * eta * rate * R_e / (h * h)

    lx, ly = math.sqrt(2 * r_x * h0), math.sqrt(2 * r_y * h0)
    F = 4 * integrate.dblquad(
        lambda t, u: pressure(ly * math.tan(t), lx * math.tan(u)) * lx * ly
        / (math.cos(t) ** 2 * math.cos(u) ** 2), 0, math.pi / 2, 0, math.pi / 2,
        epsabs=0, epsrel=1e-10)[0]
    closed_form = 6 * math.pi * eta * dissipation.pair_area(r_x, r_y) * rate / h0
    assert F / closed_form == pytest.approx(1.0, rel=1e-7)


laws = st.fixed_dictionaries({
    "stokes_critical": st.floats(0.0, 30.0),
    "restitution_dry": st.floats(0.05, 1.0),
    "squeeze_fraction": st.floats(1e-4, 1.0),
    "eta": st.floats(1e-3, 1.0),
    "sigma": st.floats(2e-8, 2e-6),
    "crowning": st.floats(1e-6, 1e-4),
    "beta": st.one_of(st.just(0.0), st.floats(0.5 * DEG, 30 * DEG)),
})


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(changes=laws, flank=st.sampled_from([DRIVE, COAST]), phi_p=st.floats(-3.0, 3.0),
       log_v=st.floats(math.log(1e-5), math.log(1.0)))
@pytest.mark.slow
def test_the_squeeze_law_equals_the_oracle(changes, flank, phi_p, log_v):
    p = MeshParameters(**SQUEEZE, **changes)
    v = math.exp(log_v)
    got = squeeze_probe(Probe(p), flank, phi_p, v)
    want = dissipation.onset(MeshModel(p), flank, phi_p, v)
    assert got.area == pytest.approx(want.area, rel=1e-12)
    assert got.stokes == pytest.approx(want.stokes, rel=1e-12)
    assert got.restitution == pytest.approx(want.restitution, rel=1e-11, abs=1e-15)
    assert got.sticks == want.sticks
    assert got.d == pytest.approx(want.d, rel=1e-10)
    if not got.sticks:  # the factor realizes the law's e at this speed exactly
        assert contact.hunt_crossley_restitution(got.d * v) == pytest.approx(got.restitution,
                                                                            rel=1e-10)
    event("sticks" if got.sticks else "rebounds")


def test_the_squeeze_law_rises_from_zero_at_the_critical_stokes_number():
    p = MeshParameters(**SQUEEZE)
    probe = Probe(p)
    v_c = critical_speed(p)
    # the central parameters: sticking below about 2 mm/s (a starved film: phi = 0.03)
    assert 1e-3 < v_c < 4e-3
    assert squeeze_probe(probe, DRIVE, 0.0, v_c).stokes == pytest.approx(p.stokes_critical,
                                                                        rel=1e-12)
    speeds = [v_c * f for f in (0.01, 0.5, 0.999, 1.0001, 1.01, 1.5, 3, 10, 100, 1e4)]
    e = [squeeze_probe(probe, DRIVE, 0.0, v).restitution for v in speeds]
    assert e[:3] == [0.0, 0.0, 0.0] and all(x > 0.0 for x in e[3:])
    assert all(b > a for a, b in itertools.pairwise(e[2:]))
    assert e[-1] == pytest.approx(p.restitution_dry * (1 - 1e-4), rel=1e-12)
    for v, x in zip(speeds, e, strict=True):
        assert x == pytest.approx(max(0.0, p.restitution_dry * (1 - v_c / v)), rel=1e-12)


def test_no_stokes_number_below_critical_rebounds_and_the_contact_is_then_film_damped():
    p = MeshParameters(**SQUEEZE)
    probe = Probe(p)
    onset = squeeze_probe(probe, DRIVE, 0.0, 0.5 * critical_speed(p))
    assert onset.sticks and onset.d == 0.0
    # the loads of a sticking contact: Hertz plus each pair's squeeze film at the roughness
    # gap on its penetration rate
    m = MeshModel(p)
    d = probe.derived
    phi_w = m.wheel_angle(DRIVE, 0.0, 0.1e-6)
    rate = 1e-4  # [m/s] into the flank
    loads = probe.loads(DRIVE, 0.0, 0.0, phi_w, -rate / d["arm_wheel"], 1e-4)
    static = probe.loads(DRIVE, 0.0, 0.0, phi_w, 0.0, 1e-4)
    touching = [r for r in loads.pairs if r["delta"] > 0.0]
    assert touching
    film = sum(dissipation.film_damping(m, r["r_x"], m.law.r_y, pen=r["delta"])  # crowned
               for r in touching)
    assert pytest.approx(film * rate, rel=1e-12) == loads.W - static.W


def test_line_contact_squeeze_film_is_the_cylinders():
    # The squeeze-film law on the line contact: the area it uses is the cylinder's
    # sqrt(2) L R^(3/2) / (St_c sqrt(sigma)) per pair (the oracle's, within 1e-12), so its
    # critical speed 6 pi eta phi A St_c / m_n does not depend on St_c.
    speeds = []
    for st_c in (5.0, 10.0, 20.0):
        p = MeshParameters(contact_geometry=2, stokes_critical=st_c)
        probe = Probe(p)
        m = MeshModel(p)
        onset = squeeze_probe(probe, DRIVE, 0.0, 1e-3)
        assert onset.area == pytest.approx(dissipation.flank_area(m, DRIVE, 0.0), rel=1e-12)
        assert onset.area > 0.0
        speeds.append(dissipation.critical_speed(m, onset.area))
    assert speeds[0] == pytest.approx(speeds[1], rel=1e-12) == pytest.approx(speeds[2],
                                                                               rel=1e-12)


# ------------------------------------------------------------------ realized by single impacts
@pytest.mark.parametrize("flank", [DRIVE, COAST])
def test_single_impacts_realize_the_squeeze_law(flank):
    # The wheel against a pinion at rest: e(v) from 0.3 of the critical speed to 100 mm/s is
    # the law's within 1e-4 (the integration), zero below the critical speed, and rises.
    p = MeshParameters(**SQUEEZE)
    probe = Probe(p)
    v_c = critical_speed(p, flank)
    speeds = [0.3 * v_c, 0.9 * v_c, 1.05 * v_c, 1.5 * v_c, 3 * v_c, 10e-3, 30e-3, 100e-3]
    measured = [restitution(v, flank, **SQUEEZE) for v in speeds]
    for v, e in zip(speeds, measured, strict=True):
        assert e == pytest.approx(squeeze_probe(probe, flank, 0.0, v).restitution, abs=1e-4)
    assert measured[:2] == [0.0, 0.0]
    assert all(b > a for a, b in itertools.pairwise(measured[1:]))


@settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck))
@given(changes=laws, log_v=st.floats(math.log(1e-4), math.log(0.3)),
       flank=st.sampled_from([DRIVE, COAST]))
@pytest.mark.slow
def test_any_legal_squeeze_law_is_realized_by_its_impacts(changes, log_v, flank):
    v = math.exp(log_v)
    try:
        p = free_parameters(v, flank, **SQUEEZE, **changes)
        e = restitution(v, flank, **SQUEEZE, **changes)
    except ModelError as err:  # beyond the contact's validity or resolution
        assert "beyond the validity" in str(err) or "too stiff" in str(err)
        event("refused")
        return
    law = dissipation.onset(MeshModel(p), flank, 0.0, v)
    if law.sticks:
        assert e == 0.0
    else:
        assert e == pytest.approx(law.restitution, abs=1e-3)
    event("sticks" if law.sticks else "rebounds")


# ------------------------------------------------------------------ mesh damping ratio
def ratio_restitution(zeta: float) -> float:
    """Restitution of m x'' = -K x^(3/2) - 2 zeta sqrt(m k(x)) x', k = 3/2 K x^(1/2), with
    m = K = 1 and v = 1 (any m, K and v: the ratio makes it dimensionless), by direct
    integration until the force vanishes (the flanks do not pull)."""
    c = 2 * zeta * math.sqrt(1.5)

    def force(x, u):
        return max(x, 0.0) ** 1.5 + c * max(x, 0.0) ** 0.25 * u

    def rhs(t, y):
        return [y[1], -max(force(y[0], y[1]), 0.0)]

    def release(t, y):
        return y[0] if y[1] >= 0 else force(y[0], y[1]) if y[0] > 0 else y[0]
    release.terminal, release.direction = True, -1
    sol = integrate.solve_ivp(rhs, (0.0, 100.0), [0.0, 1.0], rtol=1e-11, atol=1e-13,
                              events=release, first_step=1e-7, method="DOP853")
    return -sol.y_events[0][0][1]


@pytest.mark.parametrize("zeta", [0.03, 0.05, 0.1])
def test_the_mesh_damping_ratio_gives_a_speed_independent_restitution(zeta):
    # A single pair (spur, pinion at rest; penetrations far below the next pair's crown
    # offset) on the Hertz law (rigid teeth: with the teeth in series the law is no power law
    # and e varies with the speed): the same e at 0.5-50 mm/s, that of the dimensionless
    # integration -- within 2.5e-3 at the default solver.h_max (the damping force
    # ~ delta^(1/4) delta' is not smooth at the onset, which costs RK4 its order there), 1e-4
    # at 0.5 us.
    exact = ratio_restitution(zeta)
    changes = {"dissipation": 4, "damping_ratio": zeta, "beta": 0.0, "tooth_compliance": 0}
    for h_max, tol in ((1e-5, 2.5e-3), (5e-7, 1e-4)):
        e = [restitution(v, **changes, h_max=h_max) for v in (0.5e-3, 4e-3, 50e-3)]
        assert max(abs(x - exact) for x in e) < tol, (h_max, e, exact)


@pytest.mark.parametrize("teeth", [0, 1], ids=["rigid teeth", "teeth in series"])
def test_the_mesh_damping_ratio_is_zeta_of_the_linearized_contact(teeth):
    # Small oscillations about a loaded state: the damping force per unit penetration rate is
    # 2 zeta sqrt(k m_n), k = dW/d(delta) of the touching pairs (1.5 K delta^(1/2) on the
    # Hertz law; the series law's with the teeth, the oracle's).
    p = MeshParameters(dissipation=4, damping_ratio=0.07, tooth_compliance=teeth)
    probe, m = Probe(p), MeshModel(p)
    d = probe.derived
    laws = {pl.slot: pl for pl in m.pair_laws(DRIVE, 0.0)}
    for delta in (0.05e-6, 0.3e-6, 2e-6):
        phi_w = m.wheel_angle(DRIVE, 0.0, delta)
        rate = 1e-5
        moving = probe.loads(DRIVE, 0.0, 0.0, phi_w, -rate / d["arm_wheel"], 0.0)
        static = probe.loads(DRIVE, 0.0, 0.0, phi_w, 0.0, 0.0)
        k = sum(m.approach.stiffness(r["K"], 0.0, r["delta"], laws[r["slot"]].c_t)
                for r in static.pairs if r["delta"] > 0)
        if not teeth:
            assert k == pytest.approx(sum(1.5 * r["K"] * math.sqrt(r["delta"])
                                          for r in static.pairs if r["delta"] > 0), rel=1e-14)
        c = (moving.W - static.W) / rate
        assert c == pytest.approx(2 * 0.07 * math.sqrt(k * d["normal_mass"]), rel=1e-9)
