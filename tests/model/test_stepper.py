"""Event location: onsets and releases are located, not stepped over; exact touches at a
communication point are onsets."""

import math
from dataclasses import replace

import pytest

from drive_rattle import COAST, DRIVE, MeshParameters, MeshUnit

from .helpers import approach_unit, free_parameters, rest_step, run_impact

H = 1e-4


def penetration(d: dict, flank: int, phi_p: float, phi_w: float) -> float:
    """The flank's penetration [m] as the library computes it, from its own derived values."""
    return flank * (d["arm_pinion"] * phi_p - d["arm_wheel"] * phi_w) - d["half_backlash"]


def touching_angle(d: dict, flank: int, phi_p: float) -> float:
    """A wheel angle at which ``flank`` has penetration exactly 0.0 against ``phi_p``."""
    phi = (d["arm_pinion"] * phi_p - flank * d["half_backlash"]) / d["arm_wheel"]
    for _ in range(64):
        pen = penetration(d, flank, phi_p, phi)
        if pen == 0.0:
            return phi
        # d(pen)/d(phi_w) = -flank arm_w: step the wheel angle by one ulp towards zero
        phi = math.nextafter(phi, (flank if pen > 0.0 else -flank) * math.inf)
    pytest.fail(f"no wheel angle with exactly zero penetration near {phi!r}")


def test_onset_between_substeps_located_within_1ns():
    v, gap = 3e-3, 41.3e-9
    unit = approach_unit(v, DRIVE, gap=gap)
    onset = rest_step(unit, H).events[0]  # ten substeps of 1e-5 s; the onset between two
    assert onset.kind == "onset"
    t_exact = gap / v
    assert (t_exact * 1e5) % 1 > 0.1  # not on a substep boundary
    assert abs(onset.time - t_exact) < 1e-9


@pytest.mark.parametrize("a_p, tau", [(40.0, -0.05), (40.0, 0.05), (-40.0, -0.05)])
def test_onset_with_load_and_pinion_acceleration_matches_the_quadratic(a_p, tau):
    p = free_parameters(0.0, DRIVE, gap=50e-9)
    d = p.derived()
    unit = MeshUnit(p, 0.0, 0.0, tau)
    report = unit.step(2e-4, 0.0, 0.0, a_p, tau)
    # delta(t) = -gap + 1/2 (arm_p a_p - arm_w a_w) t^2 with a_w = -tau / J
    acc = d["arm_pinion"] * a_p + d["arm_wheel"] * tau / p.J_wheel
    t_exact = math.sqrt(2 * 50e-9 / acc) if acc > 0 else math.inf
    if t_exact < 2e-4:
        assert report.events[0].kind == "onset"
        assert abs(report.events[0].time - t_exact) < 1e-9
    else:  # moving apart, or not reaching the flank in the step
        assert not report.events


@pytest.mark.parametrize("flank", [DRIVE, COAST])
def test_release_is_at_zero_penetration(flank):
    unit = approach_unit(4e-3, flank)
    d = unit.describe()
    for _ in range(400):
        report = rest_step(unit, 1e-5)
        if any(e.kind == "release" for e in report.events):
            break
    release = next(e for e in report.events if e.kind == "release")
    out = unit.outputs()
    assert out["mesh.delta"] == 0.0 and out["mesh.W"] == 0.0 and out["mesh.n_contact"] == 0
    # The state at the step end is in free flight; back-propagate to the release time.
    phi, w = unit.wheel()
    phi_release = phi - w * (1e-5 - release.time)
    assert abs(penetration(d, flank, 0.0, phi_release)) < 1e-15


def test_time_grid_is_not_accumulated():
    # Many steps with a step size that is not a binary fraction: the substep grid inside
    # each step ends exactly at h, so nothing drifts.
    unit = approach_unit(0.0, DRIVE, gap=1e-9)
    h = 1e-4 / 3
    for _ in range(3000):
        rest_step(unit, h)
    out = unit.outputs()
    assert out["wheel.w"] == 0.0 and out["mesh.n_contact"] == 0
    assert out["mesh.impacts_drive"] == out["mesh.impacts_coast"] == 0


