"""The unit (unit.c, unit_mesh.c, unit_driveline.c): a refused call -- a bad input, step size
or communication point, a bad set, a refused initialization -- changes nothing; and how the
units start and read their inputs (init.settle_first_step, inputs.continue_when_held;
docs/tools.md): each unit started on its input starts outputs its partner's, the mesh
settles against the first step's inputs, the driveline starts its shaft anew, held inputs
run on.  The start and hold rules are driven through the pythonfmu slave classes
(tests/fmi/slave_driver.py), the way a master that makes no exchange at initialization
drives them."""

import ctypes
import math

import pytest

from drive_rattle import DrivelineParameters, DrivelineUnit, MeshParameters, ModelError, Unit
from drive_rattle.library import DRIVELINE, MESH
from drive_rattle.units import input_starts
from drive_rattle_cosim.ssp import consistent_input_starts
from tests.fmi.slave_driver import Driveline, Driven, GearMeshRattle
from tests.fmu.closed_forms import engine_orders

from .helpers import H, assert_refused_and_unchanged, history

# ------------------------------------------------------------------ a refused call changes nothing
REFUSED_STEPS = [
    (H, {"pinion.phi": math.nan}, "pinion.phi"),
    (H, {"pinion.w": math.inf}, "pinion.w"),
    (H, {"pinion.a": -math.inf}, "pinion.a"),
    (H, {"wheel.tau_load": math.nan}, "wheel.tau_load"),
    (H, {"wheel.tau_load": 1e308}, "out of range"),
    (H, {"pinion.phi": 2e6}, "out of range"),
    (0.0, {}, "step size"),
    (-H, {}, "step size"),
    (math.nan, {}, "step size"),
    (math.inf, {}, "step size"),
    (2e-2, {}, "h_comm_max"),
    # the pinion jumps 12 mrad (~250 um) into the flank: beyond the validity of the Hertz
    # contact (a 1 us step: the substeps this penetration needs stay few)
    (1e-6, {"pinion.phi": 87.0 * 5 * H + 0.012}, "penetrate"),
]


@pytest.mark.parametrize("h, inputs, match", REFUSED_STEPS)
def test_a_refused_step_leaves_the_unit_unchanged(h, inputs, match):
    unit, twin = history(), history()
    unit.set({"pinion.phi": 87.0 * 5 * H, "pinion.w": 87.0, "pinion.a": 0.0,
              "wheel.tau_load": 0.1} | inputs)
    message = assert_refused_and_unchanged(unit, "rm_do_step", unit.time, h, match=match)
    assert message.startswith("doStep: ")
    # ...and the unit continues as one that never saw the refused call
    args = (H, 87.0 * 5 * H, 87.0, 0.0, 0.1)
    unit.step(*args)
    twin.step(*args)
    assert unit.outputs() == twin.outputs() and unit.save() == twin.save()


def test_a_step_that_does_not_continue_the_last_one_is_refused():
    unit = history()
    assert_refused_and_unchanged(unit, "rm_do_step", unit.time + 1e-6, H, match="doStep")
    assert_refused_and_unchanged(unit, "rm_do_step", 0.0, H, match="doStep")


def test_a_refused_driveline_step_leaves_the_unit_unchanged():
    unit = DrivelineUnit(DrivelineParameters(), 0.0, 44.57)
    unit.step(H, 0.0, 44.57)
    unit.set({"wheel.phi": math.nan})
    before = unit.save()
    with pytest.raises(ModelError, match=r"'wheel\.phi' = nan"):
        unit.call("rm_do_step", unit.time, H)
    assert unit.save() == before


