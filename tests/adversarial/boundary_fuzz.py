"""Randomized FMI boundary fuzzer: call sequences and arguments drawn by hypothesis against a
built FMU through raw ctypes (raw_fmi.py), in this process -- run it as a child process, so
that a crash of the host is an exit code:

    python boundary_fuzz.py <FMU> <examples> <seed>    -> last line: JSON summary

Each example instantiates the FMU, makes a drawn sequence of calls -- life cycle in any
order, get/set of any value references (valid, of another type, hidden, unknown, >= 2^31)
with any values (NaN, infinities, huge, invalid UTF-8, FIFO and device paths), steps of any
size and communication point, FMU states got, reused, set, freed, serialized into short and
long buffers and deserialized from damaged bytes, debug-logging categories, status queries,
unsupported functions -- and frees it.  NULL and dangling pointers are left out (FMI does not
allow them).  After every call it checks:

* the host is alive and the status is one the call may return in the instance's mode: never
  fmi2Fatal, fmi2Discard or fmi2Pending (the FMUs refuse with fmi2Error); calls FMI does not
  allow in the mode, and unknown value references, are refused; valid gets are fmi2OK;
* a refused call (fmi2Error) logged a message, and changed nothing observable: every variable
  of the modelDescription (one get per type) and the serialized FMU state are as before;
* an accepted set stores exactly the values given (read back bit for bit).
"""

from __future__ import annotations

import json
import math
import sys
from ctypes import c_void_p
from pathlib import Path

from hypothesis import HealthCheck, Phase, given, seed, settings
from hypothesis import strategies as st
from raw_fmi import (
    CO_SIMULATION,
    DISCARD,
    ERROR,
    FATAL,
    HEADER,
    MODEL_EXCHANGE,
    OK,
    PENDING,
    WARNING,
    Model,
    state_payload,
    unpack,
)
from records import Record

ALLOWED = {OK, WARNING, ERROR}  # what these FMUs may answer; FATAL/DISCARD/PENDING never
MODES = ("instantiated", "initialization", "stepping", "terminated")  # the record's phases
H = 1e-4
SLOTS = 3

floats_any = st.one_of(
    st.sampled_from([0.0, -0.0, 1.0, -1.0, 1e-4, 0.15, 44.57, 86.92, 300.0, 1e5, -1e5, 1e6,
                     1e300, -1e300, 5e-324, math.nan, math.inf, -math.inf]),
    st.floats(allow_nan=True, allow_infinity=True))
ints_any = st.one_of(st.sampled_from([0, 1, -1, 2, 20, 39, 400, 2**31 - 1, -(2**31)]),
                     st.integers(-(2**31), 2**31 - 1))
strings_any = st.one_of(
    st.sampled_from([b"", b"x", b"/dev/zero", b"/nonexistent/table.csv", b"\xdcbersetzung",
                     b"ok\xc3", b"\xed\xa0\x80", "Übersetzung.csv".encode(), b"%s%n%d",
                     b"x" * 5000, b"speed.csv"]),
    st.binary(max_size=40).map(lambda b: b.replace(b"\0", b"")))


class Fuzz:
    """The FMU under test and the bookkeeping of one example."""

    def __init__(self, model: Model, table: Path):
        self.m = model
        self.table = table
        names = model.variables
        self.n_vars = len(names)
        self.by_kind = {k: [model.vr(n) for n in model.names(k)]
                        for k in ("Real", "Integer", "Boolean", "String")}
        hidden = range(self.n_vars, self.n_vars + 3)  # the shim's hidden variables
        self.bad_vrs = [*hidden, self.n_vars + 3, 4096, 2**31, 2**31 + 7, 2**32 - 1]
        self.inputs = {n: vr for n, (vr, _, c) in names.items() if c == "input"}
        #: the inputs that carry the partner's motion (inputs.continue_when_held)
        self.motion_vrs = {vr for n, vr in self.inputs.items()
                           if n in ("pinion.phi", "pinion.w", "pinion.a", "wheel.phi",
                                    "wheel.w")}
        self.defaults = []  # (kind, vrs, start values) of the parameters
        for kind in ("Real", "Integer", "Boolean", "String"):
            params = [(vr, start) for n, (vr, k, c) in names.items()
                      if k == kind and c == "parameter" for start in [model.starts[n]]]
            if params:
                self.defaults.append((kind, [vr for vr, _ in params],
                                      [start for _, start in params]))
        self.calls = 0
        self.refusals = 0
        self.by_status = {s: 0 for s in range(6)}
        self.by_op: dict[str, list[int]] = {}  # op -> [accepted, refused]

    # ------------------------------------------------------------------ observation
    def observe(self, inst) -> tuple:
        """Everything observable: all variables and the serialized FMU state."""
        snap = inst.snapshot()
        for kind, (status, _) in snap.items():
            assert status == OK, ("a get of valid variables failed", kind, inst.log[-3:])
        return snap, inst.serialized()


