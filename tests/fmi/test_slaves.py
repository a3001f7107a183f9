"""The slave classes, instantiated directly (no FMU binary): FMI behaviour of the glue."""

import json
import math

import pytest

from drive_rattle.driveline import DrivelineParameters
from drive_rattle.parameters import MeshParameters, specs
from drive_rattle_cosim.system import simulate

from .slave_driver import SLAVES, Driveline, Driven, GearMeshRattle

ERROR = 3
PINION = {"pinion.phi": 0.0, "pinion.w": 86.92, "pinion.a": 0.0, "wheel.tau_load": 0.15}


def mesh(**inputs):
    m = Driven(GearMeshRattle)
    assert m.initialize(**{**PINION, **inputs}) == (0, "")
    return m


def test_registration_follows_the_specs():
    for name, cls in SLAVES.items():
        s = Driven(cls)
        public = [v.name for v in s.slave.public_variables]
        expected = ([spec.name for _, spec in specs(cls.PARAMETERS)]
                    + [x.name for x in cls.INPUTS] + [x.name for x in cls.OUTPUTS])
        assert public == expected, name
        assert [s.vr[n] for n in public] == list(range(len(public)))


def test_parameters_take_effect_at_end_of_initialization():
    m = Driven(GearMeshRattle)
    m.slave.setup_experiment(0.0)
    m.slave.enter_initialization_mode()
    m.set_named(PINION)
    m.set(wheel__J=2.6e-3, gear__backlash=0.2e-3)
    assert m.slave._model is None  # nothing built before exitInitializationMode
    m.slave.exit_initialization_mode()
    assert m.status() == (0, "")
    assert m.slave._model.params.J_wheel == 2.6e-3
    assert m.slave._model.params.backlash == 0.2e-3


@pytest.mark.parametrize("name, value, fragment", [
    ("wheel.J", -1.0, "'wheel.J' = -1.0"),
    ("gear.beta", 1.0, "'gear.beta' = 1.0"),
    ("gear.z_pinion", 3, "'gear.z_pinion' = 3"),
    ("lubricant.eta", float("nan"), "must be finite"),
])
def test_invalid_parameter_fails_exit_initialization(name, value, fragment):
    m = Driven(GearMeshRattle)
    m.slave.setup_experiment(0.0)
    m.slave.enter_initialization_mode()
    m.set_named(PINION)
    m.set_named({name: value})
    m.slave.exit_initialization_mode()
    code, msg = m.status()
    assert code == ERROR and fragment in msg and "allowed" in msg
    assert m.slave._mode == "initialization" and m.slave._model is None
    # Fixing the parameter lets initialization finish.
    m.set_named({name: next(s.default for _, s in specs(MeshParameters) if s.name == name)})
    m.slave.exit_initialization_mode()
    assert m.status() == (0, "")


def test_fixed_parameter_rejected_after_initialization():
    m = mesh()
    m.set(wheel__J=5e-3)
    code, msg = m.status()
    assert code == ERROR and "'wheel.J' is fixed" in msg and "5e-3" in msg.replace("0.005", "5e-3")
    assert m.get("wheel.J") == 1.3e-3


@pytest.mark.parametrize("name", ["pinion.phi", "pinion.w", "pinion.a", "wheel.tau_load"])
@pytest.mark.parametrize("bad", [float("nan"), float("inf"), -float("inf")])
def test_non_finite_input_rejected_and_state_kept(name, bad):
    m = mesh()
    assert m.step(0.0, 1e-4) == (0, "")
    before = json.dumps(m.slave._get_fmu_state(), sort_keys=True)
    m.set_named({name: bad})
    code, msg = m.step(1e-4, 1e-4)
    assert code == ERROR and f"input '{name}'" in msg and "not finite" in msg
    # Everything but the offending input value itself is as before the call.
    after = m.slave._get_fmu_state()
    after["values"][name] = json.loads(before)["values"][name]
    assert json.dumps(after, sort_keys=True) == before


@pytest.mark.parametrize("t, h, fragment", [
    (0.0, 0.0, "step size 0.0"), (0.0, -1e-4, "step size -0.0001"),
    (0.0, float("nan"), "step size nan"), (0.0, 2.0, "exceeds solver.h_comm_max"),
    (5e-4, 1e-4, "does not continue"), (-1e-4, 1e-4, "does not continue"),
    (float("inf"), 1e-4, "communication point inf s is not finite"),
])
def test_bad_communication_steps_rejected(t, h, fragment):
    m = mesh()
    before = json.dumps(m.slave._get_fmu_state(), sort_keys=True)
    code, msg = m.step(t, h)
    assert code == ERROR and fragment in msg
    assert json.dumps(m.slave._get_fmu_state(), sort_keys=True) == before
    assert m.step(0.0, 1e-4) == (0, "")  # and the instance still works


