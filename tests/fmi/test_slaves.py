"""The slave classes, instantiated directly (no FMU binary): the pythonfmu face over the model
library.  Every FMI call is one library call, the library's statuses and messages reach the
status channel verbatim, nothing raises, and a refused call changes nothing (the unit's record,
``rm_save``, is the same before and after)."""

import math
from pathlib import Path

import pytest

from drive_rattle import library
from drive_rattle.interface import DRIVELINE_INPUTS, MESH_INPUTS
from drive_rattle.parameters import DrivelineParameters, MeshParameters, specs
from drive_rattle.units import MeshUnit, input_starts
from drive_rattle_cosim.system import simulate
from drive_rattle_fmi.slave import (
    LAST_SUCCESSFUL_TIME_VARIABLE,
    MESSAGE_VARIABLE,
    STATUS_ADDRESS_VARIABLE,
)

from .slave_driver import SLAVES, Driveline, Driven, GearMeshRattle

OK, WARNING, ERROR = 0, 1, 3
PINION = {"pinion.phi": 0.0, "pinion.w": 86.92, "pinion.a": 0.0, "wheel.tau_load": 0.15}


def mesh(**inputs):
    m = Driven(GearMeshRattle)
    assert m.initialize(**{**PINION, **inputs}) == (OK, "")
    return m


def test_registration_follows_the_specs_and_the_library_table():
    for name, cls in SLAVES.items():
        s = Driven(cls)
        public = [v.name for v in s.slave.public_variables]
        expected = ([spec.name for _, spec in specs(cls.PARAMETERS)]
                    + [x.name for x in cls.INPUTS] + [x.name for x in cls.OUTPUTS])
        assert public == expected, name
        # value reference = registration index = the library's table index
        table = library.variables(cls.KIND)
        assert [s.vr[n] for n in public] == list(range(len(public))) == [v["vr"] for v in table]
        assert [(v["name"], v["type"], v["causality"]) for v in table] == [
            (v.name, type(v).__name__, v.causality.name) for v in s.slave.public_variables]
        # the hidden variables of the status channel come last
        assert [v.name for v in s.slave.vars.values()][len(public):] == [
            STATUS_ADDRESS_VARIABLE, MESSAGE_VARIABLE, LAST_SUCCESSFUL_TIME_VARIABLE]


@pytest.mark.parametrize("cls, inputs", [(GearMeshRattle, MESH_INPUTS),
                                         (Driveline, DRIVELINE_INPUTS)])
def test_input_start_values_are_the_librarys(cls, inputs):
    s = Driven(cls)
    starts = input_starts(cls.KIND)
    assert {x.name: s.get(x.name) for x in inputs} == starts
    assert all(math.isfinite(v) for v in starts.values())


def test_parameters_take_effect_at_end_of_initialization():
    """Set in initialization mode, used from exitInitializationMode: the slave steps exactly as
    the Python API's unit of the same parameters (both are the library)."""
    m = Driven(GearMeshRattle)
    m.slave.setup_experiment(0.0)
    m.slave.enter_initialization_mode()
    m.set_named(PINION)
    m.set(wheel__J=2.6e-3, gear__backlash=0.2e-3)
    m.slave.exit_initialization_mode()
    assert m.status() == (OK, "")
    assert m.get("wheel.J") == 2.6e-3
    ref = MeshUnit(MeshParameters(J_wheel=2.6e-3, backlash=0.2e-3), PINION["pinion.phi"],
                   PINION["pinion.w"], PINION["wheel.tau_load"])
    default = MeshUnit(None, PINION["pinion.phi"], PINION["pinion.w"], PINION["wheel.tau_load"])
    for k in range(20):
        phi = 86.92 * k * 1e-4
        m.set_named({"pinion.phi": phi, "pinion.a": 300.0})
        assert m.step(k * 1e-4, 1e-4) == (OK, "")
        ref.step(1e-4, phi, 86.92, 300.0, 0.15)
        default.step(1e-4, phi, 86.92, 300.0, 0.15)
    assert m.get("wheel.w") == ref.outputs()["wheel.w"] != default.outputs()["wheel.w"]