def test_refused_sets_and_a_refused_initialization_change_nothing():
    unit = Unit(MESH, MeshParameters(), initialize=False)
    real = ctypes.c_double * 2
    j, z = unit.variables["wheel.J"].vr, unit.variables["gear.z_pinion"].vr
    # one bad entry refuses the whole call: an unknown reference, an Integer set as Real, an
    # output
    for vrs, match in (((j, 99999), "99999"), ((j, z), "no Real variable"),
                       ((j, unit.variables["mesh.W"].vr), "output")):
        message = assert_refused_and_unchanged(
            unit, "rm_set_real", (ctypes.c_uint * 2)(*vrs), 2, real(2e-3, 1.0), match=match)
        assert message.startswith("setReal: ")
    # parameters are checked when initialization ends: refused there, nothing changes
    unit.set({"wheel.J": math.nan})
    unit.call("rm_setup", 0.0)
    unit.call("rm_enter_initialization")
    assert_refused_and_unchanged(unit, "rm_exit_initialization", match="'wheel.J' = nan")
    assert unit.phase == "initialization"
    unit.set({"wheel.J": 1.3e-3})
    unit.call("rm_exit_initialization")
    # parameters are fixed once stepping
    assert_refused_and_unchanged(unit, "rm_set_real", (ctypes.c_uint * 1)(j), 1,
                                 (ctypes.c_double * 1)(2e-3), match="wheel.J")


# ------------------------------------------------------------------ start and held inputs
OK, WARNING, ERROR = 0, 1, 3
MESH_STARTS = input_starts(MESH)
DRIVELINE_STARTS = input_starts(DRIVELINE)


def started(cls, parameters=None, inputs=None):
    """A slave through initialization: parameters, and only the given inputs set."""
    unit = Driven(cls)
    unit.set_named(parameters or {})
    unit.slave.setup_experiment(0.0)
    unit.slave.enter_initialization_mode()
    unit.set_named(inputs or {})
    unit.slave.exit_initialization_mode()
    assert unit.status() == (OK, "")
    return unit


def outputs(unit, names):
    return {n: unit.get(n) for n in names}


@pytest.mark.parametrize("parameters", [
    {},
    {"GearMeshRattle.gear.backlash": 2e-4, "GearMeshRattle.wheel.J": 2e-3,
     "Driveline.engine.w_mean": 120.0, "Driveline.engine.phase[1]": 0.7,
     "Driveline.vehicle.drag": 0.3, "Driveline.vehicle.drag_viscous": 1e-3},
])
def test_each_unit_started_on_its_input_starts_outputs_its_partners(parameters):
    """The fixed point: initialized on these start values alone (no exchange), each unit
    outputs exactly the other's start values."""
    starts = consistent_input_starts(parameters)
    units = {"GearMeshRattle": GearMeshRattle, "Driveline": Driveline}
    started_units = {}
    for name, cls in units.items():
        own = {k.split(".", 1)[1]: v for k, v in parameters.items() if k.startswith(name + ".")}
        inputs = {k.split(".", 1)[1]: v for k, v in starts.items() if k.startswith(name + ".")}
        started_units[name] = started(cls, own, inputs)
    mesh, drive = started_units["GearMeshRattle"], started_units["Driveline"]
    # The scenario at speed and under load, not the zeros that put the wheel at rest.
    assert starts["GearMeshRattle.pinion.w"] > 10.0 and starts["Driveline.wheel.w"] > 10.0
    for name in MESH_STARTS:
        assert drive.get(name) == starts[f"GearMeshRattle.{name}"], name
    for name in DRIVELINE_STARTS:
        assert mesh.get(name) == starts[f"Driveline.{name}"], name


