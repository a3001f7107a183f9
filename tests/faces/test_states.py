"""FMU states on every face: the serialized state is the envelope (magic, version, payload size,
FNV-1a checksum, this FMU's token) around the model library's own record (``rm_save``), byte for
byte, and restores into a fresh instance that continues as the original did; states of other
FMUs (another model, another face of the same model) and damaged ones are refused with a
message (the envelope by the face, the record kept as it is until rm_restore checks it); state
handles are reused, and foreign pointers refused, not dereferenced.  A refused call changes
nothing."""

from __future__ import annotations

import ctypes

import pytest

from drive_rattle.interface import MODELS
from drive_rattle.units import Unit

from .calls import last, started
from .conftest import FACES
from .raw_fmi import ERROR, HEADER, OK, Model, fnv1a64, unpack, with_payload
from .twin import KINDS, input_rows


@pytest.mark.parametrize("model", MODELS)
def test_fmu_states_are_the_library_records(face, models, model):
    """At points of the regression inputs the serialized state is the envelope (this FMU's
    token) around the unit's own record, the twin's rm_save at the same point byte for byte;
    deserialized into a fresh instance it continues as the original did."""
    m = models[model]
    names = m.names(causality="input")
    rows = input_rows(model)
    inst = m.instantiate(b"original")
    twin = Unit(KINDS[model], initialize=False)
    assert inst.begin(rows[0][0]) == OK
    twin.call("rm_setup", rows[0][0])
    twin.call("rm_enter_initialization")
    inst.set_named(dict(zip(names, rows[0][1:], strict=True)))
    twin.set(dict(zip(names, rows[0][1:], strict=True)))
    assert inst.exit() == OK
    twin.call("rm_exit_initialization")
    saved, after = None, []
    for k in range(len(rows) - 1):
        inputs = dict(zip(names, rows[k][1:], strict=True))
        assert inst.set_named(inputs) == OK
        twin.set(inputs)
        t, h = rows[k][0], rows[k + 1][0] - rows[k][0]
        assert inst.step(t, h) == OK, inst.log[-2:]
        twin.call("rm_do_step", t, h)
        if k % 40 == 0 or k == 250:
            blob = inst.serialized()
            assert blob[32:32 + len(m.token)] == m.token.encode()
            assert blob[HEADER:] == twin.save(), k
            if k == 250:
                saved = blob
        if saved is not None:
            after.append(inst.snapshot())
    other = m.instantiate(b"restored")
    status, state = other.deserialize(saved)
    assert status == OK and other.set_state(state) == OK, other.log
    assert other.snapshot() == after[0]
    for k in range(251, len(rows) - 1):
        other.set_named(dict(zip(names, rows[k][1:], strict=True)))
        assert other.step(rows[k][0], rows[k + 1][0] - rows[k][0]) == OK
        assert other.snapshot() == after[k - 250], k
    assert not inst.log and not other.log
    for i in (inst, other):
        i.free()
    twin.close()


def test_states_of_other_fmus_and_damaged_states_refused(face, models, request, tmp_path):
    mesh, driveline = models["GearMeshRattle"], models["Driveline"]
    inst = started(mesh)
    assert inst.step(0.0, 1e-4) == OK
    blob = inst.serialized()
    before = inst.snapshot()
    other = started(driveline)
    # the same model on another face: the same record, another token
    twin_face = FACES["native" if face.name != "native" else "fmi3"]
    fmu = request.getfixturevalue(twin_face.fixture)["GearMeshRattle"]
    twin_inst = started(Model(unpack(fmu, tmp_path / twin_face.name)))
    assert twin_inst.step(0.0, 1e-4) == OK
    twin_blob = twin_inst.serialized()
    assert twin_blob[HEADER:] == blob[HEADER:]  # the same record: one model
    assert blob[:8] == twin_blob[:8] == b"RTLSTSER"  # the same envelope,
    assert blob[32:HEADER] != twin_blob[32:HEADER]  # each face's token in it
    assert int.from_bytes(blob[16:24], "little") == len(blob) - HEADER  # the record's size
    deserialize = f"{face.dialect.name('DeserializeFMUState')}: "
    cases = [
        (other.serialized(), "belongs to the FMU with GUID"),
        (twin_blob, "belongs to the FMU with GUID"),
        (blob[:HEADER - 1], "are not a serialized state of a drive-rattle FMU"),
        (blob[:-1], "the serialized state is truncated"),
        (blob[:-1] + bytes([blob[-1] ^ 1]), "corrupt (checksum mismatch)"),
        (b"RTLSTSER" + bytes(4) + blob[12:], "envelope version 0"),
    ]
    for data, fragment in cases:
        status, _ = inst.deserialize(data)
        assert status == ERROR and fragment in last(inst)[2], (fragment, last(inst))
        assert last(inst)[2].startswith(deserialize), last(inst)
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
    # a larger buffer than needed: the state, then zeros; it reads back
    st, state = inst.get_state()
    assert st == OK
    st, big = inst.serialize(state, extra=100)
    assert st == OK and big[-100:] == bytes(100) and inst.deserialize(big)[0] == OK
    assert inst.serialize(state, extra=-1)[0] == ERROR
    assert f"({face.dialect.name('SerializedFMUStateSize')}); nothing written" in last(inst)[2]
    for i in (inst, other, twin_inst):
        i.free()


def test_state_handles_reused_and_foreign_pointers_refused(face, mesh):
    inst = started(mesh)
    get, set_, free = (face.dialect.name(f) for f in ("GetFMUState", "SetFMUState",
                                                      "FreeFMUState"))
    st, state = inst.get_state()
    assert st == OK
    assert inst.step(0.0, 1e-4) == OK
    assert inst.get_state(state)[0] == OK  # reused: the state now holds t = 1e-4
    assert inst.set_state(state) == OK and inst.time() == (OK, 1e-4)
    junk = ctypes.create_string_buffer(b"x" * 200)
    assert getattr(mesh.lib, set_)(inst.c, ctypes.cast(junk, ctypes.c_void_p)) == ERROR
    assert last(inst)[2] == (f"{set_}: not an FMU state of this FMU (made by {get} or "
                             f"{face.dialect.name('DeserializeFMUState')} of {mesh.token}); "
                             "nothing changed")
    assert getattr(mesh.lib, get)(inst.c, None) == ERROR
    assert last(inst)[2] == f"{get}: the {get[7:]} pointer is NULL"
    assert getattr(mesh.lib, set_)(inst.c, None) == ERROR
    # the state passed where its address belongs (fmusim 0.0.39 frees its state files' states
    # so, which crashed the FMU): refused with a message, not dereferenced
    wrong = ctypes.cast(state, ctypes.POINTER(ctypes.c_void_p))
    for call in (free, get):
        assert getattr(mesh.lib, call)(inst.c, wrong) == ERROR
        assert last(inst)[2].startswith(f"{call}: {get[7:]} points to an FMU state, not to "
                                        "the host's variable that holds one (FMI asks for its "
                                        "address, &state); nothing ")
    assert inst.set_state(state) == OK  # nothing freed
    assert inst.free_state(state) == OK and not state
    assert getattr(mesh.lib, free)(inst.c, ctypes.POINTER(ctypes.c_void_p)()) == OK  # ignored
    _, _other = inst.get_state()
    inst.free()  # frees its states too (no leak: tests/sanitize)
