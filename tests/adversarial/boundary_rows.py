"""The FMI boundary's cases (no host crash, no leak, no half-applied call, whatever a master
passes), one function per row, each run against the built FMUs of one face in a child
process:

    python boundary_rows.py <row> <GearMeshRattle.fmu> <Driveline.fmu> <work folder>
        [--keep-going]

(``<row>`` may be several, "1,5,7", or "all": each in its own folder below the work folder;
with --keep-going every row named runs, each reporting "row <k> ok" or "row <k> FAILED:
<reason>" on a line of its own, its traceback on stderr after "=== row <k>".)  A row passes
when the function returns (exit code 0); a failed check is an AssertionError (exit code 1), a
crash of the host a signal.

Every row is written once for FMI 2.0 and FMI 3.0: the FMUs are driven through raw_fmi.py,
whose dialect (chosen by the modelDescription) holds what the standards name or pass
differently -- the types' names (``Model.kind``: "Real" or "Float64"), the start time
(``Instance.begin``), the time reached (``Instance.time``), the resources argument, the
interfaces these FMUs refuse.  A part of a row that FMI 3.0 does not have is asked as its
counterpart there, or left out with the reason in the row's docstring.
test_fmi_boundary.py runs every row on every face; tests/sanitize/test_boundary_sanitized.py
runs them against sanitizer builds.
"""

from __future__ import annotations

import json
import math
import os
import resource
import struct
import subprocess
import sys
import time
import traceback
from ctypes import c_void_p
from pathlib import Path

from raw_fmi import (
    ERROR,
    HEADER,
    OK,
    Model,
    state_payload,
    unpack,
    with_payload,
)
from records import Record

from drive_rattle.parameters import DrivelineParameters

H = 1e-4
#: The default drag, which the Driveline hands to the wheel in steady state.
DRIVELINE_DRAG = DrivelineParameters().drag
MESH_INPUTS = {"pinion.phi": 0.0, "pinion.w": 86.92, "pinion.a": 0.0, "wheel.tau_load": 0.15}
DRIVE_INPUTS = {"wheel.phi": 0.0, "wheel.w": 44.57}


def refused(inst, status: int, since: int, *fragments: str) -> str:
    """Assert that a call was refused with an Error status and a logged message holding
    ``fragments``; returns the message."""
    messages = inst.messages(since, ERROR)
    assert status == ERROR, (status, inst.log[since:])
    assert messages, f"refused without a message: {inst.log[since:]}"
    text = "\n".join(messages)
    for fragment in fragments:
        assert fragment in text, (fragment, text)
    return text


def started(model: Model, inputs: dict, params: dict | None = None, steps: int = 0,
            name: bytes = b"inst"):
    """An instance initialized with ``params`` and ``inputs`` and stepped ``steps`` times;
    the mesh's pinion moves on with its speed."""
    inst = model.instantiate(name)
    assert inst is not None, model.pending_log
    assert inst.begin(0.0) == OK, inst.log
    assert inst.set_named({**(params or {}), **inputs}) == OK, inst.log
    assert inst.exit() in (OK,), inst.log
    finite_outputs(inst, "after exitInitializationMode")
    for k in range(steps):
        advance(inst, k)
    return inst


def finite_outputs(inst, where: str = "") -> None:
    """An output that a get answers with OK is finite (an
    output that cannot be computed is refused)."""
    real = inst.m.kind("Real")
    names = inst.m.names(real, "output")
    st, values = inst.get(real, [inst.m.vr(n) for n in names])
    if st != OK:  # which ones: each alone
        values = [v if s == OK else 0.0 for n in names
                  for s, (v,) in [inst.get(real, [inst.m.vr(n)])]]
    bad = [(n, v) for n, v in zip(names, values, strict=True) if not math.isfinite(v)]
    assert not bad, f"{where}: non-finite outputs answered with OK: {bad}"


def advance(inst, k: int, h: float = H) -> int:
    if "pinion.w" in inst.m.variables and inst.m.variables["pinion.w"][2] == "input":
        inst.set_named({"pinion.phi": inst.get_named("pinion.w") * k * h})
    st = inst.step(k * h, h)
    assert st == OK, inst.log[-3:]
    finite_outputs(inst, f"after step {k}")
    return st


def run_outputs(inst, k0: int, n: int) -> list:
    rows = []
    for k in range(k0, k0 + n):
        advance(inst, k)
        rows.append(inst.snapshot())
    return rows


def healthy(model: Model, inputs: dict) -> None:
    """The process still makes working instances."""
    inst = started(model, inputs, steps=3)
    inst.free()


