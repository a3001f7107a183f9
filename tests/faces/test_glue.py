"""The FMI glue of every face (fmu_src/fmi_common with fmu_src/fmi2 or fmu_src/fmi3 on the C
faces; the shim before pythonfmu's wrapper on the pythonfmu face), call by call through the raw
driver: which of the library's messages reach the host's logger and how (verbatim, as "%s",
message, in the category of the status), the refusals of gets and sets, NULL arrays and
pointers, the time reached, the step's refusals, the functions these units do not provide and
the types every variable is reached with. What differs between the standards (their spelling of
a function, FMI 3.0's logging by category, its step outputs) is the face's parameter here; what
only one standard has is in test_fmi2_only.py and test_fmi3_only.py. A refused call changes
nothing."""

from __future__ import annotations

import zipfile
from ctypes import c_double, c_uint
from xml.etree import ElementTree

import pytest

from .calls import last, started
from .raw_fmi import ERROR, OK, WARNING

#: The library's messages these tests provoke (the faces pass them on verbatim).
NOT_INITIALIZED = "doStep: doStep is not allowed in mode 'instantiated' (initialize first)"
FIRST_STEP = "doStep at the first step: the inputs (pinion.phi = "
#: The inputs that make the library settle its first step (and warn about it).
UNSETTLED = {"pinion.phi": 1e-3, "wheel.tau_load": 0.2}
#: standard -> the type a Real is got and set as
REAL = {"2.0": "Real", "3.0": "Float64"}
#: standard -> the name of the count of value references in the glue's messages
N_REFERENCES = {"2.0": "nvr", "3.0": "nValueReferences"}


# ------------------------------------------------------------------ the library's messages
#: (logging on at instantiation, SetDebugLogging's (on, categories) or None) -> whether a
#: warning reaches the logger, by standard.  FMI 2.0's faces log every non-OK status whatever
#: debug logging says; FMI 3.0's logs a warning only while logStatusWarning or logAll is on
#: (SetDebugLogging with no category: all of them; with some: those only).  Errors reach the
#: logger always, on both.
LOGGING = [
    ((False, None), {"2.0": True, "3.0": False}),
    ((True, None), {"2.0": True, "3.0": True}),
    ((False, (True, None)), {"2.0": True, "3.0": True}),
    ((False, (True, [b"logStatusWarning"])), {"2.0": True, "3.0": True}),
    ((False, (True, [b"logAll"])), {"2.0": True, "3.0": True}),
    ((False, (True, [b"logStatusError"])), {"2.0": True, "3.0": False}),
    ((True, (False, None)), {"2.0": True, "3.0": False}),
    ((True, (False, [b"logAll"])), {"2.0": True, "3.0": True}),  # logStatusWarning stays on
]


def logging_id(on: bool, debug) -> str:
    calls = "" if debug is None else f"-then-{'on' if debug[0] else 'off'}" + "".join(
        f"-{c.decode()}" for c in debug[1] or [])
    return f"instantiated-{'on' if on else 'off'}{calls}"


@pytest.mark.parametrize(("logging", "shown"), LOGGING,
                         ids=[logging_id(*logging) for logging, _ in LOGGING])
def test_errors_always_logged_warnings_as_the_standard_says(face, mesh, logging, shown):
    logging_on, debug = logging
    inst = mesh.instantiate(b"glue", logging_on=logging_on)
    if debug is not None:
        assert inst.logging(*debug) == OK, inst.log
    assert inst.step(0.0, 1e-4) == ERROR  # out of order: the library's message, always
    # once, in the category of its status (not "FORMAT": logged as ("%s", text))
    assert inst.log == [(ERROR, "logStatusError", NOT_INITIALIZED)], inst.log
    assert inst.begin(0.0) == OK and inst.exit() == OK, inst.log
    assert inst.set_named(UNSETTLED) == OK
    before = len(inst.log)
    assert inst.step(0.0, 1e-4) == WARNING  # the library settles the first step, and says so
    warnings = [m for s, _, m in inst.log[before:] if s == WARNING]
    assert bool(warnings) == shown[face.standard], (logging, inst.log)
    if warnings:
        assert warnings == [last(inst)[2]] and last(inst)[:2] == (WARNING, "logStatusWarning")
        assert warnings[0].startswith(FIRST_STEP), warnings
    assert inst.step(0.5, 1e-4) == ERROR  # errors: always
    assert last(inst)[:2] == (ERROR, "logStatusError")
    assert last(inst)[2].startswith("doStep: communication point 0.5 s does not continue the "
                                    "last step, which ended at 0.0001"), last(inst)
    assert inst.step(1e-4, 1e-4) == OK
    inst.free()


