"""Values and the life cycle on every face, driven call by call through ctypes: the statuses
and messages are the model library's, passed on verbatim (a parameter checked at the end of
initialization, a parameter set too late, a speed table that cannot be read); the face adds
no rule of its own; reset gives a fresh instance.  A refused call changes nothing."""

from __future__ import annotations

from .calls import last, started, twin_error
from .raw_fmi import ERROR, OK


def test_invalid_parameter_refused_with_the_library_message(face, mesh):
    inst = mesh.instantiate(b"glue")
    assert inst.begin(0.0) == OK
    assert inst.set_named({"gear.backlash": -1e-3}) == OK  # checked at the end of initialization
    assert inst.exit() == ERROR
    expected = twin_error("GearMeshRattle", ("set", {"gear.backlash": -1e-3}),
                          ("rm_setup", 0.0), ("rm_enter_initialization",),
                          ("rm_exit_initialization",))
    assert expected.startswith("exitInitializationMode: parameter 'gear.backlash' = ")
    assert last(inst) == (ERROR, "logStatusError", expected)
    # nothing changed: still in initialization, corrected and initialized
    assert inst.set_named({"gear.backlash": 1e-4}) == OK and inst.exit() == OK
    inst.free()


def test_parameters_fixed_after_initialization_inputs_not(face, mesh):
    """The library decides what may be set when; the face adds no rule: after initialization
    a parameter (a real one, an integer code: FMI 3.0's Enumeration) is refused, an input
    accepted; after terminate both are refused (neither standard's co-simulation state table
    allows a set in the terminated state)."""
    inst = started(mesh)
    assert inst.set_named({"gear.backlash": 2e-4}) == ERROR
    assert last(inst)[2] == twin_error(
        "GearMeshRattle", ("initialize", 0.0), ("set", {"gear.backlash": 2e-4}))
    assert inst.set_named({"contact.dissipation": 1}) == ERROR
    assert last(inst)[2] == twin_error(
        "GearMeshRattle", ("initialize", 0.0), ("set", {"contact.dissipation": 1}))
    assert inst.set_named({"pinion.w": 80.0}) == OK
    assert inst.terminate() == OK
    assert inst.set_named({"pinion.w": 80.0}) == ERROR
    assert "mode is 'terminated'" in last(inst)[2]
    assert inst.set_named({"wheel.J": 1e-3}) == ERROR
    assert "mode is 'terminated'" in last(inst)[2]
    inst.free()


def test_reset_is_a_fresh_instance(face, mesh):
    fresh = started(mesh)
    inst = started(mesh, **{"gear.backlash": 2e-4, "contact.dissipation": 2})
    for k in range(5):
        assert inst.step(k * 1e-4, 1e-4) == OK
    assert inst.reset() == OK
    assert inst.begin(0.0) == OK and inst.exit() == OK
    assert inst.snapshot() == fresh.snapshot()
    fresh.free()
    inst.free()


def test_strings_checked_by_the_library(face, models):
    driveline = models["Driveline"]
    inst = driveline.instantiate(b"glue")
    vr = driveline.vr("engine.speed_table")
    assert inst.set("String", [vr], [b"\xff.csv"]) == ERROR
    # the C faces pass the library's message on; pythonfmu's strings are checked by its shim
    # before Python sees them
    assert last(inst)[2].startswith(
        "setString: value 0 ('engine.speed_table') is not valid UTF-8" if face.native else
        f"fmi2SetString: value 0 (value reference {vr}) is not valid UTF-8"), last(inst)
    assert inst.set("String", [vr], ["no such table.csv"]) == OK
    assert inst.get("String", [vr]) == (OK, ["no such table.csv"])
    assert inst.begin(0.0) == OK and inst.exit() == ERROR
    assert last(inst)[2].startswith("exitInitializationMode: parameter 'engine.speed_table' "
                                    "= 'no such table.csv' cannot be read")
    inst.free()
    # a relative name resolves against this FMU's resources folder
    (driveline.root / "resources" / "run-up.csv").write_text("0,80\n1,90\n", encoding="utf-8")
    inst = driveline.instantiate(b"glue")
    assert inst.set("String", [vr], ["run-up.csv"]) == OK
    assert inst.begin(0.0) == OK and inst.exit() == OK, inst.log
    assert inst.get_named("pinion.w") == 80.0
    inst.free()
