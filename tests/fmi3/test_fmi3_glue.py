"""The FMI 3.0 face (fmu_src/fmi3/fmi3_functions.c), driven call by call through ctypes: the
model's statuses and messages are the library's, passed on verbatim through logMessage; what
is FMI 3.0's is the glue's own -- the instantiation checks (name, token, event mode,
intermediate variables, the resources folder), the types (Float64, Int32, Enumerations as
Int64, Boolean, String; the independent variable time), NULL pointers and nValues, logging
categories, FMU states, fmi3DoStep's outputs and the functions these units do not provide.  A
refused call changes nothing and the host survives (every call here runs in this process).
What every face is asked alike (instantiation, values, states) is in tests/faces."""

from __future__ import annotations

import ctypes
import itertools
import sys
import zipfile
from ctypes import c_double, c_uint
from pathlib import Path
from xml.etree import ElementTree

import pytest

from drive_rattle.parameters import MeshParameters, specs

from ..faces.calls import last, loaded, started
from ..faces.raw_fmi import ERROR, FMI3, OK, WARNING, Model, unpack

ROOT = Path(__file__).resolve().parents[2]

CTYPES = FMI3.types


@pytest.fixture(scope="module")
def models(fmi3_fmus, tmp_path_factory):
    return loaded(fmi3_fmus, tmp_path_factory, "glue3")


@pytest.fixture
def mesh(models):
    return models["GearMeshRattle"]


# ------------------------------------------------------------------ the library's messages


def test_errors_always_logged_warnings_when_their_category_is_on(mesh):
    """FMI 3.0: with logging off only errors reach logMessage; a warning does when
    logStatusWarning (or logAll) is on -- the library's first-step warning here."""
    for on, categories, shown in [(False, None, False), (True, None, True),
                                  (False, [b"logStatusWarning"], True),
                                  (False, [b"logAll"], True),
                                  (False, [b"logStatusError"], False)]:
        inst = started(mesh)
        if categories is not None:
            assert inst.logging(True, categories) == OK
        elif on:
            assert inst.logging(True, None) == OK
        assert inst.set_named({"pinion.phi": 1e-3, "wheel.tau_load": 0.2}) == OK
        assert inst.step(0.0, 1e-4) == WARNING
        warnings = [m for s, _, m in inst.log if s == WARNING]
        assert bool(warnings) == shown, (on, categories, inst.log)
        if shown:
            assert warnings[0].startswith("doStep at the first step: the inputs (pinion.phi = ")
            assert inst.log[-1][1] == "logStatusWarning"
        assert inst.step(0.5, 1e-4) == ERROR  # errors: always
        assert last(inst)[:2] == (ERROR, "logStatusError")
        assert last(inst)[2].startswith("doStep: communication point 0.5 s does not continue")
        inst.free()


def test_debug_logging_categories(mesh, fmi3_fmus):
    inst = mesh.instantiate(b"glue")
    with zipfile.ZipFile(fmi3_fmus["GearMeshRattle"]) as z:
        md = ElementTree.fromstring(z.read("modelDescription.xml"))
    names = [c.get("name").encode() for c in md.find("LogCategories")]
    assert names == [b"logStatusWarning", b"logStatusDiscard", b"logStatusError",
                     b"logStatusFatal", b"logAll"]
    assert inst.logging(True, names) == OK  # every category of the modelDescription
    assert inst.logging(True, [b"logEvents"]) == ERROR
    assert last(inst)[2].startswith("fmi3SetDebugLogging: category 'logEvents' is not one of "
                                    "this FMU's; allowed: logStatusWarning, ")
    assert inst.logging(True, [b"logAll", None]) == ERROR
    assert mesh.lib.fmi3SetDebugLogging(inst.c, True, 2, None) == ERROR
    inst.free()