def test_flank_reached_exactly_by_the_pinion_at_a_communication_point():
    # Free flight towards the drive flank; the next step's pinion angle puts the flank exactly
    # at zero penetration at the step start (the pinion input may jump between steps).
    p = MeshParameters(init_in_contact=False, w_start=-5.0)
    d = p.derived()
    unit = MeshUnit(p, 0.0, 0.0, 0.0)
    rest_step(unit, H)
    assert unit.outputs()["mesh.n_contact"] == 0
    phi_w = unit.wheel()[0]
    phi_p = (d["arm_wheel"] * phi_w + d["half_backlash"]) / d["arm_pinion"]
    for _ in range(64):
        pen = penetration(d, DRIVE, phi_p, phi_w)
        if pen == 0.0:
            break
        phi_p = math.nextafter(phi_p, -math.inf if pen > 0.0 else math.inf)
    assert penetration(d, DRIVE, phi_p, phi_w) == 0.0
    report = unit.step(H, phi_p, 0.0, 0.0, 0.0)
    assert report.events[0].kind == "onset" and report.events[0].time == 0.0


def test_zero_load_start_with_an_accelerating_pinion_is_an_onset():
    # wheel.tau_load = 0 starts the wheel touching the drive flank at the rigid speed; a pinion
    # accelerating into it loads the flank from the first instant (no free flight into it).
    p = MeshParameters(friction_enabled=False)
    unit = MeshUnit(p, 0.0, 86.92, 0.0)
    report = unit.step(1e-4, 0.0, 86.92, 200.0, 0.0)
    assert report.events[0].kind == "onset" and report.events[0].time == 0.0
    assert report.events[0].flank == DRIVE
    out = unit.outputs()
    assert out["mesh.W_peak"] > 0.0 and out["mesh.delta"] > 0.0
    # The penetration reached is what the load needs, not a free flight of a whole step.
    assert out["mesh.delta_peak"] < 0.05e-6


def touching_unit(v: float, tau_load: float, flank: int = DRIVE, **changes) -> MeshUnit:
    """A unit whose wheel is in free flight (no flank in contact) at initialization and exactly
    touches ``flank`` at the start of the first step, approaching at v [m/s]: the wheel starts
    at the touching angle against phi_p = 0 while the pinion is initialized 1 nm short of it
    (the first step's pinion.phi = 0 closes the gap by a jump, as a master's input may)."""
    p = MeshParameters(init_in_contact=False, **changes)
    d = p.derived()
    p = replace(p, phi_start=touching_angle(d, flank, 0.0), w_start=-flank * v / d["arm_wheel"])
    unit = MeshUnit(p, -flank * 1e-9 / d["arm_pinion"], 0.0, tau_load)
    assert unit.outputs()["mesh.n_contact"] == 0
    return unit


@pytest.mark.parametrize("flank", [DRIVE, COAST])
def test_exact_touch_at_a_communication_point_is_an_onset(flank):
    # The flank reached exactly at a step boundary (penetration 0.0, approaching at 0.1 m/s)
    # must start the contact at once, not be flown through for a step.  (A wheel started
    # exactly touching and approaching starts in contact: no onset.)
    v = 0.1
    unit = touching_unit(v, 0.0, flank, friction_enabled=False, dissipation=0)
    onset = next(e for e in rest_step(unit, H).events if e.kind in ("onset", "release"))
    assert (onset.kind, onset.time, onset.flank) == ("onset", 0.0, flank)
    assert onset.speed == pytest.approx(v, rel=1e-12)
    assert unit.get(["mesh.W_peak"])["mesh.W_peak"] > 0.0
    events, _, _ = run_impact(unit, h=H)
    release = [e for _, e in events if e.kind == "release"]
    assert -release[0].speed == pytest.approx(v, rel=1e-3)


@pytest.mark.parametrize("a_p, tau_load", [(500.0, 0.0), (0.0, 0.3)])
def test_exact_touch_at_rest_accelerated_into_contact(a_p, tau_load):
    # Wheel and pinion at rest, exactly touching; the pinion's acceleration or the load drives
    # the drive flank into contact: an onset at t = 0 at zero speed.
    unit = touching_unit(0.0, tau_load)
    report = unit.step(H, 0.0, 0.0, a_p, tau_load)
    onsets = [e for e in report.events if e.kind == "onset"]
    assert [(e.time, e.flank, e.speed) for e in onsets] == [(0.0, DRIVE, 0.0)]
    for k in range(1, 20):
        t = k * H
        unit.step(H, 0.5 * a_p * t * t, a_p * t, a_p, tau_load)
        assert unit.outputs()["mesh.delta"] > 0.0
    assert unit.outputs()["mesh.impacts_drive"] == 1


@pytest.mark.parametrize("v", [1e-4, 1e-5])
def test_grazing_contact_from_exact_touch_is_one_onset_and_one_release(v):
    # Exactly touching, approaching at v [m/s] while the load pulls the wheel back off the
    # drive flank at ~30 m/s^2: the flank is left within the first 10 us substep, whether or
    # not a sample of the substep penetrates (at 1e-4 m/s one does, at 1e-5 m/s none).
    unit = touching_unit(v, -1.0)
    kinds = []
    for _ in range(3):
        kinds += [e.kind for e in unit.step(H, 0.0, 0.0, 0.0, -1.0).events
                  if e.kind in ("onset", "release")]
    assert kinds == ["onset", "release"]
    assert unit.outputs()["mesh.n_contact"] == 0