def test_debug_logging_categories(face, mesh, face_fmus):
    """Every category of the modelDescription is accepted; a NULL one, or a NULL array of
    them, is refused; FMI 3.0's face also refuses a name that is not one of its categories
    (FMI 2.0's logs every non-OK status whatever the categories say, so it has no use for
    their names)."""
    inst = mesh.instantiate(b"glue")
    with zipfile.ZipFile(face_fmus["GearMeshRattle"]) as z:
        md = ElementTree.fromstring(z.read("modelDescription.xml"))
    names = [c.get("name").encode() for c in md.find("LogCategories")]
    assert names == [b"logStatusWarning", b"logStatusDiscard", b"logStatusError",
                     b"logStatusFatal", b"logAll"]
    assert inst.logging(True, names) == OK, inst.log
    function = face.dialect.name("SetDebugLogging")
    assert inst.logging(True, [b"logAll", None]) == ERROR
    assert last(inst)[2].startswith(f"{function}: "), last(inst)
    assert mesh.call("SetDebugLogging")(inst.c, True, 2, None) == ERROR
    assert last(inst)[2].startswith(f"{function}: "), last(inst)
    if face.standard == "3.0":
        assert inst.logging(True, [b"logEvents"]) == ERROR
        assert last(inst)[2].startswith(f"{function}: category 'logEvents' is not one of "
                                        "this FMU's; allowed: logStatusWarning, ")
    inst.free()


# ------------------------------------------------------------------ values
def test_get_and_set_refusals(face, mesh):
    """An unknown value reference, a Real set into an integer variable, an output set: each
    refused with the library's message; a set that mixes a good entry with a bad one stores
    nothing."""
    real = REAL[face.standard]
    inst = mesh.instantiate(b"glue")
    st, values = inst.get(real, [9999])
    assert st == ERROR and last(inst)[2] == "getReal: no Real variable with value reference 9999"
    assert values[0] != values[0]  # NaN for the invalid entry
    vr = mesh.vr("gear.z_pinion")
    assert inst.set(real, [vr], [20.0]) == ERROR  # an integer, set as a Real
    assert last(inst)[2].startswith(f"setReal: no Real variable with value reference {vr}")
    assert inst.set(real, [mesh.vr("wheel.w")], [1.0]) == ERROR
    assert last(inst)[2] == ("setReal: 'wheel.w' is an output and cannot be set; nothing of "
                             "this call was stored")
    for name in ("gear.backlash", "pinion.w"):  # a parameter, an input
        before = inst.get_named(name)
        assert inst.set(real, [mesh.vr(name), 9999], [before + 1.5, 1.0]) == ERROR
        assert last(inst)[2] == ("setReal: no Real variable with value reference 9999; "
                                 "nothing of this call was stored")
        assert inst.get_named(name) == before
    assert inst.get_named("gear.backlash") == 1e-4
    inst.free()


def test_null_arrays_and_pointers_refused_by_the_glue(face, mesh):
    inst = mesh.instantiate(b"glue")
    vr, out = (c_uint * 1)(mesh.vr("gear.backlash")), (c_double * 1)()
    get, set_ = (mesh.call(f"{f}{REAL[face.standard]}") for f in ("Get", "Set"))
    counts = (1,) if face.dialect.counts_values else ()
    nothing = (0,) if face.dialect.counts_values else ()
    count = N_REFERENCES[face.standard]
    # pythonfmu's shim says what is NULL, not that nothing was done
    done = "; nothing done" if face.native else ""
    assert get(inst.c, None, 1, out, *counts) == ERROR
    assert last(inst)[2] == (f"{get.__name__}: {count} = 1 but the value-reference array is "
                             f"NULL{done}")
    assert set_(inst.c, vr, 1, None, *counts) == ERROR
    assert last(inst)[2] == f"{set_.__name__}: {count} = 1 but the value array is NULL{done}"
    assert get(inst.c, None, 0, None, *nothing) == OK  # nothing asked
    get_state, set_state = (face.dialect.name(f) for f in ("GetFMUState", "SetFMUState"))
    assert mesh.call("GetFMUState")(inst.c, None) == ERROR
    assert last(inst)[2] == f"{get_state}: the {get_state[7:]} pointer is NULL"
    assert mesh.call("SetFMUState")(inst.c, None) == ERROR
    assert last(inst)[2] == f"{set_state}: the FMU state is NULL"
    assert mesh.call("SerializedFMUStateSize")(inst.c, None, None) == ERROR
    assert inst.get_named("gear.backlash") == 1e-4  # nothing changed
    inst.free()


@pytest.mark.parametrize("model", ["GearMeshRattle", "Driveline"])
def test_types_map_onto_the_library_tables(face, models, model):
    """Every variable of the modelDescription is reachable with the access of its type in the
    face's standard (a generic table walk: no variable is known to the glue by name)."""
    m = models[model]
    inst = m.instantiate(b"glue")
    for kind in face.dialect.types:
        names = m.names(kind)
        st, values = inst.get(kind, [m.vr(n) for n in names])
        assert st == OK, (kind, inst.log[-1:])
        assert len(values) == len(names)
    assert not inst.log
    inst.free()