@pytest.mark.parametrize("name, value, fragment", [
    ("wheel.J", -1.0, "'wheel.J' = -1"),
    ("gear.beta", 1.0, "'gear.beta' = 1"),
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
    assert code == ERROR and msg.startswith("exitInitializationMode: ")
    assert fragment in msg and "allowed" in msg
    assert m.phase() == "initialization"
    # Fixing the parameter lets initialization finish.
    m.set_named({name: next(s.default for _, s in specs(MeshParameters) if s.name == name)})
    m.slave.exit_initialization_mode()
    assert m.status() == (OK, "") and m.phase() == "stepping"


def test_fixed_parameter_rejected_after_initialization():
    m = mesh()
    before = m.state()
    m.set(wheel__J=5e-3)
    code, msg = m.status()
    assert code == ERROR and "'wheel.J' is fixed" in msg and "0.005" in msg
    assert m.get("wheel.J") == 1.3e-3 and m.state() == before


@pytest.mark.parametrize("name", ["pinion.phi", "pinion.w", "pinion.a", "wheel.tau_load"])
@pytest.mark.parametrize("bad", [float("nan"), float("inf"), -float("inf"), 1e300])
def test_bad_input_rejected_and_state_kept(name, bad):
    m = mesh()
    assert m.step(0.0, 1e-4) == (OK, "")
    good = m.get(name)
    m.set_named({name: good})  # (a set marks the motion inputs set: the record holds it)
    before = m.state()
    m.set_named({name: bad})
    code, msg = m.step(1e-4, 1e-4)
    assert code == ERROR and f"input '{name}'" in msg and "allowed" in msg
    # Everything but the offending input value itself is as before the call.
    m.set_named({name: good})
    assert m.state() == before
    assert m.step(1e-4, 1e-4) == (OK, "")


@pytest.mark.parametrize("t, h, fragment", [
    (0.0, 0.0, "step size 0 s"), (0.0, -1e-4, "step size -0.0001"),
    (0.0, float("nan"), "step size nan"), (0.0, 2.0, "exceeds solver.h_comm_max"),
    (5e-4, 1e-4, "does not continue"), (-1e-4, 1e-4, "does not continue"),
    (float("inf"), 1e-4, "communication point inf s is not finite"),
])
def test_bad_communication_steps_rejected(t, h, fragment):
    m = mesh()
    before = m.state()
    code, msg = m.step(t, h)
    assert code == ERROR and msg.startswith("doStep: ") and fragment in msg
    assert m.state() == before
    assert m.step(0.0, 1e-4) == (OK, "")  # and the instance still works


def test_calls_out_of_order_are_rejected():
    m = Driven(GearMeshRattle)
    before = m.state()
    m.slave.do_step(0.0, 1e-4)
    code, msg = m.status()
    assert code == ERROR and "doStep is not allowed in mode 'instantiated'" in msg
    m.slave.exit_initialization_mode()
    assert "exitInitializationMode is not allowed" in m.status()[1]
    m.slave.terminate()
    assert "terminate is not allowed" in m.status()[1]
    assert m.state() == before
    m.slave.setup_experiment(0.0)
    m.slave.enter_initialization_mode()
    m.slave.enter_initialization_mode()
    assert "enterInitializationMode is not allowed" in m.status()[1]
    m.slave.setup_experiment(0.0)
    assert "setupExperiment is not allowed" in m.status()[1]


def test_unknown_value_reference_wrong_type_and_outputs():
    m = mesh()
    before = m.state()
    assert math.isnan(m.slave.get_real([9999])[0])
    assert m.status() == (ERROR, "getReal: no Real variable with value reference 9999")
    m.slave.set_integer([m.vr["wheel.J"]], [3])
    assert "no Integer variable" in m.status()[1]
    m.slave.set_real([m.vr["wheel.w"]], [1.0])
    assert "'wheel.w' is an output and cannot be set" in m.status()[1]
    # pythonfmu passes value references as signed C ints: 2^31 arrives as -2^31
    m.slave.set_real([-(2**31)], [1.0])
    assert "value reference 2147483648" in m.status()[1]
    assert m.state() == before


def test_a_multi_value_set_with_one_bad_entry_stores_nothing():
    m = Driven(GearMeshRattle)
    before = m.state()
    m.slave.set_real([m.vr["wheel.J"], m.vr["wheel.w"], m.vr["gear.backlash"]],
                     [2e-3, 1.0, 2e-4])
    code, msg = m.status()
    assert code == ERROR and "nothing of this call was stored" in msg
    assert m.state() == before and m.get("wheel.J") == 1.3e-3


def test_state_rollback_reproduces_outputs_bit_for_bit():
    m = mesh()
    for k in range(5):
        m.set(pinion__phi=86.92 * k * 1e-4)
        assert m.step(k * 1e-4, 1e-4) == (OK, "")
    saved = m.slave._get_fmu_state()
    blob = m.slave._fmu_state_to_bytes(saved)
    assert isinstance(blob, bytes) and blob.startswith(b"RATLUNIT")  # the library's record
    outs = [v.name for v in m.slave.public_variables if v.causality.name == "output"]

    def run(x):
        rows = []
        for k in range(5, 40):
            x.set(pinion__phi=86.92 * k * 1e-4, pinion__a=300.0 * math.cos(k))
            assert x.step(k * 1e-4, 1e-4) == (OK, "")
            rows.append([x.get(n) for n in outs])
        return rows

    first = run(m)
    m.slave._set_fmu_state(saved)
    assert m.status() == (OK, "")
    assert run(m) == first
    # A serialized state restored into a new instance.
    other = Driven(GearMeshRattle)
    other.slave._set_fmu_state(GearMeshRattle._fmu_state_from_bytes(blob))
    assert other.status() == (OK, "")
    assert run(other) == first


@pytest.mark.parametrize("record", [b"", b"RATLUNIT", b"\0" * 64, "not bytes", None, 3])
def test_an_invalid_state_is_refused_and_changes_nothing(record):
    m = mesh()
    assert m.step(0.0, 1e-4) == (OK, "")
    before = m.state()
    m.slave._set_fmu_state(record)
    code, msg = m.status()
    assert code == ERROR and msg.startswith("setFMUstate: ") and "nothing changed" in msg
    assert m.state() == before


def test_a_truncated_or_foreign_record_is_refused():
    m, d = mesh(), Driven(Driveline)
    record = m.state()
    before = m.state()
    for bad in (record[:len(record) // 2], record[:-1], d.state()):
        m.slave._set_fmu_state(bad)
        code, msg = m.status()
        assert code == ERROR and "nothing changed" in msg
        assert m.state() == before


def test_instances_are_independent():
    a, b, c = mesh(), mesh(**{"wheel.tau_load": 0.3}), mesh()
    b_state = b.state()
    for k in range(20):
        a.set(pinion__a=500.0 * math.sin(k), pinion__phi=86.92 * k * 1e-4)
        assert a.step(k * 1e-4, 1e-4) == (OK, "")
    # Stepping a changed neither b nor the identical instance c.
    assert b.state() == b_state
    for k in range(20):
        c.set(pinion__a=500.0 * math.sin(k), pinion__phi=86.92 * k * 1e-4)
        assert c.step(k * 1e-4, 1e-4) == (OK, "")
    assert c.get("wheel.phi") == a.get("wheel.phi") and c.get("mesh.W") == a.get("mesh.W")


def test_initial_unknowns_in_initialization_mode():
    d = Driven(Driveline)
    d.slave.setup_experiment(0.0)
    d.slave.enter_initialization_mode()
    assert d.get("pinion.w") == pytest.approx(86.92, abs=0.01)
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
    assert m.status() == d.status() == (OK, "")
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
        assert m.step(t, h_k) == (OK, "") and d.step(t, h_k) == (OK, "")


class CountingLibrary:
    """The model library, counting the calls a slave makes (rm_message aside: it only reads
    the reason of a status)."""

    def __init__(self, lib):
        self._lib, self.calls = lib, []

    def __getattr__(self, name):
        fn = getattr(self._lib, name)

        def call(*args):
            if name != "rm_message":
                self.calls.append(name)
            return fn(*args)
        return call


def test_every_fmi_call_is_one_library_call():
    m = mesh()
    counting = m.slave._lib = CountingLibrary(m.slave._lib)
    vrs = [m.vr[n] for n in ("wheel.w", "mesh.W", "wheel.phi")]
    record = m.state()
    calls = {
        "get_real": lambda: m.slave.get_real(vrs),
        "get_integer": lambda: m.slave.get_integer([m.vr["mesh.impacts_drive"]] * 3),
        "get_boolean": lambda: m.slave.get_boolean([m.vr["friction.enabled"]]),
        "get_string": lambda: m.slave.get_string([]),
        "set_real": lambda: m.slave.set_real([m.vr["pinion.phi"], m.vr["pinion.w"]],
                                             [0.0, 86.92]),
        "set_integer": lambda: m.slave.set_integer([m.vr["gear.z_pinion"]], [20]),
        "set_boolean": lambda: m.slave.set_boolean([m.vr["friction.enabled"]], [True]),
        "do_step": lambda: m.slave.do_step(0.0, 1e-4),
        "get_fmu_state": lambda: m.slave._get_fmu_state(),
        "set_fmu_state": lambda: m.slave._set_fmu_state(record),
        "terminate": lambda: m.slave.terminate(),
        "reset": lambda: m.slave.reset(),
        "setup_experiment": lambda: m.slave.setup_experiment(0.0),
        "enter_initialization_mode": lambda: m.slave.enter_initialization_mode(),
        "exit_initialization_mode": lambda: m.slave.exit_initialization_mode(),
    }
    for what, call in calls.items():
        counting.calls.clear()
        call()
        m.status()
        assert len(counting.calls) == 1, (what, counting.calls)


@pytest.mark.parametrize("call", [
    lambda s: s.get_real([1.5]), lambda s: s.get_real(None), lambda s: s.get_real([2**40]),
    lambda s: s.set_real([0], ["x"]), lambda s: s.set_real([0, 1], [1.0]),
    lambda s: s.set_real([0], [10**400]), lambda s: s.set_integer([0], [2**40]),
    lambda s: s.set_integer([0], [1.5]), lambda s: s.set_string([0], [None]),
    lambda s: s.set_string([0], ["a\0b"]), lambda s: s.set_string(None, None),
    lambda s: s.setup_experiment("soon"), lambda s: s.do_step(None, 1e-4),
], ids=lambda c: "")
def test_nothing_ever_raises_out_of_the_slave(call):
    """What pythonfmu never passes (a slave driven from Python can): an Error with the reason,
    no exception (pythonfmu would make it fmi2Fatal), nothing changed."""
    m = Driven(GearMeshRattle)
    before = m.state()
    call(m.slave)
    code, msg = m.status()
    assert code == ERROR and msg, msg
    assert m.state() == before


def test_strings_go_through_the_librarys_utf8_check():
    d = Driven(Driveline)
    d.set_named({"engine.speed_table": "caf\u00e9.csv"})
    assert d.status() == (OK, "") and d.get("engine.speed_table") == "caf\u00e9.csv"
    d.set_named({"engine.speed_table": "bad\udcff.csv"})  # a lone surrogate: not UTF-8
    code, msg = d.status()
    assert code == ERROR and "not valid UTF-8" in msg
    assert d.get("engine.speed_table") == "caf\u00e9.csv"


def test_hidden_variables_of_the_status_channel():
    m = Driven(GearMeshRattle)
    vr = m.vr
    assert not m.slave._shim_attached
    address = m.slave.get_string([vr[STATUS_ADDRESS_VARIABLE]])[0]
    assert int(address, 16) and m.slave._shim_attached  # the shim reads it at instantiation
    assert math.isnan(m.slave.get_real([vr[LAST_SUCCESSFUL_TIME_VARIABLE]])[0])
    code, msg = m.status()
    assert code == ERROR and "fmi2LastSuccessfulTime" in msg
    assert m.slave.get_string([vr[MESSAGE_VARIABLE]]) == [msg]
    assert m.initialize(**PINION) == (OK, "")
    assert m.step(0.0, 1e-4) == (OK, "")
    assert m.step(5.0, 1e-4)[0] == ERROR  # refused: the last successful time stays
    assert m.slave.get_real([vr[LAST_SUCCESSFUL_TIME_VARIABLE]]) == [1e-4]
    # a hidden variable under another type is unknown (the library's refusal)
    m.slave.get_real([vr[MESSAGE_VARIABLE]])
    assert "no Real variable" in m.status()[1]


def test_with_the_shim_do_step_returns_true_without_it_false():
    """With the shim the status channel carries a refusal; without it (a platform without
    the shim) do_step returns False (fmi2Discard) and the message goes to pythonfmu's log,
    '%' escaped (pythonfmu uses it as a printf format)."""
    plain = mesh()
    assert plain.slave.do_step(7.0, 1e-4) is False
    queue = plain.slave._get_log_queue()
    assert queue and "does not continue" in queue[-1].msg and queue[-1].status == ERROR
    shimmed = mesh()
    shimmed.slave.get_string([shimmed.vr[STATUS_ADDRESS_VARIABLE]])
    assert shimmed.slave.do_step(7.0, 1e-4) is True
    assert shimmed.status()[0] == ERROR
    assert shimmed.slave.do_step(0.0, 1e-4) is True and shimmed.status() == (OK, "")


def test_a_first_step_that_settles_reports_the_librarys_warning():
    m = mesh()
    m.set_named({"wheel.tau_load": 0.3})
    code, msg = m.step(0.0, 1e-4)
    assert code == WARNING and msg.startswith("doStep at the first step") and "settled" in msg


def test_the_unit_is_freed_with_the_slave():
    m = Driven(GearMeshRattle)
    free = m.slave._free
    assert free.alive
    del m
    assert not free.alive  # no reference cycle keeps the slave (and its unit) for the GC


def test_the_model_description_is_the_one_the_build_rendered():
    cls = GearMeshRattle
    with pytest.raises(RuntimeError, match="rendered by the build"):
        Driven(cls).slave.to_xml()
    rendered = object()
    cls.MODEL_DESCRIPTION = rendered
    try:
        assert Driven(cls).slave.to_xml() is rendered
    finally:
        cls.MODEL_DESCRIPTION = None


@pytest.mark.parametrize("name", list(SLAVES))
def test_the_slave_modules_define_no_class_of_their_own(name):
    """pythonfmu executes the slave module's source anew at every fmi2Instantiate (its
    namespace as globals, a new dict as locals) and keeps what that makes: the source makes no
    new class (the one class is made once per process), and it holds the reference to its
    namespace that pythonfmu releases afterwards (tests/adversarial/test_endurance.py)."""
    import sys

    module = sys.modules[name]
    code = compile(Path(module.__file__).read_text(encoding="utf-8"), module.__file__, "exec")
    namespace = module.__dict__
    before = sys.getrefcount(namespace)
    made = {}
    exec(code, namespace, made)
    assert sys.getrefcount(namespace) == before + 1  # hold_namespace: one more reference
    classes = [v for v in made.values() if isinstance(v, type)]
    assert classes == [SLAVES[name]] and classes[0] is getattr(module, name)