# ------------------------------------------------------------------ one impact, counted once
ON_GRID = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 2.0, 3.5)
OFF_GRID = (0.05, 0.37, 1.234, 2.71)


def placed_onset(v: float, f: float, flank: int, w_p: float, h: float = H):
    """A free wheel approaching ``flank`` at normal speed ``v`` [m/s], no load, against a
    pinion turning at the constant speed ``w_p`` [rad/s] (phi_p = w_p t, exact at every
    point), placed to reach the flank at f h: ``(unit, derived values)``."""
    p = MeshParameters(init_in_contact=False, friction_enabled=False)
    d = p.derived()
    gap = v * f * h
    p = replace(p, phi_start=-flank * (d["half_backlash"] - gap) / d["arm_wheel"],
                w_start=(d["arm_pinion"] * w_p - flank * v) / d["arm_wheel"])
    return MeshUnit(p, 0.0, w_p, 0.0), d


@pytest.mark.parametrize("w_p", [0.0, 86.92], ids=["pinion at rest", "pinion turning"])
@pytest.mark.parametrize("flank", [DRIVE, COAST])
@pytest.mark.parametrize("f", ON_GRID + OFF_GRID)
def test_an_onset_on_the_substep_grid_or_a_communication_point_counts_once(f, flank, w_p):
    # An onset at f H falls on the 10 us substep grid (f a tenth), on a communication point
    # (f whole) or between them; its located time carries the rounding of the quadratic root,
    # so it lands a few ulps before or after the grid point.  Before, the contact substep of a
    # few ulps that followed ended with the penetration at or below zero to rounding and
    # reported a release while the flanks still approached, then a second onset: the impact
    # counted twice and its energy entered the rattle index twice.
    v, tau = 4e-3, MeshParameters().rattle_time
    unit, d = placed_onset(v, f, flank, w_p)
    energy = 0.5 * d["normal_mass"] * v * v
    events, k = [], 0
    while not any(e.kind == "release" for _, e in events):
        t = k * H
        report = unit.step(H, w_p * t, w_p, 0.0, 0.0)
        events += [(t + e.time, e) for e in report.events if e.kind in ("onset", "release")]
        k += 1
        if k == math.ceil(f) + 1:  # the step after the onset's: the index of one impact
            onset_time = events[0][0]
            out = unit.outputs()
            assert out["mesh.rattle_index"] == pytest.approx(
                energy / tau * math.exp(-(k * H - onset_time) / tau), rel=1e-9)
            assert out["mesh.impact_energy"] == pytest.approx(energy, rel=1e-9)
        assert k < 100
    kinds = [(e.kind, e.flank) for _, e in events]
    assert kinds == [("onset", flank), ("release", flank)], events
    assert events[0][0] == pytest.approx(f * H, rel=1e-9, abs=1e-15)
    assert events[0][1].speed == pytest.approx(v, rel=1e-9)
    out = unit.outputs()
    assert (out["mesh.impacts_drive"], out["mesh.impacts_coast"]) == (
        (1, 0) if flank == DRIVE else (0, 1))


def jumped_unit(flank: int, v: float, jump: float):
    """A wheel in free flight at normal speed ``v`` [m/s] on ``flank`` (> 0 approaching, < 0
    receding), pinion at rest, after one step that leaves it short of the flank; and the
    pinion angle that puts the flank ``jump`` [m] deep against the wheel where it is:
    ``(unit, pinion angle, derived values)``."""
    p = MeshParameters(init_in_contact=False, friction_enabled=False)
    d = p.derived()
    gap = 1e-9 + max(v, 0.0) * H
    p = replace(p, phi_start=-flank * (d["half_backlash"] - gap) / d["arm_wheel"],
                w_start=-flank * v / d["arm_wheel"])
    unit = MeshUnit(p, 0.0, 0.0, 0.0)
    unit.step(H, 0.0, 0.0, 0.0, 0.0)
    out = unit.outputs()
    assert out["mesh.n_contact"] == 0 and out["mesh.impacts_drive"] + out[
        "mesh.impacts_coast"] == 0
    pen = flank * out["mesh.transmission_error"] - d["half_backlash"]
    assert pen < 0.0
    return unit, flank * (jump - pen) / d["arm_pinion"], d


