"""Property-based tests (hypothesis) over parameters and inputs: the slave never raises and
accepted runs stay finite and within the contact's validity; the model library's free wheel
creates no energy (its loads probed through rm_probe_loads, the contact time from the
readable Hertz equations of tests/oracle)."""

import ctypes
import math

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from drive_rattle import COAST, DRIVE, MeshParameters, MeshUnit
from drive_rattle.parameters import DEG

from ..fmi.slave_driver import Driven, GearMeshRattle
from ..oracle import contact

ERROR = 3
SETTINGS = settings(max_examples=80, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])

# Parameter values drawn around and beyond their ranges: invalid sets must be refused cleanly.
parameters = st.fixed_dictionaries({}, optional={
    "gear.backlash": st.floats(-1e-4, 6e-3),
    "wheel.J": st.floats(-1e-3, 1e-1),
    "gear.beta": st.floats(-0.1, 50 * DEG),
    "gear.b": st.floats(1e-3, 0.3),
    "gear.z_pinion": st.integers(3, 120),
    "gear.z_wheel": st.integers(3, 120),
    "contact.crowning": st.floats(1e-7, 2e-3),
    "contact.hertz_law": st.integers(0, 2),
    "contact.dissipation": st.integers(0, 3),
    "contact.restitution": st.floats(0.0, 1.2),
    "contact.damping": st.floats(0.0, 100.0),
    "friction.enabled": st.booleans(),
    "friction.form": st.integers(0, 2),
    "friction.shear_speed": st.integers(0, 1),
    "surface.sigma": st.floats(1e-8, 1e-5),
    "init.in_contact": st.booleans(),
    "wheel.w_start": st.floats(-50.0, 50.0),
    "solver.h_max": st.floats(1e-6, 1e-4),
})
input_series = st.lists(
    st.tuples(st.floats(-300.0, 300.0), st.floats(-2e4, 2e4), st.floats(-20.0, 20.0)),
    min_size=1, max_size=25)


@SETTINGS
@given(params=parameters, series=input_series,
       h=st.sampled_from([1e-5, 3e-5, 1e-4, 2.5e-4, 1e-3]))
def test_slave_never_raises_and_accepted_runs_stay_finite(params, series, h):
    m = Driven(GearMeshRattle)
    m.slave.setup_experiment(0.0)
    m.slave.enter_initialization_mode()
    w0 = series[0][0]
    m.set_named({**params, "pinion.w": w0, "wheel.tau_load": series[0][2]})
    if not params.get("init.in_contact", True):  # a start angle within the backlash
        m.set_named({"wheel.phi_start": 0.0})
    m.slave.exit_initialization_mode()
    code, msg = m.status()
    assert code in (0, ERROR)
    if code:
        assert "allowed" in msg or "equilibrium" in msg, msg
        return
    # the Hertz contact's validity limit on the penetration (the library's, for these values)
    limit = MeshParameters.from_public(params).derived()["penetration_limit"]
    phi, t = 0.0, 0.0
    for k, (w, a, tau) in enumerate(series):
        m.set_named({"pinion.phi": phi, "pinion.w": w, "pinion.a": a, "wheel.tau_load": tau})
        record_before = m.state()
        m.slave.do_step(t, h)
        code, msg = m.status()
        assert code in (0, ERROR), msg
        if code:  # refused with a clean reason, nothing changed
            assert "diverged" in msg or "allowed" in msg or "too stiff to resolve" in msg, msg
            assert m.state() == record_before
            break
        t = (k + 1) * h
        # The pinion moves on consistently with its speed (as a driveline would move it).
        phi += w * h + 0.5 * a * h * h
        for v in m.slave.public_variables:
            if v.causality.name == "output":
                assert math.isfinite(m.get(v.name)), v.name
        # Bounded penetration: accepted steps stay within the Hertz validity limit.
        assert 0.0 <= m.get("mesh.delta_peak") <= limit
        assert 0.0 <= m.get("mesh.delta") <= limit


