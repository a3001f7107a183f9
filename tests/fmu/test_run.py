"""The built FMUs running under fmpy: alone, coupled, and through the FMI error paths."""

import math

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.fmi1 import FMICallException

from drive_rattle.parameters import DrivelineParameters, MeshParameters
from drive_rattle.units import MeshUnit
from drive_rattle_cosim.harness import CoSimulation, CoSimulationError, Unit
from drive_rattle_cosim.system import simulate

from .closed_forms import engine_orders

W_P = 86.92


def test_driveline_alone_under_simulate_fmu(fmus):
    r = simulate_fmu(str(fmus["Driveline"]), stop_time=0.05, output_interval=1e-4)
    kin = engine_orders(DrivelineParameters())
    assert r["pinion.a"][0] == pytest.approx(kin(0.0)[2], rel=1e-12)  # no step yet: the
    # instantaneous acceleration
    for row in r[1::50]:
        t = row["time"]
        phi, w, _ = kin(t)
        assert row["pinion.phi"] == pytest.approx(phi, rel=1e-12, abs=1e-12)
        assert row["pinion.w"] == pytest.approx(w, rel=1e-12)
        # pinion.a_over_step: the mean acceleration over the coming step of 1e-4 s
        assert row["pinion.a"] == pytest.approx((kin(t + 1e-4)[1] - w) / 1e-4, rel=1e-6)
    # Wheel inputs held at 0: the shaft stays in its steady state, transmitting the drag.
    assert np.allclose(r["wheel.tau_load"], DrivelineParameters().drag, rtol=1e-12)


def test_driveline_alone_with_wheel_input_table(fmus):
    # The wheel turns steadily at 44 rad/s from t = 0: the shaft starts wound up by the drag
    # behind it and the vehicle follows at the same speed, so the load stays the drag.
    w = 44.0
    table = np.array([(0.0, 0.0, w), (1.0, w, w)],
                     dtype=[("time", "f8"), ("wheel.phi", "f8"), ("wheel.w", "f8")])
    r = simulate_fmu(str(fmus["Driveline"]), stop_time=0.05, output_interval=1e-4, input=table)
    assert np.allclose(r["wheel.tau_load"], DrivelineParameters().drag, rtol=1e-9)
    assert np.allclose(r["vehicle.w"], w, rtol=1e-12)
    # A wheel at rest, then turned by 0.01 rad at t = 0.02 s: the shaft torque rises by
    # k * 0.01 and the vehicle starts to follow.
    k = DrivelineParameters().k_shaft
    jump = np.array([(0.0, 0.0, 0.0), (0.02, 0.0, 0.0), (0.02, 0.01, 0.0), (1.0, 0.01, 0.0)],
                    dtype=table.dtype)
    r = simulate_fmu(str(fmus["Driveline"]), stop_time=0.05, output_interval=1e-4,
                     input=jump, start_values={"vehicle.drag": 1.0})
    before, after = r["time"] < 0.0199, (r["time"] > 0.0201) & (r["time"] < 0.0205)
    assert np.allclose(r["wheel.tau_load"][before], 1.0, rtol=1e-12)
    assert np.allclose(r["vehicle.w"][before], 0.0, atol=1e-15)
    assert np.allclose(r["wheel.tau_load"][after], 1.0 + k * 0.01, rtol=1e-4)
    assert r["vehicle.w"][-1] > 0.0


def test_mesh_alone_under_simulate_fmu_with_input_table(fmus):
    T, load = 0.03, 0.15
    table = np.array([(0.0, 0.0, W_P, 0.0, load), (1.0, W_P, W_P, 0.0, load)],
                     dtype=[("time", "f8"), ("pinion.phi", "f8"), ("pinion.w", "f8"),
                            ("pinion.a", "f8"), ("wheel.tau_load", "f8")])
    # The wheel's response to the table's last-bit rounding (below) stays within 3.3e-12
    # relative over the run (before the film's engagement was made continuous, the default
    # squeeze film reached 4.2e-8 here: tests/model/test_stepper.py)
    r = simulate_fmu(str(fmus["GearMeshRattle"]), stop_time=T, output_interval=1e-4,
                     input=table)
    assert len(r) == 301
    # The same inputs through the library's Python API; fmpy interpolates pinion.phi from the
    # table, which rounds differently from W_P * t in the last bits, hence not bit for bit.
    unit = MeshUnit(MeshParameters(), 0.0, W_P, load)
    for k in range(len(r) - 1):
        t = r["time"][k]
        assert r["wheel.w"][k] == pytest.approx(unit.wheel()[1], rel=1e-9)
        unit.step(r["time"][k + 1] - t, W_P * t, W_P, 0.0, load)
    assert np.mean(r["wheel.w"]) == pytest.approx(W_P * 20 / 39, rel=1e-4)
    # crowned pairs: the one or two whose face centre is in the path of contact carry the load
    assert set(r["mesh.n_contact"]) <= {1, 2}
    assert np.all(r["mesh.impacts_coast"] == 0)