def vr_lists(f: Fuzz, kind: str):
    own = f.by_kind[kind] or f.bad_vrs  # GearMeshRattle has no String variable
    other = [vr for k, vrs in f.by_kind.items() if k != kind for vr in vrs]
    pool = st.one_of(st.sampled_from(own), st.sampled_from(own), st.sampled_from(own),
                     st.sampled_from(other or own), st.sampled_from(f.bad_vrs),
                     st.integers(0, 2**32 - 1))
    return st.lists(pool, min_size=0, max_size=5)


def value_strategy(kind: str):
    return {"Real": floats_any, "Integer": ints_any, "Boolean": ints_any,
            "String": strings_any}[kind]


def call_strategy(f: Fuzz):
    kinds = ("Real", "Integer", "Boolean", "String")
    sets = [vr_lists(f, k).flatmap(
        lambda vrs, k=k: st.tuples(st.just("set"), st.just(k), st.just(vrs),
                                   st.lists(value_strategy(k), min_size=len(vrs),
                                            max_size=len(vrs))))
            for k in kinds]
    gets = [st.tuples(st.just("get"), st.just(k), vr_lists(f, k)) for k in kinds]
    realistic_inputs = st.tuples(st.just("inputs"), st.sampled_from([0.0, 0.5, 1.0, 1.3]))
    step = st.tuples(st.just("step"),
                     st.one_of(st.just("next"), st.just("next"), st.just("next"), floats_any),
                     st.one_of(st.sampled_from([H, H, H, 5e-5, 1e-3, 1e-2, 1e-8]),
                               floats_any))
    life = st.sampled_from([("enter",), ("exit",), ("terminate",), ("reset",), ("cancel",),
                            ("derivative",)])
    setup = st.tuples(st.just("setup"), floats_any, st.booleans(), floats_any)
    slot = st.integers(0, SLOTS - 1)
    states = st.one_of(
        st.tuples(st.just("get_state"), slot),
        st.tuples(st.just("set_state"), slot),
        st.tuples(st.just("free_state"), slot),
        st.tuples(st.just("serialize"), slot,
                  st.sampled_from([0, 0, 1, 4096, -1, -HEADER, -10**6])),
        st.tuples(st.just("deserialize"), slot, st.integers(0, 10**6),
                  st.sampled_from(["as is", "as is", "flip", "truncate", "pad", "guid",
                                   "garbage"])))
    logging = st.tuples(st.just("logging"), st.integers(-1, 2),
                        st.lists(st.one_of(st.sampled_from([b"logAll", b"logStatusError",
                                                            b"nonsense", None]),
                                           strings_any), max_size=3))
    status = st.tuples(st.just("status"), st.sampled_from(["Real", "Integer", "Boolean",
                                                           "String", "Status"]),
                       st.integers(-1, 5))
    instantiate = st.tuples(st.just("instantiate"), st.sampled_from(
        ["model exchange", "latin-1 name", "blank name", "wrong guid", "unzip root",
         "http", "relative", "missing"]))
    single = st.one_of(*sets, *gets, realistic_inputs, step, life, setup, states, logging,
                       status, instantiate)
    # Sequences a master makes, so that the fuzz also reaches (and leaves) stepping.
    initialize = st.builds(lambda scale: [("setup", 0.0, False, 0.0), ("enter",),
                                          ("defaults",), ("inputs", scale), ("exit",)],
                           st.sampled_from([0.0, 1.0, 1.3]))
    run = st.builds(lambda n, scale, h: [c for _ in range(n)
                                         for c in (("inputs", scale), ("step", "next", h))],
                    st.integers(1, 6), st.sampled_from([1.0, 1.0, 0.5]),
                    st.sampled_from([H, H, 5e-5, 1e-3]))
    one = single.map(lambda c: [c])
    # sampled_from weighs its choices evenly (one_of favours its first branches)
    return st.sampled_from([one, one, one, one, initialize, run, run]).flatmap(lambda s: s)