# ------------------------------------------------------------------ the rows
def row_1(fmus, work):
    """An unpack folder whose name holds a literal "%20" (fmpy percent-encodes it as %2520);
    raw, the folder given as a file URI and as a plain path (FMI 3.0's form)."""
    env = {**os.environ, "TMPDIR": str(work / "x%20y")}
    (work / "x%20y").mkdir()
    code = ("import fmpy, sys\n"
            "for f in sys.argv[1:]:\n"
            "    r = fmpy.simulate_fmu(f, stop_time=0.001, output_interval=1e-4)\n"
            "    assert len(r) == 11, len(r)\n"
            "print('simulated')\n")
    run = subprocess.run([sys.executable, "-c", code, *map(str, fmus.values())], env=env,
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0 and "simulated" in run.stdout, (run.returncode, run.stderr[-2000:])
    # And raw: the folder itself named with %20, as a file URI and as a plain path.
    for name, fmu in fmus.items():
        model = Model(unpack(fmu, work / f"{name} %20 100%"))
        for location in (model.resources_uri(), os.fsencode(model.root / "resources")):
            inst = model.instantiate(location=location)
            assert inst is not None, model.pending_log
            assert inst.begin() == OK
            assert inst.set_named(MESH_INPUTS if name == "GearMeshRattle" else DRIVE_INPUTS) == OK
            assert inst.exit() == OK, inst.log  # the model library was found there
            advance(inst, 0)
            inst.free()


def row_2(fmus, work):
    """Resource locations that are not this FMU's resources folder: refused, NULL, logged.
    FMI 3.0 lets an importer without a resources folder pass NULL: there it is accepted (the
    instance steps; relative speed-table paths then resolve against the working directory)."""
    for name, fmu in fmus.items():
        other = "Driveline" if name == "GearMeshRattle" else "GearMeshRattle"
        model = Model(unpack(fmu, work / name))
        foreign = unpack(fmus[other], work / f"{other}-foreign")
        gone = unpack(fmu, work / f"{name}-deleted")
        subprocess.run(["rm", "-rf", str(gone)], check=True)
        missing = "cannot be opened: no such file or directory"
        cases = {
            b"file://" + os.fsencode(model.root): "the folder the FMU was unpacked to",
            os.fsencode(model.root): "the folder the FMU was unpacked to",
            os.fsencode(gone / "resources"): missing,
            b"file://" + os.fsencode(work / "missing" / "resources"): missing,
            b"resources": "relative path",
            b"file:resources": "relative file URI",
            b"http://example.com/fmu/resources": "URI scheme 'http'",
            b"file://otherhost/tmp/resources": "another host",
            b"": "empty",
            b"file:///tmp/a%00b": "%00",
            os.fsencode(foreign / "resources"): f"the resources of FMU '{other}'",
            os.fsencode(work): "not the resources folder of this FMU",
        }
        for location, fragment in cases.items():
            assert model.instantiate(location=location) is None, location
            text = " ".join(m for s, _, m in model.pending_log if s >= ERROR)
            assert model.dialect.resources_argument in text and fragment in text, (location,
                                                                                   text)
        null = model.instantiate(location=None, default_location=False)
        if model.dialect.null_resources_accepted:
            assert null is not None, model.pending_log
            assert null.begin() == OK
            assert null.set_named(MESH_INPUTS if name == "GearMeshRattle" else DRIVE_INPUTS) == OK
            assert null.exit() == OK, null.log
            advance(null, 0)
            null.free()
        else:
            assert null is None
            assert "is NULL" in model.pending_log[-1][2]
        if not model.native:  # pythonfmu imports the slave module from its resources
            resources = model.root / "resources"
            (resources / f"{name}.py").rename(resources / "moved.py")
            assert model.instantiate() is None
            assert "lacks the slave module" in model.pending_log[-1][2]
            (resources / "moved.py").rename(resources / f"{name}.py")
        healthy(model, MESH_INPUTS if name == "GearMeshRattle" else DRIVE_INPUTS)


def row_3(fmus, work):
    """SetDebugLogging with a NULL category (or NULL array) or one that is not UTF-8:
    refused, nothing changed."""
    model = Model(unpack(fmus["GearMeshRattle"], work / "m"))
    inst = started(model, MESH_INPUTS)
    n = len(inst.log)
    refused(inst, inst.logging(1, [b"logStatusError", None]), n, "category 1 of 2 is NULL")
    n = len(inst.log)
    refused(inst, inst.call("SetDebugLogging", 1, 2, None), n, "categories is NULL")
    n = len(inst.log)
    refused(inst, inst.logging(1, [b"logAll\xff"]), n, model.dialect.bad_category)
    # Logging stayed off: a refused step is still reported (always), nothing else is logged.
    assert inst.logging(0, []) == OK
    advance(inst, 0)
    assert inst.logging(1, [b"logStatusError", b"logAll"]) == OK
    advance(inst, 1)
    inst.free()


def row_4(fmus, work):
    """Instance names and String values that are not UTF-8."""
    for name, fmu in fmus.items():
        model = Model(unpack(fmu, work / name))
        for bad, fragment in ((b"\xdcbersetzung", "not valid UTF-8"),
                              (b"ok\xc3", "not valid UTF-8"), (b"", "blank"),
                              (b"  ", "blank"), (None, "NULL"),
                              (b"\xed\xa0\x80", "not valid UTF-8")):  # a UTF-16 surrogate
            assert model.instantiate(name=bad) is None
            assert any(fragment in m for _, _, m in model.pending_log), (bad, model.pending_log)
        inst = model.instantiate(name="Übersetzung".encode())  # UTF-8: fine
        assert inst is not None
        inst.free()
    model = Model(unpack(fmus["Driveline"], work / "d2"))
    inst = model.instantiate()
    assert inst.begin() == OK
    vr = model.vr("engine.speed_table")
    before = inst.snapshot()
    n = len(inst.log)
    refused(inst, inst.set("String", [vr], [b"\xdcbersetzung.csv"]), n,
            "not valid UTF-8", "byte 0xDC")
    n = len(inst.log)
    refused(inst, inst.set("String", [vr], [None]), n, "is NULL")
    assert inst.snapshot() == before
    assert inst.set("String", [vr], ["Übersetzung.csv"]) == OK
    assert inst.get_named("engine.speed_table") == "Übersetzung.csv"
    inst.free()
    # A NULL String after initialization and after terminate: refused (by the library as a
    # fixed parameter, naming the NULL value, or as a call after terminate; by the pythonfmu
    # face's glue as a NULL value first), nothing changed.
    inst = started(model, DRIVE_INPUTS, steps=1)
    for mode, fragment in (("stepping", "value NULL rejected"),
                           ("terminated", "after terminate")):
        if mode == "terminated":
            assert inst.terminate() == OK
        before = inst.snapshot()
        n = len(inst.log)
        text = refused(inst, inst.set("String", [vr], [None]), n)
        assert fragment in text or "is NULL" in text, (mode, text)
        assert inst.snapshot() == before
    inst.free()


def row_5(fmus, work):
    """Serializing into buffers larger (FMI allows it) or smaller than the state."""
    for name, fmu in fmus.items():
        model = Model(unpack(fmu, work / name))
        inputs = MESH_INPUTS if name == "GearMeshRattle" else DRIVE_INPUTS
        inst = started(model, inputs, steps=5)
        st, state = inst.get_state()
        assert st == OK
        st, exact = inst.serialize(state)
        assert st == OK
        size = len(exact)
        for extra in (1, 64 * 1024, 64 * 1024 * 1024):
            st, buf = inst.serialize(state, extra=extra)
            assert st == OK, inst.log[-2:]
            assert buf[:size] == exact
            assert buf[size:] == bytes(extra), "bytes past the state were written"
            # The whole buffer reads back (the padding is ignored) and restores the state.
            st, back = inst.deserialize(buf)
            assert st == OK, inst.log[-2:]
            assert inst.set_state(back) == OK
            assert inst.free_state(back) == OK
        for short in (-1, -size + HEADER, -size):
            n = len(inst.log)
            st, buf = inst.serialize(state, extra=short)
            refused(inst, st, n, "too small", f"needs {size} bytes")
            assert buf == bytes([0xA5]) * (size + short), "a refused call wrote into the buffer"
        n = len(inst.log)
        refused(inst, inst.deserialize(exact[:-1])[0], n, "truncated")
        assert inst.free_state(state) == OK
        inst.free()


def rss_kib() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * (resource.getpagesize() // 1024)


def row_6(fmus, work):
    """GetFMUState into a non-NULL state (libcosim's save_state) reuses it: no leak."""
    model = Model(unpack(fmus["GearMeshRattle"], work / "m"))
    inst = started(model, MESH_INPUTS, steps=3)
    st, state = inst.get_state()
    assert st == OK
    first = state.value
    for _ in range(2000):  # warm up the allocator
        inst.get_state(into=state)
    before = rss_kib()
    calls = 20_000
    for _ in range(calls):
        assert inst.get_state(into=state)[0] == OK
    grown = rss_kib() - before
    # pythonfmu leaked 2.2 kiB per call (44 MB here); allow 1/10 of one leaked state per call.
    # (Under AddressSanitizer freed memory stays in its quarantine: its leak check counts.)
    if not os.environ.get("RATTLE_SANITIZED"):
        assert grown < calls * 0.22, f"resident memory grew by {grown} kiB in {calls} calls"
    assert state.value == first  # the same state, reused
    # States left to FreeInstance are freed with the instance, and freeing twice is a no-op.
    assert inst.free_state(state) == OK and state.value is None
    assert inst.free_state(state) == OK
    for _ in range(5):
        inst.get_state()
    inst.free()
    print(json.dumps({"row6_calls": calls, "rss_growth_kib": grown}))


def row_7(fmus, work):
    """Own states restore: free start (init.in_contact = false) after the pinion moved, and the
    Driveline with a speed table whose file is gone; also in another process."""
    model = Model(unpack(fmus["GearMeshRattle"], work / "m"))
    free_start = {"init.in_contact": False, "wheel.phi_start": 0.0, "wheel.w_start": 44.5}
    inst = started(model, MESH_INPUTS, free_start, steps=10)
    st, state = inst.get_state()
    assert st == OK
    blob = inst.serialized()
    saved = inst.snapshot()
    reference = run_outputs(inst, 10, 10)
    n = len(inst.log)
    assert inst.set_state(state) == OK, inst.log[n:]
    assert inst.snapshot() == saved
    assert run_outputs(inst, 10, 10) == reference
    other = model.instantiate(b"other")  # a fresh instance, never initialized
    st, restored = other.deserialize(blob)
    assert st == OK and other.set_state(restored) == OK, other.log
    assert run_outputs(other, 10, 10) == reference
    (work / "mesh_state.bin").write_bytes(blob)
    (work / "mesh_reference.json").write_text(json.dumps(reference))

    drive = Model(unpack(fmus["Driveline"], work / "d"))
    table = work / "speed.csv"
    table.write_text("time,speed\n0,80\n0.01,95\n0.02,85\n")
    dinst = started(drive, DRIVE_INPUTS, {"engine.speed_table": str(table)}, steps=5)
    dblob = dinst.serialized()
    st, dstate = dinst.get_state()
    dref = run_outputs(dinst, 5, 10)
    table.unlink()  # restoring must not read it
    assert dinst.set_state(dstate) == OK, dinst.log[-2:]
    assert run_outputs(dinst, 5, 10) == dref
    (work / "drive_state.bin").write_bytes(dblob)
    (work / "drive_reference.json").write_text(json.dumps(dref))
    # Another process restores both (the table file no longer exists anywhere).
    code = (
        "import json, sys\n"
        "from pathlib import Path\n"
        "sys.path.insert(0, sys.argv[1])\n"
        "import boundary_rows as b\n"
        "from raw_fmi import Model, OK\n"
        "work = Path(sys.argv[2])\n"
        "for name, folder, k0 in (('mesh', 'm', 10), ('drive', 'd', 5)):\n"
        "    inst = Model(work / folder).instantiate(b'restored')\n"
        "    st, state = inst.deserialize((work / f'{name}_state.bin').read_bytes())\n"
        "    assert st == OK and inst.set_state(state) == OK, inst.log\n"
        "    rows = json.loads(json.dumps(b.run_outputs(inst, k0, 10)))\n"
        "    assert rows == json.loads((work / f'{name}_reference.json').read_text())\n"
        "print('restored')\n")
    run = subprocess.run([sys.executable, "-c", code, str(Path(__file__).parent), str(work)],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0 and "restored" in run.stdout, run.stderr[-3000:]


def row_8(fmus, work):
    """A multi-value set with one bad entry stores nothing."""
    mesh = Model(unpack(fmus["GearMeshRattle"], work / "m"))
    inst = started(mesh, MESH_INPUTS, steps=2)
    v = mesh.vr
    real, integer = mesh.kind("Real"), mesh.kind("Integer")
    cases = [  # (the library names its own types in its messages: "no Real variable")
        (real, [v("pinion.w"), v("wheel.tau_mesh")], [123.0, 0.0], "is an output"),
        (real, [v("pinion.w"), 99999], [123.0, 0.0], "value reference 99999"),
        (real, [v("pinion.w"), v("wheel.J")], [123.0, 5e-3], "'wheel.J' is fixed"),
        (real, [v("pinion.w"), v("mesh.impacts_drive")], [123.0, 1.0], "no Real variable"),
        (integer, [v("gear.z_pinion"), v("mesh.n_contact")], [25, 1], "'gear.z_pinion' is fixed"),
        ("Boolean", [2**31 + 5, v("friction.enabled")], [0, 1], "value reference 2147483653"),
    ]
    for kind, vrs, values, fragment in cases:
        before = inst.snapshot()
        n = len(inst.log)
        refused(inst, inst.set(kind, vrs, values), n, fragment, "nothing of this call was stored")
        assert inst.snapshot() == before, (kind, vrs)
    # In initialization mode too (parameters are settable there): nothing of a bad call.
    fresh = mesh.instantiate(b"init")
    assert fresh.begin() == OK
    before = fresh.snapshot()
    n = len(fresh.log)
    refused(fresh, fresh.set(integer, [v("gear.z_pinion"), 4242], [25, 1]), n,
            "value reference 4242")
    n = len(fresh.log)
    refused(fresh, fresh.set("Boolean", [v("init.in_contact"), v("mesh.n_contact")], [0, 1]), n,
            "no Boolean variable")
    assert fresh.snapshot() == before
    drive = Model(unpack(fmus["Driveline"], work / "d"))
    d = drive.instantiate()
    assert d.begin() == OK
    before = d.snapshot()
    n = len(d.log)
    refused(d, d.set("String", [drive.vr("engine.speed_table"), 77777], ["table.csv", "x"]), n,
            "value reference 77777")
    assert d.snapshot() == before


def row_9(fmus, work):
    """engine.speed_table naming a FIFO, /dev/zero, an oversize file, a 100 000-character
    name: refused at exitInitializationMode at once, with a message."""
    model = Model(unpack(fmus["Driveline"], work / "d"))
    fifo = work / "table.fifo"
    os.mkfifo(fifo)
    big = work / "big.csv"
    with big.open("w") as f:
        f.write("time,speed\n")
        row = "".join(f"{k * 1e-3!r},{80.0 + k % 7!r}\n" for k in range(1000))
        while f.tell() < 5 * 1024 * 1024:
            f.write(row)
    cases = {
        str(fifo): "not a regular file (a FIFO)",
        "/dev/zero": "not a regular file (a character device)",
        str(work): "not a regular file (a directory)",
        str(big): "bytes; allowed: a readable regular file of at most 4194304 bytes",
        "x" * 100_000: "too long a path",
        str(work / "missing.csv"): "no such file or directory",
    }
    for value, fragment in cases.items():
        inst = model.instantiate()
        assert inst.begin() == OK
        assert inst.set_named({**DRIVE_INPUTS, "engine.speed_table": value}) == OK
        t0 = time.monotonic()
        n = len(inst.log)
        refused(inst, inst.exit(), n, "'engine.speed_table'", fragment)
        assert time.monotonic() - t0 < 5.0
        # Still in initialization mode: fixing the parameter lets it finish.
        assert inst.set_named({"engine.speed_table": ""}) == OK
        assert inst.exit() == OK
        inst.free()


def row_10(fmus, work):
    """Legal but extreme output shafts on a light vehicle: finite, physical values or a
    refusal, never absurd values with status OK.  Checked against the steady state of the
    spring-damper, tau = drag + drag_viscous w (closed form), reached within one step when the
    shaft's time scales are far below the step."""
    model = Model(unpack(fmus["Driveline"], work / "d"))
    w = DRIVE_INPUTS["wheel.w"]
    for params in ({"shaft.c": 1e6, "vehicle.J": 1e-6},
                   {"vehicle.drag_viscous": 1e5, "vehicle.J": 1e-6},
                   {"shaft.c": 1e6, "vehicle.drag_viscous": 1e5, "vehicle.J": 1e-6,
                    "shaft.k": 1e9},
                   {"shaft.k": 1e9, "shaft.c": 0.0, "vehicle.J": 1e-6}):
        inst = started(model, DRIVE_INPUTS, params)
        drag = DRIVELINE_DRAG + params.get("vehicle.drag_viscous", 0.0) * w
        for k in range(20):
            inst.set_named({"wheel.phi": w * k * H})
            assert inst.step(k * H, H) == OK, inst.log[-2:]
            tau = inst.get_named("wheel.tau_load")
            assert math.isfinite(tau), (params, k, tau)
            if params.get("shaft.c", 0.005) > 0 or params.get("vehicle.drag_viscous", 0) > 0:
                assert math.isclose(tau, drag, rel_tol=1e-6, abs_tol=1e-9), (params, k, tau)
            else:  # undamped 5 kHz shaft: it oscillates about the drag, bounded by its start
                assert abs(tau - drag) <= abs(drag) + 1e-6, (params, k, tau)
        inst.free()


def row_11(fmus, work):
    """The time reached after a refused step (FMI 2.0: fmi2GetRealStatus(
    fmi2LastSuccessfulTime); FMI 3.0: the variable time, and fmi3DoStep's lastSuccessfulTime
    of the refused step); instantiation as Model Exchange or another interface refused
    (fmi2Type 0 and 7; fmi3InstantiateModelExchange and fmi3InstantiateScheduledExecution).
    Before the first step FMI 2.0 refuses the time (no step made), FMI 3.0 reads the start
    time.  The refusal of an unknown status kind is FMI 2.0's alone (FMI 3.0 has no status
    inquiries)."""
    for name, fmu in fmus.items():
        model = Model(unpack(fmu, work / name))
        inputs = MESH_INPUTS if name == "GearMeshRattle" else DRIVE_INPUTS
        for interface in ("model exchange", "other"):
            assert not model.instantiate_other(interface), interface
            assert any(s == ERROR and "co-simulation only" in m
                       for s, _, m in model.pending_log), (interface, model.pending_log)
        inst = model.instantiate()
        n = len(inst.log)
        if model.dialect.time_before_first_step_refused:
            refused(inst, inst.time()[0], n, "no communication step")
        else:
            assert inst.time() == (OK, 0.0)
        inst.free()
        inst = started(model, inputs, steps=3)
        assert inst.time() == (OK, 3 * H)
        first = next(iter(inputs))
        inst.set_named({first: math.nan})
        n = len(inst.log)
        status, flags = inst.step_flags(3 * H, H)
        refused(inst, status, n, "not finite")
        assert flags is None or flags[3] == 3 * H, flags  # FMI 3.0's lastSuccessfulTime
        assert inst.time() == (OK, 3 * H)
        assert inst.step(3 * H, 2.0) == ERROR  # beyond solver.h_comm_max
        assert inst.time() == (OK, 3 * H)
        inst.set_named(inputs)
        st, state = inst.get_state()
        assert st == OK
        advance(inst, 3)
        assert inst.time() == (OK, 4 * H)
        assert inst.set_state(state) == OK
        assert inst.time() == (OK, 3 * H)
        if model.dialect.standard == "2.0":
            n = len(inst.log)
            refused(inst, inst.real_status(0)[0], n, "status kind 0")
        inst.free()


def row_12(fmus, work):
    """Corrupt, forged and foreign states are refused at deserialization or set, with a
    message, and change nothing.  The forged ones are re-sealed (a valid envelope around an
    edited record), so that they reach the library's checks."""
    mesh = Model(unpack(fmus["GearMeshRattle"], work / "m"))
    drive = Model(unpack(fmus["Driveline"], work / "d"))
    inst = started(mesh, MESH_INPUTS, steps=4)
    blob = inst.serialized()
    payload = state_payload(blob)
    assert payload.startswith(b"RATLUNIT") and blob[32:70].rstrip(b"\0").decode() == mesh.guid
    assert Record.decode(payload, mesh.unit_variables).encode() == payload  # the reader's right

    def edited(fn):
        r = Record.decode(payload, mesh.unit_variables)
        fn(r)
        return r.encode()

    forged = {
        "mode 7": edited(lambda r: setattr(r, "phase", 7)),
        "record version is 9": edited(lambda r: setattr(r, "version", 9)),
        "another unit": edited(lambda r: setattr(r, "kind", 1)),
        "time nan s do not go together": edited(lambda r: setattr(r, "time", math.nan)),
        "do not go together": edited(lambda r: setattr(r, "start_time", 1e300)),
        "the wheel speed = nan": edited(lambda r: r.model.__setitem__("wheel.w", math.nan)),
        "the flank in contact = 7": edited(lambda r: r.model.__setitem__("flank", 7)),
        "'friction.enabled' = 2": edited(lambda r: r.values.__setitem__("friction.enabled", 2)),
        "'gear.z_pinion' = 4294967296": edited(
            lambda r: r.values.__setitem__("gear.z_pinion", 2**32)),
        "'gear.backlash'": edited(lambda r: r.values.__setitem__("gear.backlash", -1.0)),
        "does not go with no model state": edited(lambda r: setattr(r, "has_model", 0)),
        "the record ends before variable": payload[:60],
        "follow the end of the record": payload + b"\0" * 8,
        "not a state of this model": b"{}" + payload[2:],
        "not a state": b"",
    }
    before = inst.snapshot()
    state_before = inst.serialized()
    for fragment, p in forged.items():
        st, state = inst.deserialize(with_payload(blob, p))
        assert st == OK, inst.log[-2:]  # the envelope is intact; the content is checked at set
        n = len(inst.log)
        refused(inst, inst.set_state(state), n, "the FMU state is invalid", fragment,
                "nothing changed")
        assert inst.snapshot() == before and inst.serialized() == state_before
        inst.free_state(state)
    envelopes = {
        "checksum mismatch": with_payload(blob, edited(lambda r: setattr(r, "phase", 7)),
                                          fix_checksum=False),
        "envelope version 9": blob[:8] + (9).to_bytes(4, "little") + blob[12:],
        "not a serialized state": b"{}" + blob[2:],
        "truncated": blob[:HEADER + 10],
    }
    for fragment, data in envelopes.items():
        n = len(inst.log)
        refused(inst, inst.deserialize(data)[0], n, fragment)
    # A state of the other FMU, in memory and serialized.
    d = started(drive, DRIVE_INPUTS, steps=1)
    st, foreign = d.get_state()
    n = len(inst.log)
    refused(inst, inst.set_state(foreign), n, f"belongs to the FMU with GUID {drive.guid}")
    foreign_blob = d.serialized()
    n = len(inst.log)
    refused(inst, inst.deserialize(foreign_blob)[0], n, "belongs to the FMU")
    # ... and its record re-sealed with this FMU's GUID: the library refuses the other kind
    st, state = inst.deserialize(with_payload(blob, state_payload(foreign_blob)))
    assert st == OK
    n = len(inst.log)
    refused(inst, inst.set_state(state), n, "another unit")
    n = len(inst.log)
    refused(inst, inst.free_state(foreign), n, "belongs to the FMU")
    fake = c_void_p(id(blob))  # some readable memory that is not a state
    n = len(inst.log)
    refused(inst, inst.set_state(fake), n, "not an FMU state of this FMU")
    assert inst.snapshot() == before and inst.serialized() == state_before
    advance(inst, 4)


def row_13(fmus, work):
    """Counters beyond the 32-bit integer range (fmi2Integer; FMI 3.0's counters are Int32
    too) saturate at 2^31 - 1 (documented); beyond 2^53 (where a double counter stops being
    exact) a state is refused."""
    model = Model(unpack(fmus["GearMeshRattle"], work / "m"))
    inst = started(model, MESH_INPUTS, steps=2)
    blob = inst.serialized()
    payload = state_payload(blob)
    vr = [model.vr("mesh.impacts_drive"), model.vr("mesh.impacts_coast")]
    counter = model.variables["mesh.impacts_drive"][1]
    assert counter == model.kind("Integer"), counter  # a 32-bit integer in both standards
    for count, expected in ((2**31 - 1, 2**31 - 1), (2**31 + 5, 2**31 - 1), (2**53, 2**31 - 1)):
        r = Record.decode(payload, model.unit_variables)
        r.model["n_drive"] = count
        st, state = inst.deserialize(with_payload(blob, r))
        assert st == OK and inst.set_state(state) == OK, inst.log[-2:]
        assert inst.get(counter, vr) == (OK, [expected, 0])
        advance(inst, 2)  # the counter goes on inside (drive-flank contact: no new onsets)
        assert inst.get(counter, vr)[0] == OK
        assert inst.get(counter, vr)[1][0] == expected
    for count in (2**53 + 1, 2**62, -1):
        r = Record.decode(payload, model.unit_variables)
        r.model["n_drive"] = count
        st, state = inst.deserialize(with_payload(blob, r))
        n = len(inst.log)
        refused(inst, inst.set_state(state), n, "expected an integer in [0, 2^53]")


def row_14(fmus, work):
    """A non-UTF-8 unpack path works (pythonfmu gets /proc/self/fd/<n>, said in the debug log);
    an unknown value reference >= 2^31 is reported unsigned."""
    for name, fmu in fmus.items():
        folder = os.fsencode(work) + b"/\xdcbersetzung " + name.encode()
        model = Model(unpack(fmu, folder))
        inst = model.instantiate(logging_on=1)
        assert inst is not None, model.pending_log
        if not model.native:  # pythonfmu, which would misread the path, gets the descriptor
            assert any("/proc/self/fd/" in m for _, _, m in inst.log), inst.log
        assert inst.begin() == OK
        assert inst.set_named(MESH_INPUTS if name == "GearMeshRattle" else DRIVE_INPUTS) == OK
        assert inst.exit() == OK, inst.log
        advance(inst, 0)
        for vr in (2**31, 2**31 + 7, 2**32 - 1):
            n = len(inst.log)
            st, _ = inst.get(model.kind("Real"), [vr])
            refused(inst, st, n, f"value reference {vr}")
        inst.free()


def rest(index: int, value: float):
    """An edit of a Driveline record: the index-th of its model's leading doubles (shaft
    angle, speed, torque, the driveline's time, the last step) set to ``value``."""
    def edit(r):
        buf = bytearray(r.rest)
        struct.pack_into("<d", buf, 8 * index, value)
        r.rest = bytes(buf)
    return edit


def row_15(fmus, work):
    """No call answers OK or Warning with a non-finite output or
    state -- speed tables whose speeds, times or angle overflow, pinion.phi_start = 1e300,
    start time 1e15 s, steps that do not move the time, re-sealed states whose times do not
    go together; each refused with the value and what is allowed, nothing changed."""
    drive = Model(unpack(fmus["Driveline"], work / "d"))
    mesh = Model(unpack(fmus["GearMeshRattle"], work / "m"))
    tables = {  # table text -> what the refusal names
        "0,1e308\n1,-1e308\n2,1e308\n": ("sample 1 (time 0 s): speed 1e+308 rad/s is out of "
                                          "range", "allowed: [-10000, 10000] rad/s"),
        "0,1.7e308\n1,1.7e308\n": ("sample 1 (time 0 s): speed 1.7e+308 rad/s",
                                   "allowed: [-10000"),
        "time,speed\n0,1e308\n1,1e308\n": ("sample 1 (time 0 s): speed 1e+308 rad/s",
                                            "allowed: [-10000"),
        "0,1e4\n1e303,1e4\n": ("sample 2 (time 1e+303 s): the time is out of range",
                               "allowed: [-1e+10, 1e+10] s"),
        "-1e308,0\n1e308,0\n": ("sample 1 (time -1e+308 s): the time is out of range",
                                "allowed: [-1e+10, 1e+10] s"),
        "1.7e308,80\n1.7e308,80\n": ("row 2: time 1.7e+308 s does not increase",),
        "0,10000\n200,10000\n": ("sample 2 (time 2e+02 s): the input-shaft angle reaches "
                                 "2e+06 rad", "allowed: within [-1e+06, 1e+06] rad"),
        "0,80\n1e400,90\n": ("row 2: time '1e400' reads as inf", "allowed: finite numbers"),
    }
    for k, (text, fragments) in enumerate(tables.items()):
        table = work / f"table{k}.csv"
        table.write_text(text, encoding="utf-8")
        inst = drive.instantiate()
        assert inst.begin() == OK
        assert inst.set_named({**DRIVE_INPUTS, "engine.speed_table": str(table)}) == OK
        before = inst.serialized()
        n = len(inst.log)
        refused(inst, inst.exit(), n, str(table), *fragments)
        finite_outputs(inst, f"table {text!r} in initialization")
        assert inst.serialized() == before  # still initializing, nothing changed
        assert inst.set_named({"engine.speed_table": ""}) == OK and inst.exit() == OK
        advance(inst, 0)
        inst.free()
    # a start angle beyond the angles' range
    inst = drive.instantiate()
    assert inst.begin() == OK
    assert inst.set_named({**DRIVE_INPUTS, "pinion.phi_start": 1e300}) == OK
    n = len(inst.log)
    refused(inst, inst.exit(), n, "parameter 'pinion.phi_start' = 1e+300 is out of range",
            "allowed: [-1e+06, 1e+06] rad")
    finite_outputs(inst, "pinion.phi_start = 1e300 in initialization")
    inst.free()
    # start times: 1e15 s refused; at 1e9 s a step below the time's rounding is refused
    for model, inputs in ((mesh, MESH_INPUTS), (drive, DRIVE_INPUTS)):
        inst = model.instantiate()
        n = len(inst.log)
        refused(inst, inst.begin(1e15), n, "start time 1e+15 s is invalid",
                "allowed: finite, within +-1e+09 s")
        assert inst.begin(1e9) == OK and inst.set_named(inputs) == OK
        assert inst.exit() == OK, inst.log[-2:]
        finite_outputs(inst, "start time 1e9 s")
        before = inst.serialized()
        n = len(inst.log)
        refused(inst, inst.step(1e9, 1e-8), n, "communication step size 1e-08 s does not "
                "advance the time 1e+09 s", "allowed: a step that moves the time")
        assert inst.serialized() == before
        assert inst.time() == (OK, 1e9)
        assert inst.step(1e9, 1e-4) == OK, inst.log[-2:]
        finite_outputs(inst, "a step at 1e9 s")
        inst.free()
    # re-sealed states whose times do not go together (restore checks their consistency,
    # not only that they are finite), the Driveline's own time and last step
    for model, inputs in ((drive, DRIVE_INPUTS), (mesh, MESH_INPUTS)):
        inst = started(model, inputs, steps=3)
        blob = inst.serialized()
        payload = state_payload(blob)

        def forged(edit, payload=payload, model=model):
            r = Record.decode(payload, model.unit_variables)
            edit(r)
            return r.encode()

        cases = {
            "start time 1e+308 s and time 0.00030000000000000003 s do not go together":
                lambda r: setattr(r, "start_time", 1e308),
            "start time 0 s and time 1e+308 s do not go together":
                lambda r: setattr(r, "time", 1e308),
            "start time 1e+09 s and time 0.00030000000000000003 s do not go together":
                lambda r: setattr(r, "start_time", 1e9),
            "time 6e+09 s do not go together": lambda r: setattr(r, "time", 6e9),
        }
        if model is drive:  # the shaft's own time and last step, its state
            cases.update({
                "the driveline's time 1e+308 s differs from the state's time "
                "0.00030000000000000003 s": rest(3, 1e308),
                "the last communication step = 1e+300 s: expected within [0, "
                "solver.h_comm_max = 1] s": rest(4, 1e300),
                "the vehicle-side shaft speed = inf": rest(1, math.inf),
            })
        before = inst.snapshot()
        for fragment, edit in cases.items():
            st, state = inst.deserialize(with_payload(blob, forged(edit)))
            assert st == OK, inst.log[-2:]
            n = len(inst.log)
            refused(inst, inst.set_state(state), n, "the FMU state is invalid", fragment,
                    "allowed" if "do not go together" in fragment else "", "nothing changed")
            assert inst.snapshot() == before and inst.serialized() == blob
            inst.free_state(state)

        def latest(r, model=model):  # the latest times that go together
            r.start_time, r.time = 1e9, 5e9
            if model is drive:
                rest(3, 5e9)(r)

        st, state = inst.deserialize(with_payload(blob, forged(latest)))
        assert st == OK and inst.set_state(state) == OK, inst.log[-2:]
        finite_outputs(inst, "restored at 5e9 s")
        n = len(inst.log)
        refused(inst, inst.step(5e9, 1e-7), n, "does not advance the time 5e+09 s")
        inst.free_state(state)
        inst.free()


def outputs(model: Model, snapshot: dict) -> dict:
    """The outputs of ``snapshot`` (``Instance.snapshot``), by name, as gets return them."""
    out = {}
    for kind, (_, values) in snapshot.items():
        for n, v in zip(model.names(kind), values, strict=True):
            if model.variables[n][2] == "output":
                out[n] = float.fromhex(v) if isinstance(v, str) and kind == model.kind(
                    "Real") else v
    return out


def row_16(fmus, work):
    """A state taken before the first step -- in Instantiated Mode, in Initialization Mode at
    start time 3 s, or after terminate from there -- set into an instance that ran since:
    its outputs are those it was taken with, not the run's (wheel.w came back as 44.57
    instead of 0), and so is FMI 3.0's variable time (it read 0 until
    exitInitializationMode)."""
    for name, fmu in fmus.items():
        model = Model(unpack(fmu, work / name))
        inputs = MESH_INPUTS if name == "GearMeshRattle" else DRIVE_INPUTS
        inst = model.instantiate()
        taken = []
        for how in ("instantiated", "initialization at 3 s", "terminated from initialization"):
            if how == "initialization at 3 s":
                assert inst.begin(3.0) == OK, inst.log[-2:]
                if not model.dialect.time_before_first_step_refused:  # FMI 3.0's time
                    assert inst.time() == (OK, 3.0)
            elif how != "instantiated":
                assert inst.terminate() == OK, inst.log[-2:]
            st, state = inst.get_state()
            assert st == OK, inst.log[-2:]
            taken.append((how, state, inst.snapshot()))
        for how, state, snapshot in taken:
            assert inst.reset() == OK
            assert inst.begin(0.0) == OK
            assert inst.set_named(inputs) == OK and inst.exit() == OK, inst.log[-2:]
            for k in range(3):
                advance(inst, k)
            # the run moved the outputs themselves (not only the inputs and FMI 3.0's time)
            moved = [n for n in model.names(causality="output")
                     if inst.get_named(n) != outputs(model, snapshot)[n]]
            assert moved, (how, "the run moved no output")
            assert inst.set_state(state) == OK, (how, inst.log[-2:])
            assert inst.snapshot() == snapshot, how
            inst.free_state(state)
        inst.free()


ROWS = {int(name.split("_")[1]): fn for name, fn in list(globals().items())
        if name.startswith("row_")}

def main(argv: list[str]) -> int:
    """Run the rows named; with --keep-going every one of them, each failure reported as
    "row <k> FAILED: <reason>" (exit code 1 when any failed)."""
    keep_going = "--keep-going" in argv
    which, mesh_fmu, drive_fmu, folder = [a for a in argv if not a.startswith("--")][:4]
    rows = sorted(ROWS) if which == "all" else [int(r) for r in which.split(",")]
    failed = 0
    for row in rows:
        work = Path(folder) / f"row{row}" if len(rows) > 1 else Path(folder)
        work.mkdir(parents=True, exist_ok=True)
        print(f"=== row {row}", file=sys.stderr, flush=True)
        try:
            ROWS[row]({"GearMeshRattle": Path(mesh_fmu), "Driveline": Path(drive_fmu)}, work)
        except Exception as err:  # (a row's own mistake too: the next rows still run)
            if not keep_going:
                raise
            failed += 1
            traceback.print_exc()
            reason = " ".join(f"{type(err).__name__}: {err}".split())[:300]
            print(f"row {row} FAILED: {reason}", flush=True)
            continue
        print(f"row {row} ok", flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
