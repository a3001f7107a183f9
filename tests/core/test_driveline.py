"""Driveline physics: input-shaft kinematics and the output shaft."""

import math

import numpy as np
import pytest

from drive_rattle.driveline import (
    RPM,
    DrivelineParameters,
    EngineOrderKinematics,
    OutputShaft,
    SpeedTableKinematics,
    read_speed_table,
)


def test_engine_orders_are_consistent_and_have_exact_mean():
    p = DrivelineParameters()
    kin = EngineOrderKinematics(p)
    assert [k for k, _, _ in p.order_terms()] == [2.0, 4.0, 6.0]
    t = np.linspace(0.0, 60 / 830 * 2, 20001)  # two crank revolutions = 4 periods of order 2
    phi, w, a = np.array([kin(x) for x in t]).T
    assert np.gradient(phi, t)[1:-1] == pytest.approx(w[1:-1], rel=1e-6, abs=1e-6)
    assert np.gradient(w, t)[1:-1] == pytest.approx(a[1:-1], rel=1e-4, abs=1e-2)
    assert (phi[-1] - phi[0]) / (t[-1] - t[0]) == pytest.approx(830 * RPM, rel=1e-12)
    # Order 2 of 830 rpm is 27.67 Hz (not the paper's 26 Hz, MODEL_NOTES section 2).
    W2 = kin.terms[0][1]
    assert W2 / (2 * math.pi) == pytest.approx(27.667, abs=1e-3)
    assert kin(0.0) == (0.0, 830 * RPM, 650.0)


def test_speed_table_is_integrated_exactly(tmp_path):
    f = tmp_path / "speed.csv"
    f.write_text("time_s,speed_rad_s\n0,10\n1,20\n3,20\n")
    kin = SpeedTableKinematics(f, phi_0=1.0)
    assert kin(0.5) == pytest.approx((1.0 + 0.5 * 10 + 0.5 * 10 * 0.25, 15.0, 10.0))
    assert kin(2.0) == pytest.approx((1.0 + 15.0 + 20.0, 20.0, 0.0))
    assert kin(4.0) == pytest.approx((1.0 + 15.0 + 40.0 + 20.0, 20.0, 0.0))


@pytest.mark.parametrize(
    "content, fragment",
    [("0,1\n0,2\n", "does not increase"), ("0,1\n", "at least two rows"),
     ("0,1\n1,x\n", "row 2"), ("0,1\n1,nan\n", "non-finite")],
)
def test_bad_speed_tables_are_rejected(tmp_path, content, fragment):
    f = tmp_path / "bad.csv"
    f.write_text(content)
    with pytest.raises(ValueError, match=fragment):
        read_speed_table(f)


def test_missing_speed_table_names_the_parameter(tmp_path):
    with pytest.raises(ValueError, match=r"engine\.speed_table"):
        read_speed_table(tmp_path / "nope.csv")


def test_output_shaft_steady_state_transmits_drag():
    p = DrivelineParameters(drag=0.2, drag_viscous=0.01)
    w = 44.5
    shaft = OutputShaft(p, 0.0, w)
    assert shaft.tau_load == pytest.approx(0.2 + 0.01 * w)
    for k in range(1000):  # the wheel turns steadily: nothing changes
        tau = shaft.step(1e-4, w * k * 1e-4, w)
    assert tau == pytest.approx(0.2 + 0.01 * w, rel=1e-9)
    assert shaft.state.w == pytest.approx(w, rel=1e-12)


def test_output_shaft_free_vibration_frequency():
    # Wheel held still, vehicle released from a twisted shaft: it oscillates at
    # sqrt(k / J_v) (light damping, no drag).
    p = DrivelineParameters(c_shaft=0.0, drag=0.0, k_shaft=5000.0, J_vehicle=5.0)
    shaft = OutputShaft(p, 0.0, 0.0)
    shaft.state.phi = 1e-3
    taus = [shaft.step(1e-4, 0.0, 0.0) for _ in range(20000)]
    crossings = np.where(np.diff(np.sign(taus)) != 0)[0]
    period = 2 * np.mean(np.diff(crossings)) * 1e-4
    assert period == pytest.approx(2 * math.pi / math.sqrt(5000 / 5.0), rel=1e-3)
    assert max(taus) == pytest.approx(5.0, rel=1e-3)  # amplitude kept: no numerical damping