# ------------------------------------------------------------------ types
def test_the_types_of_fmi3(mesh):
    """Float64, Int32, Enumerations (Int64), Boolean and String reach the library's four
    types; an Enumeration only through Int64, an Int32 only through Int32; a code beyond 32
    bits is refused with the library's "allowed"; nothing of a refused call is stored."""
    inst = mesh.instantiate(b"glue")
    dissipation, z_pinion = mesh.vr("contact.dissipation"), mesh.vr("gear.z_pinion")
    assert mesh.variables["contact.dissipation"][1] == "Enumeration"
    assert mesh.variables["gear.z_pinion"][1] == "Int32"
    assert inst.set("Enumeration", [dissipation], [2]) == OK
    assert inst.get("Enumeration", [dissipation]) == (OK, [2])
    assert inst.set("Int32", [dissipation], [1]) == ERROR
    assert last(inst)[2] == (f"fmi3SetInt32: 'contact.dissipation' (value reference "
                             f"{dissipation}) is an Enumeration: FMI 3.0 gets and sets it as "
                             "Int64; allowed: fmi3SetInt64; nothing done")
    assert inst.get("Int32", [dissipation])[0] == ERROR
    assert inst.set("Enumeration", [z_pinion], [21]) == ERROR
    assert "is an Int32, not an Enumeration; allowed: fmi3SetInt32" in last(inst)[2]
    assert inst.set("Enumeration", [dissipation, 9999], [1, 1]) == ERROR
    assert "no Enumeration (Int64) variable with value reference 9999" in last(inst)[2]
    spec = dict((s.name, s) for _, s in specs(MeshParameters))["contact.dissipation"]
    assert inst.set("Enumeration", [dissipation], [2**32 + 1]) == ERROR
    assert last(inst)[2] == (f"fmi3SetInt64: value 0 ('contact.dissipation') = {2**32 + 1} "
                             f"is not one of its codes; allowed: {spec.allowed()}; nothing of "
                             "this call was stored")
    assert inst.set("Enumeration", [dissipation], [7]) == OK  # checked by the library at exit
    assert inst.enter(0.0) == OK and inst.exit() == ERROR
    assert "parameter 'contact.dissipation' = 7" in last(inst)[2]
    assert inst.set("Enumeration", [dissipation], [2]) == OK
    assert inst.get("Enumeration", [dissipation]) == (OK, [2])
    # Booleans: bool <-> 0/1
    enabled = mesh.vr("friction.enabled")
    assert inst.set("Boolean", [enabled], [False]) == OK
    assert inst.get("Boolean", [enabled]) == (OK, [False])
    assert inst.set("Boolean", [enabled], [True]) == OK
    assert inst.get("Boolean", [enabled]) == (OK, [True])
    assert inst.exit() == OK, inst.log
    # a set that mixes a good entry with a bad one stores nothing
    w = mesh.vr("pinion.w")
    before = inst.get("Float64", [w])[1]
    assert inst.set("Float64", [w, 9999], [1.5, 1.0]) == ERROR
    assert last(inst)[2] == ("setReal: no Real variable with value reference 9999; nothing of "
                             "this call was stored")
    assert inst.get("Float64", [w])[1] == before
    inst.free()


def test_the_independent_variable_time(mesh):
    inst = mesh.instantiate(b"glue")
    time = mesh.vr("time")
    assert mesh.variables["time"] == (len(mesh.variables) - 1, "Float64", "independent")
    assert inst.get("Float64", [time]) == (OK, [0.0])
    assert inst.enter(0.25) == OK
    w = mesh.vr("wheel.w")
    st, (t, wheel_w) = inst.get("Float64", [time, w])
    assert st == OK and t == 0.25 and wheel_w == inst.get("Float64", [w])[1][0]
    assert inst.exit() == OK
    assert inst.step(0.25, 1e-4) == OK
    assert inst.get("Float64", [w, time, time])[1][1:] == [0.25 + 1e-4] * 2
    assert inst.set("Float64", [w - 1, time], [1.0, 2.0]) == ERROR
    assert last(inst)[2] == (f"fmi3SetFloat64: 'time' (value reference {time}) is the "
                             "independent variable and cannot be set; nothing of this call was "
                             "stored")
    assert inst.reset() == OK and inst.get("Float64", [time]) == (OK, [0.0])
    inst.free()


def test_a_state_taken_before_the_first_step_restores_its_time_and_outputs(mesh):
    """FMU states taken in Initialization Mode at startTime 3, in Instantiated Mode, and
    after terminate from Initialization Mode, set into the instance after a run: `time` is
    the state's in every mode (it read 0 until exitInitializationMode), and the outputs are
    those the state was taken with (wheel.w came back as the earlier run's, 44.57, not 0)."""
    inst = mesh.instantiate(b"glue")
    time, w = mesh.vr("time"), mesh.vr("wheel.w")
    taken = {}
    st, taken["instantiated"] = inst.get_state()
    expected = {"instantiated": inst.get("Float64", [time, w])[1]}
    assert st == OK and inst.enter(3.0) == OK
    st, taken["initialization"] = inst.get_state()
    expected["initialization"] = inst.get("Float64", [time, w])[1]
    assert st == OK and expected["initialization"][0] == 3.0
    assert inst.terminate() == OK
    st, taken["terminated"] = inst.get_state()
    expected["terminated"] = inst.get("Float64", [time, w])[1]
    assert st == OK
    for mode, state in taken.items():  # each set into the instance after a run
        assert inst.reset() == OK, mode
        assert inst.enter(0.0) == OK and inst.exit() == OK and inst.step(0.0, 1e-4) == OK
        assert inst.get("Float64", [w])[1] != [expected[mode][1]]  # the run moved it
        assert inst.set_state(state) == OK, (mode, inst.log[-2:])
        assert inst.get("Float64", [time, w]) == (OK, expected[mode]), mode
    for state in taken.values():
        assert inst.free_state(state) == OK
    inst.free()


