"""The FMI 2.0 face of the native FMUs (fmi2_functions.c), driven call by call through ctypes:
statuses and messages are the model library's, logged verbatim (as "%s", message, in the
category of the status, whatever debug logging says); what is FMI's is the glue's own --
fmi2Instantiate's checks and the resources folder, NULL pointers and arrays, FMU states (a
tag, the envelope, the record kept as it is until rm_restore checks it), status inquiries and
the functions these units do not provide.  A refused call changes nothing."""

from __future__ import annotations

import ctypes
import os
import subprocess
import sys
from ctypes import POINTER, c_double, c_uint
from pathlib import Path

import pytest

from drive_rattle.library import ModelError
from drive_rattle.units import Unit

from ..adversarial.raw_fmi import (
    ERROR,
    HEADER,
    LAST_SUCCESSFUL_TIME,
    MODEL_EXCHANGE,
    OK,
    TERMINATED,
    WARNING,
    Model,
    fnv1a64,
    unpack,
    with_payload,
)
from .twin import KINDS

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def models(native_fmus, tmp_path_factory):
    return {name: Model(unpack(fmu, tmp_path_factory.mktemp(f"glue_{name}")))
            for name, fmu in native_fmus.items()}


@pytest.fixture
def mesh(models):
    return models["GearMeshRattle"]


def twin_error(model: str, *calls) -> str:
    """The library's message for the last of ``calls`` (name, args...) on a fresh unit."""
    with Unit(KINDS[model], initialize=False) as unit:
        for name, *args in calls[:-1]:
            getattr(unit, name)(*args) if not name.startswith("rm_") else unit.call(name, *args)
        name, *args = calls[-1]
        with pytest.raises(ModelError) as err:
            getattr(unit, name)(*args) if not name.startswith("rm_") else unit.call(name, *args)
        return str(err.value)


def started(model: Model, **values):
    inst = model.instantiate(b"glue")
    assert inst is not None, model.pending_log
    assert inst.setup(0.0) == OK and inst.enter() == OK
    assert inst.set_named(values) == OK
    assert inst.exit() == OK, inst.log
    return inst


def last(inst) -> tuple[int, str, str]:
    return inst.log[-1]


# ------------------------------------------------------------------ the library's messages
def test_invalid_parameter_refused_with_the_library_message(mesh):
    inst = mesh.instantiate(b"glue")
    assert inst.setup(0.0) == OK and inst.enter() == OK
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


def test_parameters_fixed_after_initialization_inputs_not(mesh):
    """The library decides what may be set when; the glue adds no rule: after initialization
    a parameter is refused, an input accepted; after fmi2Terminate both are refused (FMI 2.0's
    co-simulation state table allows no fmi2Set* in the terminated state)."""
    inst = started(mesh)
    assert inst.set_named({"gear.backlash": 2e-4}) == ERROR
    assert last(inst)[2] == twin_error(
        "GearMeshRattle", ("initialize", 0.0), ("set", {"gear.backlash": 2e-4}))
    assert inst.set_named({"pinion.w": 80.0}) == OK
    assert inst.terminate() == OK
    assert inst.set_named({"pinion.w": 80.0}) == ERROR
    assert "mode is 'terminated'" in last(inst)[2]
    assert inst.set_named({"wheel.J": 1e-3}) == ERROR
    assert "mode is 'terminated'" in last(inst)[2]
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


def test_reset_is_a_fresh_instance(mesh):
    fresh = started(mesh)
    inst = started(mesh, **{"gear.backlash": 2e-4})
    for k in range(5):
        assert inst.step(k * 1e-4, 1e-4) == OK
    assert inst.reset() == OK
    assert inst.setup(0.0) == OK and inst.enter() == OK and inst.exit() == OK
    assert inst.snapshot() == fresh.snapshot()
    fresh.free()
    inst.free()


def test_strings_checked_by_the_library(models):
    driveline = models["Driveline"]
    inst = driveline.instantiate(b"glue")
    vr = driveline.vr("engine.speed_table")
    assert inst.set("String", [vr], [b"\xff.csv"]) == ERROR
    assert last(inst)[2].startswith("setString: value 0 ('engine.speed_table') is not valid "
                                    "UTF-8")
    assert inst.set("String", [vr], ["no such table.csv"]) == OK
    assert inst.setup(0.0) == OK and inst.enter() == OK and inst.exit() == ERROR
    assert last(inst)[2].startswith("exitInitializationMode: parameter 'engine.speed_table' "
                                    "= 'no such table.csv' cannot be read")
    inst.free()
    # a relative name resolves against this FMU's resources folder
    (driveline.root / "resources" / "run-up.csv").write_text("0,80\n1,90\n", encoding="utf-8")
    inst = driveline.instantiate(b"glue")
    assert inst.set("String", [vr], ["run-up.csv"]) == OK
    assert inst.setup(0.0) == OK and inst.enter() == OK and inst.exit() == OK, inst.log
    assert inst.get_named("pinion.w") == 80.0
    inst.free()