def test_a_null_string_refused_in_every_mode(face, models):
    """A NULL String value: refused with a message naming it, in every mode -- after
    initialization the fixed parameter's refusal names the value it was given."""
    driveline = models["Driveline"]
    vr = driveline.vr("engine.speed_table")
    inst = driveline.instantiate(b"glue")
    expected = {"instantiated": "is NULL", "initialization": "is NULL",
                "stepping": "is fixed", "terminated": "cannot be set after terminate"}
    if not face.native:  # pythonfmu's shim refuses a NULL before Python sees it
        expected = dict.fromkeys(expected, "is NULL")
    for mode, fragment in expected.items():
        if mode == "initialization":
            assert inst.begin(0.0) == OK
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


# ------------------------------------------------------------------ time and the step
def test_the_time_reached(face, mesh):
    """The time reached (FMI 2.0: fmi2GetRealStatus(fmi2LastSuccessfulTime); FMI 3.0: the
    independent variable time) is the start time after initialization and the end of the last
    step after one; before initialization FMI 2.0 has none (refused with the library's
    reason), FMI 3.0's time reads 0."""
    inst = mesh.instantiate(b"glue")
    st, t = inst.time()
    if face.standard == "2.0":
        assert st == ERROR and last(inst)[2] == (
            "getRealStatus(fmi2LastSuccessfulTime): no communication step is possible yet "
            "(mode 'instantiated'); allowed after exitInitializationMode")
    else:
        assert (st, t) == (OK, 0.0)
    assert inst.begin(0.25) == OK and inst.exit() == OK
    assert inst.time() == (OK, 0.25)
    assert inst.step(0.25, 1e-4) == OK
    assert inst.time() == (OK, 0.25 + 1e-4)
    inst.free()


def test_step_refusals_change_nothing(face, mesh):
    """A step out of order, one that does not continue the last, a negative one: refused with
    the library's message, the time reached unchanged, the next step accepted (FMI 3.0's step
    outputs: no event, no termination, no early return, the step's end)."""
    fmi3 = face.standard == "3.0"
    inst = mesh.instantiate(b"glue")
    assert inst.step(0.0, 1e-4) == ERROR
    assert last(inst)[2] == NOT_INITIALIZED
    inst.free()
    inst = started(mesh)
    status, flags = inst.step_flags(0.0, 1e-4)
    assert status == OK and flags == ((False, False, False, 1e-4) if fmi3 else None)
    status, flags = inst.step_flags(0.0, 1e-4)  # does not continue: refused, nothing moved
    assert status == ERROR and flags == ((False, False, False, 1e-4) if fmi3 else None)
    assert last(inst)[2].startswith("doStep: communication point 0 s does not continue the "
                                    "last step, which ended at 0.0001"), last(inst)
    assert inst.step(1e-4, -1.0) == ERROR
    assert last(inst)[2].startswith("doStep: "), last(inst)
    assert inst.time() == (OK, 1e-4)
    status, flags = inst.step_flags(1e-4, 1e-4)
    assert status == OK and flags == ((False, False, False, 2e-4) if fmi3 else None)
    inst.free()


#: standard -> (function, arguments after the instance, a fragment of its refusal) of what
#: these units do not provide (docs/fmi.md, docs/fmi3.md: no asynchronous steps, no
#: directional derivatives, no Event Mode, no Model Exchange)
NOT_PROVIDED = {
    "2.0": [("CancelStep", (), "canRunAsynchronuously = false"),
            ("GetDirectionalDerivative", (None, 0, None, 0, None, None),
             "providesDirectionalDerivative = false")],
    "3.0": [("EnterEventMode", (), "this FMU has no Event Mode (hasEventMode = false)"),
            ("EnterStepMode", (), "this FMU has no Event Mode"),
            ("UpdateDiscreteStates", (None,) * 6, "this FMU has no Event Mode"),
            ("GetDirectionalDerivative", (None, 0, None, 0, None, 0, None, 0),
             "providesDirectionalDerivatives = false"),
            ("SetTime", (0.0,), "a Model Exchange function")],
}


def test_what_the_units_do_not_provide(face, mesh):
    inst = started(mesh)
    for call, args, fragment in NOT_PROVIDED[face.standard]:
        name = face.prefix + call
        assert getattr(mesh.lib, name)(inst.c, *args) == ERROR, name
        assert last(inst)[2].startswith(f"{name}: ") and fragment in last(inst)[2], last(inst)
    assert inst.step(0.0, 1e-4) == OK  # nothing changed
    inst.free()