def realistic(f: Fuzz, scale: float, k: int) -> dict:
    """Consistent inputs at communication point k (scaled), so that steps do proceed."""
    t = k * H
    if "pinion.w" in f.inputs:
        w = 86.92 * scale
        return {"pinion.phi": w * t, "pinion.w": w, "pinion.a": 0.0, "wheel.tau_load": 0.15}
    return {"wheel.phi": 44.57 * scale * t, "wheel.w": 44.57 * scale}


def damaged(blob: bytes, how: str, at: int) -> bytes:
    if how == "flip" and len(blob) > HEADER:
        i = HEADER + at % (len(blob) - HEADER)
        return blob[:i] + bytes([blob[i] ^ 0x40]) + blob[i + 1:]
    if how == "truncate":
        return blob[:at % max(1, len(blob))]
    if how == "pad":
        return blob + bytes(at % 5000)
    if how == "guid":
        return blob[:32] + b"{00000000-0000-0000-0000-000000000000}".ljust(64, b"\0") + blob[96:]
    if how == "garbage":
        return bytes((at * 7 + i) % 256 for i in range(at % 300))
    return blob


def run_example(f: Fuzz, calls: list) -> None:
    m = f.m
    inst = m.instantiate(b"fuzz")
    assert inst is not None, m.pending_log
    slots: list[c_void_p | None] = [None] * SLOTS
    blobs: list[bytes] = []
    try:
        for call in calls:
            f.calls += 1
            print("CALL", repr(call)[:300], file=sys.stderr, flush=True)
            before = f.observe(inst)
            record = Record.decode(state_payload(before[1]), m.variables)
            mode, next_t = MODES[record.phase], record.time
            assert math.isfinite(next_t), record
            k = round(next_t / H)  # for the realistic inputs
            n_log = len(inst.log)
            op = call[0]
            expect_error = False
            readback = None
            if op == "set":
                _, kind, vrs, values = call
                own = set(f.by_kind[kind])
                expect_error = any(vr not in own for vr in vrs) or (
                    kind == "String" and any(_bad_utf8(v) for v in values))
                status = inst.set(kind, vrs, values)
                readback = (kind, vrs, values)
            elif op == "get":
                _, kind, vrs = call
                status, _ = inst.get(kind, vrs)
                own = set(f.by_kind[kind])
                if all(vr in own for vr in vrs):
                    assert status == OK, (call, inst.log[n_log:])
                else:
                    expect_error = True
            elif op == "inputs":
                status = inst.set_named(realistic(f, call[1], k))
            elif op == "defaults":  # every parameter back to its start value
                status = OK
                if mode in ("instantiated", "initialization"):
                    for kind, vrs, values in f.defaults:
                        status = max(status, inst.set(kind, vrs, values))
                    assert status == OK, inst.log[n_log:]
            elif op == "step":
                _, t, h = call
                t = next_t if t == "next" else t
                # docs/fmi.md: the communication point must continue the last step within
                # 1e-9 of the step plus a few ulps (flagged here only well beyond that)
                slack = 2 * (1e-9 * abs(h) + 16 * math.ulp(max(abs(t), abs(next_t))))
                expect_error = mode != "stepping" or not math.isfinite(t) or not (
                    abs(t - next_t) <= slack)
                status = inst.step(t, h)
                if status in (OK, WARNING):
                    assert mode == "stepping"
            elif op == "setup":
                _, start, _, stop = call
                expect_error = mode != "instantiated" or not math.isfinite(start)
                status = inst.setup(start, stop=stop)
            elif op in ("enter", "exit", "terminate", "reset"):
                expect_error = {"enter": mode != "instantiated",
                                "exit": mode != "initialization",
                                "terminate": mode not in ("stepping", "initialization"),
                                "reset": False}[op]
                status = getattr(inst, op)()
            elif op == "cancel":
                status = m.lib.fmi2CancelStep(inst.c)
                expect_error = True
            elif op == "derivative":
                status = inst.L.fmi2GetDirectionalDerivative(inst.c, None, 0, None, 0, None,
                                                             None)
                expect_error = True
            elif op == "get_state":
                into = slots[call[1]]
                status, state = inst.get_state(into=into)
                assert status in (OK, WARNING), (call, inst.log[n_log:])
                slots[call[1]] = state
            elif op == "set_state":
                state = slots[call[1]]
                if state is None:
                    continue
                status = inst.set_state(state)
                assert status in (OK, WARNING), ("own state refused", inst.log[n_log:])
            elif op == "free_state":
                state = slots[call[1]]
                if state is None:
                    continue
                status = inst.free_state(state)
                assert status == OK and state.value is None
                slots[call[1]] = None
            elif op == "serialize":
                _, i, extra = call
                if slots[i] is None:
                    continue
                status, data = inst.serialize(slots[i], extra=extra)
                expect_error = extra < 0
                if status == OK:
                    size = inst.state_size(slots[i])[1]
                    assert data[size:] == bytes(len(data) - size)
                    blobs.append(data)
            elif op == "deserialize":
                _, i, at, how = call
                source = blobs[at % len(blobs)] if blobs else before[1]
                data = damaged(source, how, at)
                into = slots[i]
                status, state = inst.deserialize(data, into=into)
                if how in ("guid", "garbage", "flip") or (
                        how == "truncate" and len(data) < len(source)):
                    expect_error = True
                if status in (OK, WARNING):
                    slots[i] = state
            elif op == "logging":
                _, on, cats = call
                expect_error = any(c is None or _bad_utf8(c) for c in cats)
                status = inst.logging(on, cats)
            elif op == "status":
                _, which, kind = call
                status = _status_call(inst, which, kind)
                expect_error = not (which == "Boolean" and kind == 3) and not (
                    which == "Real" and kind == 2 and mode in ("stepping", "terminated"))
            elif op == "instantiate":
                before_inst = _bad_instantiate(m, call[1])
                assert before_inst is None, call
                assert any(s >= ERROR for s, _, _ in m.pending_log), m.pending_log
                continue
            else:
                raise AssertionError(call)
            f.by_status[status] = f.by_status.get(status, 0) + 1
            f.by_op.setdefault(op, [0, 0])[status == ERROR] += 1
            assert status in ALLOWED, (call, status, inst.log[n_log:])
            if expect_error:
                assert status == ERROR, (call, mode, status, inst.log[n_log:])
            if status == ERROR:
                f.refusals += 1
                assert inst.messages(n_log, ERROR), ("refused without a message", call)
                if op in ("get_state", "free_state"):
                    continue
                after = f.observe(inst)
                assert after[0] == before[0], ("a refused call changed variables", call)
                if op == "set" and kind == "Real" and f.motion_vrs.intersection(vrs):
                    # the library's rule: a set naming a motion input marks the inputs set
                    # (the master holds nothing), accepted or not -- the record says so
                    after = (after[0], _motion_set(m, after[1], record.motion_set))
                assert after[1] == before[1], ("a refused call changed the state", call)
            elif readback is not None:
                kind, vrs, values = readback
                st_, got = inst.get(kind, vrs)
                assert st_ == OK
                last = {}
                for vr, v in zip(vrs, values, strict=True):
                    last[vr] = v
                for vr, g in zip(vrs, got, strict=True):
                    assert _same(kind, g, last[vr]), (call, vr, g, last[vr])
    finally:
        for state in slots:
            if state is not None and state.value is not None and f.calls % 2:
                inst.free_state(state)  # every other example leaves them to fmi2FreeInstance
        inst.free()