def test_harness_reproduces_in_process_system_bit_for_bit(fmus):
    n, h = 600, 1e-4
    ref = simulate(MeshParameters(), DrivelineParameters(), stop_time=n * h, step=h)
    names = ["GearMeshRattle.wheel.w", "GearMeshRattle.mesh.W", "GearMeshRattle.mesh.delta_peak",
             "GearMeshRattle.mesh.impacts_drive", "Driveline.wheel.tau_load",
             "Driveline.pinion.w"]
    with CoSimulation(fmus["GearMeshRattle"], fmus["Driveline"], step=h) as sim:
        res = sim.run(n * h, names)
    assert res.time == ref.time.tolist()
    for name in names:
        assert res[name] == ref.signals[name.split(".", 1)[1]].tolist(), name
    assert res["GearMeshRattle.mesh.impacts_drive"][-1] > 0  # it rattles within the horizon


def test_harness_parameters_and_csv(fmus, tmp_path):
    with CoSimulation(fmus["GearMeshRattle"], fmus["Driveline"],
                      parameters={"GearMeshRattle.gear.backlash": 0.2e-3,
                                  "Driveline.vehicle.drag": 0.3,
                                  "GearMeshRattle.friction.enabled": False}) as sim:
        res = sim.run(0.002, ["GearMeshRattle.wheel.w", "Driveline.wheel.tau_load"])
    assert res["Driveline.wheel.tau_load"][0] == pytest.approx(0.3)
    path = res.to_csv(tmp_path / "r.csv")
    lines = path.read_text().splitlines()
    assert lines[0] == "time [s],GearMeshRattle.wheel.w [rad/s],Driveline.wheel.tau_load [N.m]"
    assert len(lines) == 22
    with pytest.raises(KeyError, match="not a parameter"):
        CoSimulation(fmus["GearMeshRattle"], fmus["Driveline"],
                     parameters={"GearMeshRattle.wheel.w": 1.0})


def test_harness_reports_invalid_parameter_with_its_reason(fmus):
    with pytest.raises(CoSimulationError) as err:
        CoSimulation(fmus["GearMeshRattle"], fmus["Driveline"],
                     parameters={"GearMeshRattle.wheel.J": -1.0})
    msg = str(err.value)
    assert "exitInitializationMode returned Error" in msg and "'wheel.J' = -1 " in msg


def _mesh_unit(fmus, name="m"):
    u = Unit(fmus["GearMeshRattle"], name)
    u.slave.setupExperiment(startTime=0.0)
    u.slave.enterInitializationMode()
    u.set({"pinion.w": W_P, "wheel.tau_load": 0.15})
    u.slave.exitInitializationMode()
    return u


OUT = ["wheel.phi", "wheel.w", "mesh.W", "wheel.tau_mesh", "pinion.tau_mesh", "mesh.delta"]


def _outs(u):
    return u.slave.getReal([u.var(n).vr for n in OUT])


def _drive(u, k0, k1, a=300.0):
    rows = []
    for k in range(k0, k1):
        t = k * 1e-4
        u.set({"pinion.phi": W_P * t, "pinion.a": a * math.cos(170 * t)})
        u.slave.doStep(t, 1e-4)
        rows.append(_outs(u))
    return rows


