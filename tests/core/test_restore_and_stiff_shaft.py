"""Restoring the core from a snapshot (the FMU state path) and the exact output-shaft solution
for shafts too stiff or too damped for the RK4 substep (issue 12, rows 7 and 10)."""

import dataclasses
import json
import math
import shutil

import pytest

from drive_rattle import kernel
from drive_rattle.driveline import (
    DrivelineModel,
    DrivelineParameters,
    DrivelineSnapshot,
    OutputShaft,
    ShaftState,
)
from drive_rattle.parameters import MeshParameters
from drive_rattle.stepper import GRID_SLACK, WheelStepper, WheelStepperBase
from drive_rattle_build.kernel import compile_kernel

from .helpers import pinion_with_order

H = 1e-4


def run(stepper, k0, n):
    rows = []
    for k in range(k0, k0 + n):
        phi, w, a = pinion_with_order(k * H, 86.92, 400.0, 55.0)
        r = stepper.step(H, phi, w, a, 0.15)
        rows.append((stepper.state.as_tuple(), stepper.pinion, r.tau_wheel_mean, r.W_peak))
    return rows


@pytest.fixture(scope="module")
def lib(tmp_path_factory):
    if shutil.which("gcc") is None:
        pytest.skip("gcc not found on PATH: the compiled kernel cannot be built here")
    path = compile_kernel(tmp_path_factory.mktemp("kernel") / kernel.LIBRARY_NAME)
    return kernel.load_kernel(path)


@pytest.mark.parametrize("compiled", [False, True])
def test_snapshot_continues_bit_for_bit_without_solving_the_start(compiled, lib, monkeypatch):
    """A free start (init.in_contact = false) whose start check would fail once the pinion has
    moved: from_snapshot neither checks it nor solves an equilibrium, and continues exactly as
    the original stepper."""
    p = MeshParameters(init_in_contact=False, phi_start=0.0, w_start=44.5)
    cls = kernel.CompiledWheelStepper if compiled else WheelStepper
    options = {"library": lib} if compiled else {}
    original = cls(p, 0.0, 86.92, 0.15, **options)
    run(original, 0, 30)
    saved = original.snapshot()
    with pytest.raises(ValueError, match=r"wheel\.phi_start"):  # what rebuilding would do
        cls(p, original.pinion[0], original.pinion[1], 0.15, **options)

    def forbidden(*args):
        raise AssertionError("from_snapshot or restore solved a start condition")
    for name in ("start_snapshot", "equilibrium_state"):
        monkeypatch.setattr(WheelStepperBase, name, forbidden)
    restored = cls.from_snapshot(p, saved, **options)
    assert type(restored) is cls
    assert restored.snapshot() == saved
    assert run(restored, 30, 40) == run(original, 30, 40)
    # restore() into a stepper that moved on continues as well, from the same state
    restored.restore(saved)
    assert restored.snapshot() == saved
    again = cls.from_snapshot(p, saved, **options)
    assert run(restored, 30, 40) == run(again, 30, 40)


def test_driveline_snapshot_keeps_its_speed_table_without_the_file(tmp_path):
    table = tmp_path / "speed.csv"
    table.write_text("time,speed\n0,80\n0.004,95\n0.008,85\n")
    p = DrivelineParameters(speed_table=str(table))
    drive = DrivelineModel(p, 0.0, 0.0, 44.57)
    for k in range(20):
        drive.step(H, 44.57 * k * H, 44.57, t=k * H)
    snapshot = drive.snapshot()
    table.unlink()
    # through JSON, as in a serialized FMU state
    restored = DrivelineModel.from_snapshot(
        p, 0.0, DrivelineSnapshot.from_json(json.loads(json.dumps(snapshot.to_json()))))
    for k in range(20, 120):
        for d in (drive, restored):
            d.step(H, 44.57 * k * H, 44.57, t=k * H)
        assert restored.outputs() == drive.outputs()
    with pytest.raises(ValueError, match="lacks the speed table"):
        DrivelineModel.from_snapshot(p, 0.0, dataclasses.replace(snapshot, table=None))
    bad = dataclasses.replace(snapshot, table=([0.0, 0.0], [1.0, 2.0]))
    with pytest.raises(ValueError, match="does not increase"):
        DrivelineModel.from_snapshot(p, 0.0, bad)
    before = restored.snapshot()
    with pytest.raises(ValueError, match="does not increase"):
        restored.restore(bad)
    assert restored.snapshot() == before  # a refused restore changes nothing


def shaft_run(p, steps, h=H, w=44.57):
    shaft = OutputShaft(p, 0.0, w)
    shaft.state = ShaftState(shaft.state.phi - 1e-3, w + 0.5)  # start off steady state
    return [shaft.step(h, w * k * h, w) for k in range(steps)], shaft