# ------------------------------------------------------------------ fmi2Instantiate
def test_instantiate_refusals(models, tmp_path):
    mesh, driveline = models["GearMeshRattle"], models["Driveline"]
    unpacked_root = str(mesh.root).encode()
    cases = [
        (dict(name=b"  "), "instanceName is blank"),
        (dict(name=b"\xff"), "is not valid UTF-8"),
        (dict(kind=MODEL_EXCHANGE), "fmuType = 0 (fmi2ModelExchange) is not supported"),
        (dict(guid=b"{not-this-one}"), "GUID {not-this-one} does not match this FMU's"),
        (dict(location=None, default_location=False), "fmuResourceLocation '(null)' is NULL"),
        (dict(location=b""), "fmuResourceLocation '' is empty"),
        (dict(location=b"resources"), "fmuResourceLocation 'resources' is a relative path"),
        (dict(location=b"http://example.org/r"), "has the URI scheme 'http'"),
        (dict(location=b"file://otherhost/r"), "names a file on another host"),
        (dict(location=b"file:///tmp/x%00y"), "holds %00"),
        (dict(location=unpacked_root), "the folder the FMU was unpacked to"),
        (dict(location=str(tmp_path).encode()), "which has no model_identifier.txt"),
        (dict(location=str(tmp_path / "missing").encode()), "no such file or directory"),
        (dict(location=driveline.resources_uri()), "the resources of FMU 'Driveline', not "
                                                   "of GearMeshRattle"),
    ]
    for kwargs, fragment in cases:
        assert mesh.instantiate(**kwargs) is None, kwargs
        (status, category, message), = mesh.pending_log
        assert (status, category) == (ERROR, "logStatusError")
        assert message.startswith("rattle native FMU: fmi2Instantiate: ")
        assert fragment in message, (kwargs, message)
    # the plain absolute path of the resources folder is accepted too
    inst = mesh.instantiate(location=str(mesh.root / "resources").encode())
    assert inst is not None
    inst.free()


FIFO_PROBE = """
import os, sys
sys.path[:0] = sys.argv[3:]
from tests.adversarial.raw_fmi import Model
m = Model(sys.argv[1])
assert m.instantiate(location=sys.argv[2].encode()) is None
print(m.pending_log[0][2])
"""


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
def test_a_fifo_as_the_marker_does_not_block(mesh, tmp_path):
    """A FIFO named model_identifier.txt is refused at once (issue 20, item 6): the marker is
    read only when it is a regular file, opened non-blocking."""
    folder = tmp_path / "resources"
    folder.mkdir()
    os.mkfifo(folder / "model_identifier.txt")
    run = subprocess.run([sys.executable, "-c", FIFO_PROBE, str(mesh.root), str(folder),
                          str(ROOT), *sys.path], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    assert "whose model_identifier.txt is a FIFO, not a regular file" in run.stdout


# ------------------------------------------------------------------ FMU states
def test_states_of_other_fmus_and_damaged_states_refused(models):
    mesh, driveline = models["GearMeshRattle"], models["Driveline"]
    inst = started(mesh)
    assert inst.step(0.0, 1e-4) == OK
    blob = inst.serialized()
    before = inst.snapshot()
    other = started(driveline)
    cases = [
        (other.serialized(), "belongs to the FMU with GUID"),
        (blob[:HEADER - 1], "are not a serialized state of a drive-rattle FMU"),
        (blob[:-1], "the serialized state is truncated"),
        (blob[:-1] + bytes([blob[-1] ^ 1]), "corrupt (checksum mismatch)"),
        (b"RTLSTSER" + bytes(4) + blob[12:], "envelope version 0"),
    ]
    for data, fragment in cases:
        status, _ = inst.deserialize(data)
        assert status == ERROR and fragment in last(inst)[2], (fragment, last(inst))
        assert last(inst)[2].startswith("fmi2DeSerializeFMUstate: ")
    # a damaged record in an intact envelope is kept as it is, and refused by rm_restore
    record = bytearray(blob[HEADER:])
    for damage, fragment in [(bytes(record[:60]), "the record ends before variable"),
                             (b"nonsense" + bytes(record[8:]), "no record header"),
                             (bytes(record) + b"\0", "1 bytes follow the end of the record")]:
        status, state = inst.deserialize(with_payload(blob, damage))
        assert status == OK
        assert inst.set_state(state) == ERROR
        message = last(inst)[2]
        assert message.startswith("setFMUstate: the FMU state is invalid: ") and fragment in \
            message, message
        assert inst.free_state(state) == OK
    assert inst.snapshot() == before  # nothing changed
    assert fnv1a64(blob[HEADER:]) == int.from_bytes(blob[24:32], "little")
    inst.free()
    other.free()


def test_state_handles_reused_and_foreign_pointers_refused(mesh):
    inst = started(mesh)
    st, state = inst.get_state()
    assert st == OK
    assert inst.step(0.0, 1e-4) == OK
    assert inst.get_state(state)[0] == OK  # reused: the state now holds t = 1e-4
    assert inst.set_state(state) == OK and inst.real_status(LAST_SUCCESSFUL_TIME)[1] == 1e-4
    junk = ctypes.create_string_buffer(b"x" * 200)
    assert mesh.lib.fmi2SetFMUstate(inst.c, ctypes.cast(junk, ctypes.c_void_p)) == ERROR
    assert "not an FMU state of this FMU" in last(inst)[2]
    # the state passed where its address belongs (fmusim 0.0.39 frees its state files' states
    # so, which crashed the FMU): refused with a message, not dereferenced
    wrong = ctypes.cast(state, POINTER(ctypes.c_void_p))
    for call in ("fmi2FreeFMUstate", "fmi2GetFMUstate"):
        assert getattr(mesh.lib, call)(inst.c, wrong) == ERROR
        assert last(inst)[2].startswith(f"{call}: FMUstate points to an FMU state, not to the "
                                        "host's variable that holds one")
    assert inst.free_state(state) == OK and not state
    assert mesh.lib.fmi2FreeFMUstate(inst.c, POINTER(ctypes.c_void_p)()) == OK  # ignored
    _, _other = inst.get_state()
    inst.free()  # frees its states too (no leak: tests/sanitize)