def test_invalid_parameter_fails_exit_initialization_with_logged_message(fmus):
    for _ in range(3):  # and the process survives freeing the failed instance, repeatedly
        u = Unit(fmus["GearMeshRattle"], "bad")
        u.slave.setupExperiment(startTime=0.0)
        u.slave.enterInitializationMode()
        u.set({"gear.beta": 1.2})
        with pytest.raises(FMICallException) as err:
            u.slave.exitInitializationMode()
        assert err.value.status == 3
        status, message = u.messages[-1]
        assert status == "Error" and "'gear.beta' = 1.2" in message and "allowed" in message
        u.close()
    u = _mesh_unit(fmus)
    assert _drive(u, 0, 3)
    u.close()


@pytest.mark.parametrize("bad", [float("nan"), float("inf")])
def test_non_finite_input_fails_do_step_and_keeps_state(fmus, bad):
    ref = _mesh_unit(fmus, "ref")
    u = _mesh_unit(fmus, "u")
    _drive(ref, 0, 10)
    _drive(u, 0, 10)
    before = _outs(u)
    u.set({"pinion.w": bad})
    with pytest.raises(FMICallException) as err:
        u.slave.doStep(10e-4, 1e-4)
    assert err.value.status == 3
    assert "input 'pinion.w'" in u.messages[-1][1]
    assert _outs(u) == before
    u.set({"pinion.w": W_P})
    assert _drive(u, 10, 30) == _drive(ref, 10, 30)  # as if the bad call never happened
    u.close()
    ref.close()


def test_communication_point_must_continue_the_last_step(fmus):
    u = _mesh_unit(fmus)
    _drive(u, 0, 2)
    with pytest.raises(FMICallException):
        u.slave.doStep(5e-4, 1e-4)
    assert "does not continue the last step" in u.messages[-1][1]
    with pytest.raises(FMICallException):
        u.slave.doStep(2e-4, -1e-4)
    assert _drive(u, 2, 4)  # the right point still works
    u.close()


def test_fmu_state_rollback_and_serialization_are_bit_exact(fmus):
    u = _mesh_unit(fmus)
    _drive(u, 0, 20)
    state = u.slave.getFMUstate()
    blob = u.slave.serializeFMUstate(state)
    first = _drive(u, 20, 80)
    u.slave.setFMUstate(state)
    assert _drive(u, 20, 80) == first
    other = Unit(fmus["GearMeshRattle"], "other")
    other.slave.setupExperiment(startTime=0.0)
    other.slave.enterInitializationMode()
    other.slave.exitInitializationMode()
    other.slave.setFMUstate(other.slave.deSerializeFMUstate(blob))
    assert _drive(other, 20, 80) == first
    u.slave.freeFMUstate(state)
    u.close()
    other.close()


def test_instances_are_independent_and_both_fmus_load_together(fmus):
    a, b = _mesh_unit(fmus, "a"), _mesh_unit(fmus, "b")
    d = Unit(fmus["Driveline"], "d")
    ra = _drive(a, 0, 30, a=500.0)
    rb = _drive(b, 0, 30, a=0.0)
    assert ra != rb
    c = _mesh_unit(fmus, "c")
    assert _drive(c, 0, 30, a=500.0) == ra
    for x in (a, b, c, d):
        x.close()


def test_instantiate_refuses_a_foreign_guid(fmus):
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    for name, fmu in fmus.items():
        md = read_model_description(str(fmu))
        folder = extract(str(fmu))
        wrong = FMU2Slave(guid="{00000000-0000-0000-0000-000000000000}", unzipDirectory=folder,
                          modelIdentifier=name, instanceName="wrong")
        with pytest.raises(Exception, match="Failed to instantiate"):
            wrong.instantiate()
        right = FMU2Slave(guid=md.guid, unzipDirectory=folder, modelIdentifier=name,
                          instanceName="right")
        right.instantiate()
        right.freeInstance()


def test_loading_the_fmus_leaves_the_host_import_path_alone(fmus):
    # pythonfmu puts each instance's resources folder in front of sys.path; the slaves take it
    # out again, so the host keeps importing its own packages (and sys.path does not grow).
    import sys

    before = list(sys.path)
    for _ in range(3):
        for name in ("GearMeshRattle", "Driveline"):
            Unit(fmus[name], name).close()
    assert sys.path == before