def test_mesh_settles_against_the_first_steps_inputs():
    """A master that set zeros during initialization (fmu-manipulation-toolbox's container)
    and the true inputs only for the first step: the wheel is settled for them first, and the
    step is exactly that of a mesh initialized on them."""
    reference = started(GearMeshRattle, inputs=MESH_STARTS)
    reference.set_named(MESH_STARTS)
    assert reference.step(0.0, 1e-4) == (OK, "")
    zeros = {name: 0.0 for name in MESH_STARTS}
    mesh = started(GearMeshRattle, inputs=zeros)
    assert mesh.get("wheel.w") == 0.0  # at rest, as the zeros say
    mesh.set_named(MESH_STARTS)
    code, message = mesh.step(0.0, 1e-4)
    assert code == WARNING and "settled" in message and "init.settle_first_step" in message
    names = ["wheel.phi", "wheel.w", "wheel.tau_mesh", "mesh.W", "mesh.delta_peak"]
    assert outputs(mesh, names) == outputs(reference, names)
    # Only the first step settles: later ones take the inputs as they come -- a pinion set
    # back to rest at angle 0, 86 um into the wheel's coast flank and approached at 1.8 m/s:
    # refused (with the teeth's compliance in series the flanks would be driven beyond the
    # 0.05 m_n the step allows; a settled wheel would rest on the drive flank instead).
    mesh.set_named(zeros)
    code, message = mesh.step(1e-4, 1e-4)
    assert code == ERROR and "penetrate" in message, message
    assert mesh.get("mesh.impacts_coast") == 0  # the refused step changed nothing


def test_without_settling_the_first_step_takes_the_inputs_as_they_come():
    # The wheel initialized at rest on zeros, then a pinion turning at 830 rpm: without
    # settling, the first step is the impact these inputs describe -- the pinion's flank
    # strikes the resting wheel at r_bp cos(beta_b) w_p, about 1.6 m/s on the tooth normal
    # (the damped contact takes it; the undamped one was refused as beyond the Hertz contact).
    zeros = {name: 0.0 for name in MESH_STARTS}
    mesh = started(GearMeshRattle, {"init.settle_first_step": False}, zeros)
    mesh.set_named(MESH_STARTS)
    assert mesh.step(0.0, 1e-4) == (OK, "")
    assert mesh.get("mesh.impacts_drive") == 1
    v = MESH_STARTS["pinion.w"] * MeshParameters().derived()["arm_pinion"]
    assert mesh.get("mesh.v_impact") == pytest.approx(v, rel=1e-9)  # measured 1.84 m/s
    assert mesh.get("wheel.w") > 40.0  # the struck wheel is flung along (e ~ 0.005)


def test_driveline_starts_its_shaft_anew_behind_the_first_steps_wheel():
    reference = started(Driveline, inputs=DRIVELINE_STARTS)
    reference.set_named(DRIVELINE_STARTS)
    assert reference.step(0.0, 1e-4) == (OK, "")
    names = ["wheel.tau_load", "vehicle.w", "pinion.w"]
    for settle, expected in ((True, WARNING), (False, OK)):
        drive = started(Driveline, {"init.settle_first_step": settle},
                        {"wheel.phi": 0.0, "wheel.w": 0.0})
        drive.set_named(DRIVELINE_STARTS)
        assert drive.step(0.0, 1e-4)[0] == expected
        same = outputs(drive, names) == outputs(reference, names)
        assert same == settle  # without settling, the shaft starts behind a resting wheel


def test_held_pinion_runs_on_at_constant_speed():
    """fmpy simulate of the mesh alone sets no input: the pinion turns at the held speed, as
    if driven at that constant speed, and the wheel follows loaded on the drive flank (with
    the teeth's compliance the light start load lets the flanks part and meet again about
    once per mesh cycle, tests/cosim/test_masters.py)."""
    h, n = 1e-2, 20
    held = started(GearMeshRattle)  # no input ever set
    driven = started(GearMeshRattle, inputs=MESH_STARTS)
    phi, w = MESH_STARTS["pinion.phi"], MESH_STARTS["pinion.w"]
    phi_w = held.get("wheel.phi")
    names = ["wheel.phi", "wheel.w", "wheel.tau_mesh", "mesh.W", "mesh.impacts_drive",
             "mesh.impacts_coast"]
    for k in range(n):
        assert held.step(k * h, h) == (OK, "")
        driven.set_named({**MESH_STARTS, "pinion.phi": phi, "pinion.a": 0.0})
        assert driven.step(k * h, h) == (OK, "")
        phi += w * h  # the constant-speed pinion, as the stepper advances it
        assert outputs(held, names) == outputs(driven, names), k
    ratio = DRIVELINE_STARTS["wheel.w"] / w
    assert (held.get("wheel.phi") - phi_w) / (n * h) == pytest.approx(ratio * w, rel=1e-4)
    assert held.get("wheel.tau_mesh") == pytest.approx(MESH_STARTS["wheel.tau_load"], rel=0.01)
    mesh_cycles = n * h * MeshParameters().z_pinion * w / (2 * math.pi)
    assert held.get("mesh.impacts_coast") == 0
    assert held.get("mesh.impacts_drive") <= 1.05 * mesh_cycles
    assert held.get("mesh.transmission_error") > 0.0  # on the drive flank: the pinion leads


