"""The FMI 2.0 face of the native FMUs (fmi2_functions.c), driven call by call through ctypes:
statuses and messages are the model library's, logged verbatim (as "%s", message, in the
category of the status, whatever debug logging says); what is FMI's is the glue's own --
fmi2Instantiate's checks and the resources folder, NULL pointers and arrays, FMU states (a
tag, the envelope, the record kept as it is until rm_restore checks it), status inquiries and
the functions these units do not provide.  A refused call changes nothing.  What every face
is asked alike (instantiation, values, states) is in tests/faces."""

from __future__ import annotations

import ctypes
from ctypes import c_double, c_uint

import pytest

from ..faces.calls import last, loaded, started
from ..faces.raw_fmi import ERROR, LAST_SUCCESSFUL_TIME, OK, TERMINATED, WARNING


@pytest.fixture(scope="module")
def models(native_fmus, tmp_path_factory):
    return loaded(native_fmus, tmp_path_factory, "glue")


@pytest.fixture
def mesh(models):
    return models["GearMeshRattle"]


# ------------------------------------------------------------------ the library's messages


def test_messages_logged_with_debug_logging_off_and_on(mesh):
    for logging_on in (0, 1):
        inst = mesh.instantiate(b"glue", logging_on=logging_on)
        assert inst.step(0.0, 1e-4) == ERROR
        status, category, message = last(inst)
        assert (status, category) == (ERROR, "logStatusError")  # not "FORMAT": ("%s", text)
        assert message == "doStep: doStep is not allowed in mode 'instantiated' (initialize first)"
        assert inst.logging(0, [b"logAll"]) == OK
        assert inst.step(0.0, 1e-4) == ERROR and len(inst.log) == 2
        inst.free()


def test_step_refusals_and_the_first_step_warning(mesh):
    inst = started(mesh)
    assert inst.step(0.5, 1e-4) == ERROR
    assert last(inst)[2].startswith("doStep: communication point 0.5 s does not continue the "
                                    "last step, which ended at 0")
    assert inst.set_named({"pinion.phi": 1e-3, "wheel.tau_load": 0.2}) == OK
    assert inst.step(0.0, 1e-4) == WARNING  # the library settles the first step, and says so
    status, category, message = last(inst)
    assert (status, category) == (WARNING, "logStatusWarning")
    assert message.startswith("doStep at the first step: the inputs (pinion.phi = ")
    assert inst.step(1e-4, 1e-4) == OK
    inst.free()


def test_get_and_set_refusals(mesh):
    inst = mesh.instantiate(b"glue")
    st, values = inst.get("Real", [9999])
    assert st == ERROR and last(inst)[2] == "getReal: no Real variable with value reference 9999"
    assert values[0] != values[0]  # NaN for the invalid entry
    vr = mesh.vr("gear.z_pinion")
    assert inst.set("Real", [vr], [20.0]) == ERROR  # an Integer, set as a Real
    assert last(inst)[2].startswith(f"setReal: no Real variable with value reference {vr}")
    assert inst.set("Real", [mesh.vr("wheel.w")], [1.0]) == ERROR
    assert last(inst)[2] == ("setReal: 'wheel.w' is an output and cannot be set; nothing of "
                             "this call was stored")
    # one bad entry: nothing of the call stored
    good = mesh.vr("gear.backlash")
    assert inst.set("Real", [good, 9999], [2e-4, 1.0]) == ERROR
    assert inst.get_named("gear.backlash") == 1e-4
    inst.free()


def test_null_arrays_refused_by_the_glue(mesh):
    inst = mesh.instantiate(b"glue")
    L, vr = mesh.lib, (c_uint * 1)(mesh.vr("gear.backlash"))
    out = (c_double * 1)()
    assert L.fmi2GetReal(inst.c, None, 1, out) == ERROR
    assert last(inst)[2] == ("fmi2GetReal: nvr = 1 but the value-reference array is NULL; "
                             "nothing done")
    assert L.fmi2SetReal(inst.c, vr, 1, None) == ERROR
    assert last(inst)[2] == "fmi2SetReal: nvr = 1 but the value array is NULL; nothing done"
    assert L.fmi2GetReal(inst.c, None, 0, None) == OK  # nothing asked
    assert L.fmi2GetRealStatus(inst.c, LAST_SUCCESSFUL_TIME, None) == ERROR
    assert L.fmi2GetFMUstate(inst.c, None) == ERROR
    assert last(inst)[2] == "fmi2GetFMUstate: the FMUstate pointer is NULL"
    assert L.fmi2SetFMUstate(inst.c, None) == ERROR
    assert last(inst)[2] == "fmi2SetFMUstate: the FMU state is NULL"
    assert L.fmi2SerializedFMUstateSize(inst.c, None, None) == ERROR
    assert L.fmi2SetDebugLogging(inst.c, 1, 2, None) == ERROR
    inst.free()


def test_status_inquiries(mesh):
    inst = mesh.instantiate(b"glue")
    st, _ = inst.real_status(LAST_SUCCESSFUL_TIME)
    assert st == ERROR and last(inst)[2] == (
        "getRealStatus(fmi2LastSuccessfulTime): no communication step is possible yet (mode "
        "'instantiated'); allowed after exitInitializationMode")
    assert inst.setup(0.25) == OK and inst.enter() == OK and inst.exit() == OK
    assert inst.real_status(LAST_SUCCESSFUL_TIME) == (OK, 0.25)
    assert inst.step(0.25, 1e-4) == OK
    assert inst.real_status(LAST_SUCCESSFUL_TIME) == (OK, 0.25 + 1e-4)
    value = ctypes.c_int(7)
    assert mesh.lib.fmi2GetBooleanStatus(inst.c, TERMINATED, ctypes.byref(value)) == OK
    assert value.value == 0
    assert mesh.lib.fmi2GetStatus(inst.c, 0, ctypes.byref(value)) == ERROR
    assert last(inst)[2].startswith("fmi2GetStatus: status kind 0 (fmi2DoStepStatus) is not "
                                    "answered here")
    assert mesh.lib.fmi2CancelStep(inst.c) == ERROR
    assert "canRunAsynchronuously = false" in last(inst)[2]
    assert mesh.lib.fmi2GetDirectionalDerivative(inst.c, None, 0, None, 0, None, None) == ERROR
    assert "providesDirectionalDerivative = false" in last(inst)[2]
    inst.free()