def _motion_set(m: Model, blob: bytes, flag: int) -> bytes:
    """``blob`` (a serialized state) with the record's motion_set flag set to ``flag``."""
    from raw_fmi import with_payload

    record = Record.decode(state_payload(blob), m.variables)
    record.motion_set = flag
    return with_payload(blob, record)


def _bad_utf8(value) -> bool:
    if value is None:
        return True
    try:
        (value if isinstance(value, bytes) else value.encode()).decode("utf-8")
    except UnicodeDecodeError:
        return True
    return False


def _same(kind: str, got, given) -> bool:
    if kind == "Real":
        return (math.isnan(got) and math.isnan(given)) or got.hex() == float(given).hex()
    if kind == "Boolean":
        return got == (1 if given else 0)
    if kind == "String":
        return got == (given.decode() if isinstance(given, bytes) else given)
    return got == given


def _status_call(inst, which: str, kind: int) -> int:
    import ctypes

    L, c = inst.L, inst.c
    if which == "Real":
        return L.fmi2GetRealStatus(c, kind, ctypes.byref(ctypes.c_double()))
    if which == "Integer":
        return L.fmi2GetIntegerStatus(c, kind, ctypes.byref(ctypes.c_int()))
    if which == "Boolean":
        v = ctypes.c_int(7)
        status = L.fmi2GetBooleanStatus(c, kind, ctypes.byref(v))
        if status == OK:
            assert v.value == 0  # never asks to terminate
        return status
    if which == "String":
        return L.fmi2GetStringStatus(c, kind, ctypes.byref(ctypes.c_char_p()))
    return L.fmi2GetStatus(c, kind, ctypes.byref(ctypes.c_int()))