def test_held_inputs_taken_literally_drive_the_teeth_into_each_other():
    mesh = started(GearMeshRattle, {"inputs.continue_when_held": False})
    assert mesh.step(0.0, 1e-2) == (OK, "")
    code, message = mesh.step(1e-2, 1e-2)  # the pinion jumps back to the held angle
    # refused: the flanks would be driven through each other (by then the contact's time
    # scale is below 1e-11 s, refused as too stiff to resolve, or the penetration is beyond
    # the Hertz contact's validity), with the step to use
    assert code == ERROR and ("penetrate" in message or "too stiff" in message)
    assert "reduce the communication step to at most 0.0001 s" in message.lower()


def test_the_same_values_set_again_keep_the_hold_new_values_end_it():
    """Held: the pinion runs on at constant speed (as a pinion set to that motion with
    pinion.a = 0); new values are taken as given."""
    h, w = 1e-4, MESH_STARTS["pinion.w"]
    names = ["wheel.phi", "wheel.w", "wheel.tau_mesh", "mesh.W", "mesh.transmission_error"]
    mesh = started(GearMeshRattle)
    driven = started(GearMeshRattle, inputs=MESH_STARTS)
    phi = MESH_STARTS["pinion.phi"]
    assert mesh.step(0.0, h) == (OK, "")  # nothing set: held, the pinion runs on
    mesh.set_named(MESH_STARTS)  # the values of the last step again: still held
    assert mesh.step(h, h) == (OK, "")
    for k in range(2):
        driven.set_named({**MESH_STARTS, "pinion.phi": phi, "pinion.a": 0.0})
        assert driven.step(k * h, h) == (OK, "")
        phi += w * h
    assert outputs(mesh, names) == outputs(driven, names)  # two steps at constant speed
    new = {**MESH_STARTS, "pinion.phi": phi, "pinion.w": w + 1.0}
    mesh.set_named(new)  # new values: taken as given
    driven.set_named(new)
    assert mesh.step(2 * h, h) == (OK, "") and driven.step(2 * h, h) == (OK, "")
    assert outputs(mesh, names) == outputs(driven, names)


def test_held_wheel_drives_the_vehicle_steadily():
    """fmpy simulate of the Driveline alone: the wheel runs on at its start speed, the shaft
    stays in steady state (its torque is the drag), the engine turns as prescribed."""
    p = DrivelineParameters()
    drive = started(Driveline)
    w = DRIVELINE_STARTS["wheel.w"]
    h, n = 0.5, 20
    for k in range(n):
        assert drive.step(k * h, h) == (OK, "")
        # (taken literally, the held angle holds the wheel back while the vehicle runs on:
        # the shaft torque falls to -42 N.m after the second 0.5 s step)
        assert drive.get("wheel.tau_load") == pytest.approx(p.drag + p.drag_viscous * w,
                                                            rel=1e-6)
        assert drive.get("vehicle.w") == pytest.approx(w, rel=1e-9)
    phi, w_p, _ = engine_orders(p)(n * h)
    assert drive.get("pinion.phi") == pytest.approx(phi, rel=1e-12)
    assert drive.get("pinion.w") == pytest.approx(w_p, rel=1e-12)