@pytest.mark.parametrize("flank", [DRIVE, COAST])
def test_a_pinion_jump_into_a_receding_flank_is_a_touch_not_an_impact(flank):
    # The inputs move the pinion 10 nm into a flank the wheel recedes from at 0.4 mm/s (in
    # the co-simulation: the driveline's exact angle against the mesh's extrapolation over
    # the last step, typically right after a release).  The flanks carry the penetration's
    # load until they separate, but there is no approach: no impact counted, no energy in the
    # rattle index, mesh.v_impact unchanged, and the contact's start is a "touch" event.
    unit, phi_p, _ = jumped_unit(flank, -4e-4, 10e-9)
    report = unit.step(H, phi_p, 0.0, 0.0, 0.0)
    kinds = [(e.kind, e.flank, e.time) for e in report.events if e.kind != "pair"]
    assert kinds[0] == ("touch", flank, 0.0)
    assert report.events[0].speed == pytest.approx(-4e-4, rel=1e-6)
    assert unit.outputs()["mesh.W_peak"] > 0.0
    for _ in range(20):
        kinds += [(e.kind, e.flank, e.time) for e in unit.step(H, phi_p, 0.0, 0.0, 0.0).events
                  if e.kind != "pair"]
    assert [k[:2] for k in kinds] == [("touch", flank), ("release", flank)]
    out = unit.outputs()
    assert out["mesh.impacts_drive"] == out["mesh.impacts_coast"] == 0
    assert out["mesh.rattle_index"] == 0.0 and out["mesh.v_impact"] == 0.0


@pytest.mark.parametrize("flank", [DRIVE, COAST])
def test_a_pinion_jump_into_an_approaching_flank_is_an_impact_at_its_speed(flank):
    v = 4e-4
    unit, phi_p, d = jumped_unit(flank, v, 10e-9)
    report = unit.step(H, phi_p, 0.0, 0.0, 0.0)
    onset = report.events[0]
    assert (onset.kind, onset.flank, onset.time) == ("onset", flank, 0.0)
    assert onset.speed == pytest.approx(v, rel=1e-6)
    out = unit.outputs()
    assert out["mesh.impacts_drive" if flank == DRIVE else "mesh.impacts_coast"] == 1
    assert out["mesh.impact_energy"] == pytest.approx(0.5 * d["normal_mass"] * v * v, rel=1e-6)


@pytest.mark.parametrize("flank", [DRIVE, COAST])
def test_a_pinion_jump_out_of_an_approaching_contact_keeps_the_contact(flank):
    # In contact and still approaching, the inputs move the pinion 0.1 nm out of the flank:
    # a release needs a non-approaching rate, so the contact goes on (one impact, one release)
    # instead of a release while approaching and a second onset.
    v = 4e-3
    unit, phi_p, d = jumped_unit(flank, v, 0.0)
    kinds = [(e.kind, e.flank) for e in unit.step(H, phi_p, 0.0, 0.0, 0.0).events
             if e.kind in ("onset", "release", "touch")]
    assert kinds == [("onset", flank)]
    assert unit.outputs()["mesh.delta"] > 0.0  # approaching still (the contact lasts ~0.3 ms)
    phi_p -= flank * (unit.outputs()["mesh.delta"] + 0.1e-9) / d["arm_pinion"]
    for _ in range(10):
        kinds += [(e.kind, e.flank) for e in unit.step(H, phi_p, 0.0, 0.0, 0.0).events
                  if e.kind in ("onset", "release", "touch")]
    assert kinds == [("onset", flank), ("release", flank)]
    out = unit.outputs()
    assert out["mesh.impacts_drive"] + out["mesh.impacts_coast"] == 1


def test_a_release_at_the_rounding_level_of_large_angles_lets_the_step_progress():
    # After 19.45 s (about 1000 rad of pinion) a penetration is known to the ulp of phi r,
    # 4e-15 m: on the multistability grid (0.5 M*, 0.1 mm, start phase 1/3) a contact whose
    # located release fell on its substep's start was released there and met again at the same
    # instant a million times, until the step was refused as making no progress. The release
    # then ends the substep instead; the run reaches 20 s.
    from drive_rattle import DrivelineParameters
    from drive_rattle_cosim import multistability as ms

    mesh = replace(MeshParameters(), backlash=1e-4)
    drive = DrivelineParameters()
    load = ms.paper_driveline(0.5 * ms.separation_load(mesh, drive), drive)
    start = next(s for s in ms.STARTS if s.name == "phase 1/3")
    run = ms.run_start(mesh, load, start, min_time=20.0, max_time=20.0)
    assert run.seconds >= 20.0