def _bad_instantiate(m: Model, how: str):
    root = m.root
    return {
        "model exchange": lambda: m.instantiate(kind=MODEL_EXCHANGE),
        "latin-1 name": lambda: m.instantiate(name=b"\xdcbersetzung"),
        "blank name": lambda: m.instantiate(name=b" "),
        "wrong guid": lambda: m.instantiate(guid=b"{not-the-guid}"),
        "unzip root": lambda: m.instantiate(location=("file://" + str(root)).encode()),
        "http": lambda: m.instantiate(location=b"http://localhost/resources"),
        "relative": lambda: m.instantiate(location=b"resources"),
        "missing": lambda: m.instantiate(location=b"/nonexistent/resources"),
    }[how]()


def main(fmu: Path, examples: int, seed_value: int, work: Path) -> dict:
    model = Model(unpack(fmu, work / fmu.stem))
    assert CO_SIMULATION == 1
    table = work / "speed.csv"
    table.write_text("time,speed\n0,80\n0.5,95\n1,85\n")
    f = Fuzz(model, table)
    extra_strings = st.sampled_from([str(table).encode()])
    global strings_any
    strings_any = st.one_of(strings_any, extra_strings)

    @seed(seed_value)
    @settings(max_examples=examples, deadline=None, database=None,
              suppress_health_check=list(HealthCheck),
              phases=[Phase.generate, Phase.shrink])
    @given(st.lists(call_strategy(f), min_size=3, max_size=14))
    def fuzz(segments):
        run_example(f, [call for segment in segments for call in segment])

    fuzz()
    return {"fmu": fmu.stem, "examples": examples, "seed": seed_value, "calls": f.calls,
            "refused": f.refusals, "by_call": f.by_op,
            "statuses": {name: f.by_status.get(s, 0) for s, name in
                         ((OK, "OK"), (WARNING, "Warning"), (DISCARD, "Discard"),
                          (ERROR, "Error"), (FATAL, "Fatal"), (PENDING, "Pending"))}}


if __name__ == "__main__":
    fmu_path, n_examples, seed_arg, folder = sys.argv[1:5]
    summary = main(Path(fmu_path), int(n_examples), int(seed_arg), Path(folder))
    print(json.dumps(summary))