@pytest.mark.parametrize("k, c, J, dv", [
    (1e5, 0.0, 1e-3, 0.0),  # undamped, 10^4 rad/s: rho h_max = 1
    (1e6, 2000.0, 1.0, 0.0),  # critically damped (c^2 = 4 k J): the series branch
    (1e6, 2100.0, 1.0, 0.0),  # just overdamped
    (1e6, 1900.0, 1.0, 3.0),  # just underdamped, with viscous drag
    (2.0, 50.0, 1e-3, 1.0),  # heavily overdamped
])
def test_exact_shaft_matches_fine_rk4(k, c, J, dv):
    """Where the default substep is too coarse for RK4 the exact solution is used; it must
    agree with RK4 on substeps 1000 times finer (an independent integration)."""
    p = DrivelineParameters(k_shaft=k, c_shaft=c, J_vehicle=J, drag_viscous=dv)
    fine = DrivelineParameters(k_shaft=k, c_shaft=c, J_vehicle=J, drag_viscous=dv,
                               h_max=p.h_max / 1000)
    assert p.h_max * OutputShaft(p, 0.0, 0.0).spectral_radius_bound() > 0.1  # exact branch
    assert fine.h_max * OutputShaft(fine, 0.0, 0.0).spectral_radius_bound() < 0.1
    exact, _ = shaft_run(p, 30)
    reference, _ = shaft_run(fine, 30)
    scale = max(abs(x) for x in reference)
    for a, b in zip(exact, reference, strict=True):
        assert a == pytest.approx(b, rel=1e-9, abs=1e-9 * scale)


@pytest.mark.parametrize("changes", [
    {"c_shaft": 1e6, "J_vehicle": 1e-6},
    {"drag_viscous": 1e5, "J_vehicle": 1e-6},
    {"c_shaft": 1e6, "drag_viscous": 1e5, "J_vehicle": 1e-6, "k_shaft": 1e9},
    {"c_shaft": 1e3, "J_vehicle": 1e-6, "k_shaft": 1e6},
])
def test_extreme_damping_follows_the_quasi_static_closed_form(changes):
    """Damping times J/(c + c_v) of 1e-9..1e-12 s (RK4 on 1e-4 s substeps gave 1e304 N.m).
    The vehicle's inertia is then negligible: J_v -> 0 turns the shaft into the first-order
    equation u' = (drag + c_v w)/(c + c_v) - k u/(c + c_v) for the wind-up u = phi_w - phi_v
    (wheel at constant speed w), with torque tau = k u + c (w - phi_v') (+ the O(J) inertia
    term), solved in closed form.  From a disturbed start the exact solver follows it; the
    steady state is tau = drag + c_v w."""
    p = DrivelineParameters(**changes)
    w = 44.57
    taus, _ = shaft_run(p, 12, w=w)
    k, c, dv = p.k_shaft, p.c_shaft, p.drag_viscous
    steady = p.drag + dv * w
    u_inf = steady / k
    u0 = 1e-3 + u_inf  # shaft_run lowers the vehicle angle by 1e-3 rad from steady state
    rate = k / (c + dv)
    eps = p.J_vehicle * k / (c + dv) ** 2  # relative size of the reduction's O(J^2) remainder
    for n, tau in enumerate(taus, start=1):
        d = (u0 - u_inf) * math.exp(-rate * n * H)
        # plus the first-order inertia term J_v dw_v/dt = J_v d/dt (w + rate d)
        expected = k * (u_inf + d) - c * rate * d - p.J_vehicle * rate**2 * d
        assert math.isfinite(tau)
        # c (w - w_v) amplifies the rounding of the vehicle's speed, ulp(w) ~ 7e-15 rad/s
        rounding = 4.0 * (c + dv) * math.ulp(w)
        tolerance = 10 * eps * abs(expected - steady) + 1e-9 * abs(steady) + 1e-9 + rounding
        assert abs(tau - expected) <= tolerance, (n, tau, expected)


def test_default_shaft_stays_on_rk4_bit_for_bit():
    """The defaults (rho h_max = 6e-5) keep the RK4 of the committed references."""
    p = DrivelineParameters()
    shaft = OutputShaft(p, 0.0, 44.57)
    assert p.h_max * shaft.spectral_radius_bound() < 1e-3
    a, b = OutputShaft(p, 0.0, 44.57), OutputShaft(p, 0.0, 44.57)
    for k in range(50):
        w = 44.57 + math.sin(k)
        tau = a.step(H, w * k * H, w)
        n = max(1, math.ceil(H / p.h_max * (1.0 - GRID_SLACK)))
        phi, wv = b._rk4(H, n, w * k * H, w)
        b.state = ShaftState(phi, wv)
        assert tau == b.torque(w * k * H + w * H, w, b.state)