def test_calls_out_of_order_are_rejected():
    m = Driven(GearMeshRattle)
    m.slave.do_step(0.0, 1e-4)
    code, msg = m.status()
    assert code == ERROR and "doStep is not allowed in mode 'instantiated'" in msg
    m.slave.exit_initialization_mode()
    assert "exitInitializationMode is not allowed" in m.status()[1]
    m.slave.setup_experiment(0.0)
    m.slave.enter_initialization_mode()
    m.slave.enter_initialization_mode()
    assert "enterInitializationMode is not allowed" in m.status()[1]


def test_unknown_value_reference_and_wrong_type():
    m = mesh()
    assert math.isnan(m.slave.get_real([9999])[0])
    assert "value reference 9999" in m.status()[1]
    m.slave.set_integer([m.vr["wheel.J"]], [3])
    assert "no Integer variable" in m.status()[1]
    m.slave.set_real([m.vr["wheel.w"]], [1.0])
    assert "is an output" in m.status()[1]


def test_state_rollback_reproduces_outputs_bit_for_bit():
    m = mesh()
    for k in range(5):
        m.set(pinion__phi=86.92 * k * 1e-4)
        assert m.step(k * 1e-4, 1e-4) == (0, "")
    saved = m.slave._get_fmu_state()
    blob = m.slave._fmu_state_to_bytes(saved)
    outs = [v.name for v in m.slave.public_variables if v.causality.name == "output"]

    def run():
        rows = []
        for k in range(5, 40):
            m.set(pinion__phi=86.92 * k * 1e-4, pinion__a=300.0 * math.cos(k))
            assert m.step(k * 1e-4, 1e-4) == (0, "")
            rows.append([m.get(n) for n in outs])
        return rows

    first = run()
    m.slave._set_fmu_state(saved)
    assert m.status() == (0, "")
    assert run() == first
    # A serialized state restored into a new instance.
    other = Driven(GearMeshRattle)
    other.slave._set_fmu_state(GearMeshRattle._fmu_state_from_bytes(blob))
    assert other.status() == (0, "")
    m = other
    assert run() == first


def test_instances_are_independent():
    a, b, c = mesh(), mesh(**{"wheel.tau_load": 0.3}), mesh()
    b_state = json.dumps(b.slave._get_fmu_state(), sort_keys=True)
    for k in range(20):
        a.set(pinion__a=500.0 * math.sin(k), pinion__phi=86.92 * k * 1e-4)
        assert a.step(k * 1e-4, 1e-4) == (0, "")
    # Stepping a changed neither b nor the identical instance c.
    assert json.dumps(b.slave._get_fmu_state(), sort_keys=True) == b_state
    for k in range(20):
        c.set(pinion__a=500.0 * math.sin(k), pinion__phi=86.92 * k * 1e-4)
        assert c.step(k * 1e-4, 1e-4) == (0, "")
    assert c.get("wheel.phi") == a.get("wheel.phi") and c.get("mesh.W") == a.get("mesh.W")


def test_initial_unknowns_in_initialization_mode():
    d = Driven(Driveline)
    d.slave.setup_experiment(0.0)
    d.slave.enter_initialization_mode()
    assert d.get("pinion.w") == pytest.approx(86.92 + 0.0, abs=0.01)
    assert d.get("wheel.tau_load") == pytest.approx(DrivelineParameters().drag)
    d.set(engine__w_mean=100.0)
    assert d.get("pinion.w") == 100.0


def test_slaves_reproduce_the_in_process_system_bit_for_bit():
    """A Jacobi master over the two slave classes gives exactly system.simulate's numbers."""
    n, h = 60, 1e-4
    ref = simulate(MeshParameters(), DrivelineParameters(), stop_time=n * h, step=h)
    m, d = Driven(GearMeshRattle), Driven(Driveline)
    for x in (m, d):
        x.slave.setup_experiment(0.0)
        x.slave.enter_initialization_mode()
    first = {k: d.get(k) for k in ("pinion.phi", "pinion.w", "pinion.a", "wheel.tau_load")}
    m.set_named(first)
    m.slave.exit_initialization_mode()
    d.set_named({"wheel.phi": m.get("wheel.phi"), "wheel.w": m.get("wheel.w")})
    d.slave.exit_initialization_mode()
    assert m.status() == d.status() == (0, "")
    for k in range(n + 1):
        t = ref.time[k]
        assert m.get("wheel.w") == ref.signals["wheel.w"][k]
        assert m.get("mesh.W") == ref.signals["mesh.W"][k]
        assert d.get("wheel.tau_load") == ref.signals["wheel.tau_load"][k]
        if k == n:
            break
        m.set_named({x: d.get(x) for x in ("pinion.phi", "pinion.w", "pinion.a",
                                           "wheel.tau_load")})
        d.set_named({"wheel.phi": m.get("wheel.phi"), "wheel.w": m.get("wheel.w")})
        h_k = ref.time[k + 1] - t  # the integer-nanosecond grid of system.simulate
        assert m.step(t, h_k) == (0, "") and d.step(t, h_k) == (0, "")