def test_arrays_and_types_the_units_lack(mesh):
    inst = mesh.instantiate(b"glue")
    L, vr = mesh.lib, (c_uint * 1)(mesh.vr("gear.backlash"))
    out = (c_double * 1)()
    assert L.fmi3GetFloat64(inst.c, None, 1, out, 1) == ERROR
    assert last(inst)[2] == ("fmi3GetFloat64: nValueReferences = 1 but the value-reference "
                             "array is NULL; nothing done")
    assert L.fmi3SetFloat64(inst.c, vr, 1, None, 1) == ERROR
    assert last(inst)[2] == ("fmi3SetFloat64: nValueReferences = 1 but the value array is "
                             "NULL; nothing done")
    assert L.fmi3GetFloat64(inst.c, vr, 1, out, 2) == ERROR
    assert last(inst)[2].startswith("fmi3GetFloat64: nValues = 2 but nValueReferences = 1: "
                                    "every variable of this FMU is a scalar")
    assert L.fmi3GetFloat64(inst.c, None, 0, None, 0) == OK  # nothing asked
    for kind in ("Float32", "Int8", "UInt8", "Int16", "UInt16", "UInt32", "UInt64"):
        buf = ctypes.create_string_buffer(16)
        assert getattr(L, f"fmi3Get{kind}")(inst.c, vr, 1, buf, 1) == ERROR
        assert last(inst)[2].startswith(f"fmi3Get{kind}: no {kind} variable with value "
                                        "reference ")
        assert getattr(L, f"fmi3Set{kind}")(inst.c, vr, 1, buf, 1) == ERROR
        assert getattr(L, f"fmi3Get{kind}")(inst.c, None, 0, None, 0) == OK
    assert L.fmi3GetClock(inst.c, vr, 1, None) == ERROR
    assert inst.get("Float64", [mesh.vr("gear.backlash")]) == (OK, [1e-4])
    inst.free()


def test_a_null_string_refused_in_every_mode(models):
    """fmi3SetString with a NULL value: refused with a message naming it, in every mode --
    after initialization the fixed parameter's refusal names the value it was given."""
    driveline = models["Driveline"]
    vr = driveline.vr("engine.speed_table")
    inst = driveline.instantiate(b"glue")
    expected = {"instantiated": "is NULL", "initialization": "is NULL",
                "stepping": "is fixed", "terminated": "cannot be set after terminate"}
    for mode, fragment in expected.items():
        if mode == "initialization":
            assert inst.enter(0.0) == OK
        elif mode == "stepping":
            assert inst.exit() == OK and inst.step(0.0, 1e-4) == OK
        elif mode == "terminated":
            assert inst.terminate() == OK
        before = inst.snapshot()
        assert inst.set("String", [vr], [None]) == ERROR, mode
        assert fragment in last(inst)[2], (mode, last(inst))
        assert "NULL" in last(inst)[2] or mode == "terminated", (mode, last(inst))
        assert inst.snapshot() == before
    inst.free()


# ------------------------------------------------------------------ the step
def test_do_step_outputs_and_refusals(mesh):
    inst = mesh.instantiate(b"glue")
    assert inst.step(0.0, 1e-4) == ERROR  # out of order: the library's message
    assert last(inst)[2] == ("doStep: doStep is not allowed in mode 'instantiated' "
                             "(initialize first)")
    inst.free()
    inst = started(mesh)
    status, flags = inst.step_flags(0.0, 1e-4)
    assert (status, flags) == (OK, (False, False, False, 1e-4))
    status, flags = inst.step_flags(0.0, 1e-4)  # does not continue: refused, nothing moved
    assert status == ERROR and flags == (False, False, False, 1e-4)
    assert inst.step_flags(1e-4, -1.0)[0] == ERROR
    L = mesh.lib
    b, t = ctypes.c_bool(), c_double()
    assert L.fmi3DoStep(inst.c, 1e-4, 1e-4, True, None, ctypes.byref(b), ctypes.byref(b),
                        ctypes.byref(t)) == ERROR
    assert last(inst)[2] == ("fmi3DoStep: eventHandlingNeeded is NULL; allowed: a pointer to "
                             "the importer's variable; nothing done")
    assert L.fmi3DoStep(inst.c, 1e-4, 1e-4, True, ctypes.byref(b), ctypes.byref(b),
                        ctypes.byref(b), None) == ERROR
    assert inst.step_flags(1e-4, 1e-4) == (OK, (False, False, False, 2e-4))
    inst.free()