def _loads(unit: MeshUnit, flank: int, phi_p: float, phi_w: float, w_w: float = 0.0):
    """The library's loads on ``flank`` (rm_probe_loads): totals (delta, ...) and, per pair in
    contact, (slot, s, offset, r_x, K, delta, W, ...)."""
    totals = (ctypes.c_double * 5)()
    pairs = (ctypes.c_double * (14 * 16))()
    n = ctypes.c_size_t()
    assert unit._lib.rm_probe_loads(unit._ptr, flank, phi_p, 0.0, phi_w, w_w, 0.0, totals,
                                    pairs, 16, ctypes.byref(n)) == 0
    return list(totals), [pairs[14 * k:14 * k + 14] for k in range(n.value)]


def _energy(unit: MeshUnit, phi_p: float) -> float:
    """Kinetic energy of the wheel plus the elastic energy of the flank in contact (J), pinion
    at rest: U = 2/5 sum K_i delta_i^(5/2) over the pairs in contact."""
    phi_w, w_w = unit.wheel()
    e = 0.5 * unit.get(["wheel.J"])["wheel.J"] * w_w**2
    for flank in (DRIVE, COAST):
        for pair in _loads(unit, flank, phi_p, phi_w)[1]:
            e += 0.4 * pair[4] * max(pair[5], 0.0) ** 2.5
    return e


def _first_contact_stiffness(unit: MeshUnit, flank: int, phi_p: float) -> float:
    """Sum of K of the pairs that touch first on ``flank`` (zero crown offset): the wheel put
    just past the flank's contact (the penetration is linear in the wheel angle)."""
    d0 = _loads(unit, flank, phi_p, 0.0)[0][0]
    slope = _loads(unit, flank, phi_p, 1e-3)[0][0] - d0
    phi_w = (1e-9 - d0) / slope * 1e-3  # penetration 1 nm
    return sum(p[4] for p in _loads(unit, flank, phi_p, phi_w)[1] if p[2] == 0.0)


@SETTINGS
@given(phi_p=st.floats(-10.0, 10.0), w0=st.floats(0.01, 5.0), backlash=st.floats(1e-5, 5e-4),
       J=st.floats(1e-4, 1e-2), crowning=st.floats(1e-6, 1e-4), h=st.floats(2e-5, 1e-3),
       law=st.integers(0, 1))
def test_free_wheel_creates_no_energy(phi_p, w0, backlash, J, crowning, h, law):
    """Pinion at rest, friction off, no damping, no load, rigid teeth (the Hertz law whose
    energy and onset error are below; with the teeth in series the energy is the property test
    of tests/model/test_properties.py): the wheel bounces between the flanks and its kinetic
    plus contact energy must not grow beyond the integrator's error.

    That error is set by how finely RK4 resolves a contact: with N = t_c / h_max substeps per
    contact (t_c the closed-form contact duration) the W ~ delta^(3/2) onset makes the energy
    error of one impact about C N^(-5/2).  The closed-form tests measure a rebound-speed error
    of 2e-5 at N = 20 (energy 4e-5, so C = 0.07); the bound allows twice that per impact, plus
    1e-4 of the start energy."""
    p = MeshParameters(init_in_contact=False, friction_enabled=False, dissipation=0,
                       backlash=backlash, J_wheel=J, crowning=crowning, hertz_law=law,
                       phi_start=phi_p * 20 / 39, w_start=w0, tooth_compliance=0)
    derived = p.derived()
    wheel = MeshUnit(p, phi_p, 0.0, 0.0)
    e0 = _energy(wheel, phi_p)
    # Contact duration of the pairs that touch first (zero crown offset): the shortest one.
    t_c = min(contact.hertz_impact(derived["normal_mass"],
                                 _first_contact_stiffness(wheel, f, phi_p),
                                 w0 * derived["arm_wheel"]).t_contact for f in (DRIVE, COAST))
    per_impact = 2 * 0.07 * (t_c / p.h_max) ** -2.5
    impacts = 0
    for _ in range(300):
        r = wheel.step(h, phi_p, 0.0, 0.0, 0.0)
        impacts += len(r.onsets)
        assert _energy(wheel, phi_p) <= e0 * (1 + 1e-4 + per_impact * impacts)
    assert impacts >= 1 or w0 * 20 / 39 * 300 * h < backlash / derived["arm_wheel"]