def test_what_the_units_do_not_provide(mesh):
    inst = started(mesh)
    L = mesh.lib
    for call, args, fragment in [
            ("fmi3EnterEventMode", (), "this FMU has no Event Mode (hasEventMode = false)"),
            ("fmi3EnterStepMode", (), "this FMU has no Event Mode"),
            ("fmi3UpdateDiscreteStates", (None,) * 6, "this FMU has no Event Mode"),
            ("fmi3GetDirectionalDerivative", (None, 0, None, 0, None, 0, None, 0),
             "providesDirectionalDerivatives = false"),
            ("fmi3SetTime", (0.0,), "a Model Exchange function")]:
        assert getattr(L, call)(inst.c, *args) == ERROR, call
        assert last(inst)[2].startswith(f"{call}: ") and fragment in last(inst)[2], last(inst)
    assert inst.step(0.0, 1e-4) == OK  # nothing changed
    inst.free()


def test_types_map_onto_the_library_tables(mesh):
    """Every variable of the modelDescription is reachable with the access of its FMI 3.0
    type (a generic table walk: no variable is known to the glue by name)."""
    inst = mesh.instantiate(b"glue")
    for kind in CTYPES:
        names = mesh.names(kind)
        st, values = inst.get(kind, [mesh.vr(n) for n in names])
        assert st == OK, (kind, inst.log[-1:])
        assert len(values) == len(names)
    assert not inst.log
    inst.free()


# ------------------------------------------------------------------ the cost of a call
def test_the_slowest_call_at_costly_states_within_its_bound(fmi3_fmus, tmp_path):
    """Every call timed (tests/adversarial/call_clock.py) while both units run on inputs at
    their declared bounds, for steps of 1e-4 and 1e-3 s, and the mesh holds the fastest pinion
    a state may hold (1.001e7 rad/s, set through an edited, re-sealed state): no call longer
    than its bound (docs/fmi.md: 50 ms per 1e-4 s of step), with the fuzzer's margin for a
    loaded machine; the slowest is printed for the closing note."""
    sys.path.insert(0, str(ROOT / "tests" / "adversarial"))
    from call_clock import LOADED, CallClock, slowest_line
    from raw_fmi import state_payload, with_payload
    from records import Record

    from ..adversarial.boundary_fuzz import (
        EXTREME_ACCELERATIONS,
        EXTREME_LOADS,
        EXTREME_SPEEDS,
    )

    clock = CallClock()
    for name, fmu in fmi3_fmus.items():
        model = Model(unpack(fmu, tmp_path / name))
        model.lib = clock.wrap(model.lib)
        fmi2_types = {"Float64": "Real", "Int32": "Integer", "Enumeration": "Integer"}
        variables = {n: (vr, fmi2_types.get(kind, kind), c)
                     for n, (vr, kind, c) in model.variables.items() if n != "time"}
        for w, a, tau in itertools.product(EXTREME_SPEEDS, EXTREME_ACCELERATIONS, EXTREME_LOADS):
            if name == "Driveline" and (a, tau) != (0.0, 0.0):
                continue
            for h in (1e-4, 1e-3):
                inst = model.instantiate(b"costly")
                assert inst.enter(0.0) == OK and inst.exit() == OK, inst.log
                t = 0.0
                for _ in range(3):
                    values = ({"pinion.phi": w * t, "pinion.w": w, "pinion.a": a,
                               "wheel.tau_load": tau} if name == "GearMeshRattle"
                              else {"wheel.phi": w * t, "wheel.w": w})
                    assert inst.set_named(values) == OK
                    if inst.step(t, h) != OK:
                        break
                    t += h
                inst.free()
        if name == "GearMeshRattle":  # the fastest pinion a state holds, held for a step
            inst = model.instantiate(b"held")
            assert inst.enter(0.0) == OK and inst.exit() == OK and inst.step(0.0, 1e-4) == OK
            blob = inst.serialized()
            record = Record.decode(state_payload(blob), variables)
            record.model["pinion_w"] = 1.001e7
            st, state = inst.deserialize(with_payload(blob, record))
            assert st == OK and inst.set_state(state) == OK, inst.log[-2:]
            assert inst.step(1e-4, 1e-4) == ERROR and "budget" in last(inst)[2]
            inst.free_state(state)
            inst.free()
    summary = clock.summary()
    print(slowest_line("FMI 3.0", summary))
    assert summary["nearest the bound"]["fraction"] <= LOADED, summary["nearest the bound"]
