"""Randomized FMI boundary fuzzer: call sequences and arguments drawn by hypothesis against a
built FMU of any face, FMI 2.0 or 3.0, through raw ctypes (raw_fmi.py), in this process -- run
it as a child process, so that a crash of the host is an exit code:

    python boundary_fuzz.py <FMU> <examples> <seed> <work folder> [--no-shadow] [--no-shrink]
        -> last line: JSON summary

Each example instantiates the FMU, makes a drawn sequence of calls -- life cycle in any
order, get/set of any value references (valid, of another type, hidden, unknown, >= 2^31)
with any values (NaN, infinities, huge, invalid UTF-8, FIFO and device paths), steps of any
size and communication point, FMU states got, reused, set, freed, serialized into short and
long buffers, deserialized from damaged bytes and from edited records RE-SEALED (a valid
envelope around a changed record, so that they reach the library's checks in rm_restore),
debug-logging categories, status queries, unsupported functions, inputs at their declared
bounds and steps on them (the costliest work a step does) -- and frees it.  NULL and dangling
pointers are left out (FMI does not allow them).  Every call into the FMU is timed
(call_clock.py): the summary holds the slowest and the one nearest its bound.

One fuzzer for both standards: the calls are drawn in the FMU's own types (``Fuzz.kinds``:
FMI 2.0's Real, Integer, Boolean, String; FMI 3.0's Float64, Int32, Enumeration as Int64,
Boolean, String) and made through the model's dialect; the shadow is asked in the library's
types.  What one standard lacks is its counterpart in the other: FMI 3.0 has no
fmi2SetupExperiment (a drawn start time is the next fmi3EnterInitializationMode's), no status
inquiries (its variable time is read instead, and must be the state's), no fmi2CancelStep (it
calls fmi3EnterEventMode, which these FMUs refuse too); what only FMI 3.0 has is drawn on its
face alone: Int32 and Int64 calls naming the other kind of integer, Int64 values beyond 32
bits, and the independent variable time in gets and sets (the glue's refusals).

What makes a run fail:

* **the expected answer** (the shadow, shadow.py): every call that reaches the model is made
  on an in-process library unit too, and the FMU must give the same status, and afterwards
  the same value of every variable (bit for bit) and the same state record, as the library
  does; a refused call logs the library's message;
* **what holds whatever the model** (also with ``--no-shadow``): the status is one the call may
  return (never fmi2Fatal, fmi2Discard or fmi2Pending); calls FMI does not allow in the mode,
  unknown value references, bad envelopes are refused; valid gets, own states, serializing
  into a large enough buffer succeed; a master's valid call succeeds -- the initialization of
  the default parameters and inputs, and every step of the default unit on its consistent
  inputs (a "pristine" instance: nothing but that since); a refused call logged a message and
  changed nothing observable (every variable and the serialized state); an accepted set
  stores exactly the values given; **no call answers fmi2OK or fmi2Warning with a non-finite
  output or model state**;
* **enough of every state operation**: at least ``examples // 10`` (and 5) get, set, free,
  serialize and deserialize calls, and as many set calls of re-sealed edited records, and
  ``examples // 5`` pristine steps, per run.
"""

from __future__ import annotations

import json
import math
import os
import struct
import sys
from ctypes import c_bool, c_void_p
from pathlib import Path

from call_clock import CallClock
from hypothesis import HealthCheck, Phase, given, seed, settings
from hypothesis import strategies as st
from raw_fmi import (
    CO_SIMULATION,
    DISCARD,
    ERROR,
    FATAL,
    HEADER,
    OK,
    PENDING,
    WARNING,
    Model,
    state_payload,
    unpack,
    with_payload,
)
from records import MESH_MODEL, Record
from shadow import Shadow

ALLOWED = {OK, WARNING, ERROR}  # what these FMUs may answer; FATAL/DISCARD/PENDING never
MODES = ("instantiated", "initialization", "stepping", "terminated")  # the record's phases
H = 1e-4
SLOTS = 3
#: Steps a pristine instance must accept (the default experiment's step and half of it).
PRISTINE_STEPS = (H, 5e-5)
#: The operations on FMU states whose counts a run must reach.
STATE_OPS = ("get_state", "set_state", "free_state", "serialize", "deserialize",
             "set_resealed")
#: Refusals of a step that cost the stepper its whole work budget (docs/fmi.md: "How long a
#: call can take"): after one of them an example makes no more steps (the run's time stays
#: bounded; the same refusal again tells nothing new).
COSTLY_REFUSALS = ("too stiff to resolve", "would penetrate", "more work than its budget")
#: The inputs' declared bounds and a few values between, for the costly steps: a pinion at
#: its fastest and most accelerated, the largest load, the Driveline's fastest wheel.
EXTREME_SPEEDS = (1e4, -1e4, 3e3, 0.0)
EXTREME_ACCELERATIONS = (1e7, -1e7, 1e5, 0.0)
EXTREME_LOADS = (1e5, -1e5, 0.15, 0.0)
COSTLY_PER_EXAMPLE = 1
#: Deserialize variants: the envelope intact (accepted) or damaged (refused).
INTACT = ("as is", "pad", "reseal flip", "reseal truncate", "reseal field", "reseal extend")
DAMAGED = ("flip", "truncate", "guid", "garbage")

interesting_floats = [0.0, -0.0, 1.0, -1.0, 1e-4, 0.15, 44.57, 86.92, 300.0, 1e4, -1e4, 1e5,
                      -1e5, 1e6, 1e7, -1e7, 1.001e7, 1e9, 5e9, 1e15, 1e300, -1e300, 1.7e308,
                      5e-324, math.nan, math.inf, -math.inf]
floats_any = st.one_of(st.sampled_from(interesting_floats),
                       st.floats(allow_nan=True, allow_infinity=True))
ints_any = st.one_of(st.sampled_from([0, 1, -1, 2, 3, 7, 20, 39, 400, 2**31 - 1, -(2**31)]),
                     st.integers(-(2**31), 2**31 - 1))
wide_ints = st.one_of(ints_any, st.sampled_from([2**32, 2**53, 2**53 + 1, 2**62, -(2**62)]))
strings_any = st.one_of(
    st.sampled_from([b"", b"x", b"/dev/zero", b"/nonexistent/table.csv", b"\xdcbersetzung",
                     b"ok\xc3", b"\xed\xa0\x80", "Übersetzung.csv".encode(), b"%s%n%d",
                     b"x" * 5000, b"speed.csv"]),
    st.binary(max_size=40).map(lambda b: b.replace(b"\0", b"")))


class Fuzz:
    """The FMU under test, its expected model and the bookkeeping of one run."""

    def __init__(self, model: Model, table: Path, use_shadow: bool = True):
        self.m = model
        self.table = table
        self.use_shadow = use_shadow
        names = model.variables
        self.n_vars = len(names)
        d = model.dialect
        #: the FMU's types of its unit's variables -> the library's type of each
        # in the library's order of its types (Real, Integer, Boolean, String), FMI 3.0's
        # Enumeration after the Int32: the same draws from a seed as before FMI 3.0 came
        self.library = {}
        for t, kind in d.kinds.items():  # (String too: the mesh has none, calls are drawn)
            self.library[kind] = t
            self.library.update({k: t for _, (_, k, c) in names.items()
                                 if c != "independent" and d.library_type(k) == t})
        self.kinds = list(self.library)
        self.real, self.integer = model.kind("Real"), model.kind("Integer")
        #: FMI 3.0's independent variable time: the glue's, not the library's
        self.glue_vrs = {vr for _, (vr, _, c) in names.items() if c == "independent"}
        self.by_kind = {k: [model.vr(n) for n in model.names(k) if model.vr(n) not in
                            self.glue_vrs] for k in self.kinds}
        self.kind_of = {vr: k for k, vrs in self.by_kind.items() for vr in vrs}
        #: FMI 3.0 passes Booleans as bool (0/1 whatever the importer's byte), FMI 2.0 as int
        self.bool_booleans = d.types["Boolean"][0] is c_bool
        self.outputs = {vr for n, (vr, _, c) in names.items() if c == "output"}
        self.real_outputs = [vr for vr in self.by_kind[self.real] if vr in self.outputs]
        self.hidden = set(range(self.n_vars, self.n_vars + 3))  # the shim's hidden variables
        self.bad_vrs = [*self.hidden, self.n_vars + 3, 4096, 2**31, 2**31 + 7, 2**32 - 1]
        self.inputs = {n: vr for n, (vr, _, c) in names.items() if c == "input"}
        self.defaults = []  # (kind, vrs, start values) of the parameters
        for kind in self.kinds:
            params = [(vr, model.starts[n]) for n, (vr, k, c) in names.items()
                      if k == kind and c == "parameter"]
            if params:
                self.defaults.append((kind, [vr for vr, _ in params],
                                      [start for _, start in params]))
        self.calls = 0
        self.refusals = 0
        self.by_status = {s: 0 for s in range(6)}
        self.by_op: dict[str, list[int]] = {}  # op -> [accepted, refused]
        self.pristine_steps = 0
        self.steps_skipped = 0  # steps not made after costly refusals (COSTLY_REFUSALS)
        self.compared = 0  # calls whose answer was held against the shadow

    def count(self, op: str, status: int) -> None:
        self.by_op.setdefault(op, [0, 0])[status == ERROR] += 1

    def shadow_get(self, shadow: Shadow):
        """``shadow.get`` asked in the FMU's types."""
        return lambda kind, vrs: shadow.get(self.library[kind], vrs)

    def wrong_integer(self, kind: str, vrs, values=()) -> bool:
        """FMI 3.0's glue refuses, before the library, an Int32 call naming an Enumeration, an
        Int64 (Enumeration) call naming anything else, and an Int64 value beyond the library's
        32 bits; FMI 2.0 has one integer type (never)."""
        integers = [k for k, t in self.library.items() if t == "Integer"]
        if self.library.get(kind) != "Integer" or len(integers) == 1:
            return False
        if kind == self.integer:  # (a variable of another type reaches the library)
            return any(self.library.get(self.kind_of.get(vr)) == "Integer"
                       and self.kind_of[vr] != kind for vr in vrs)
        return any(self.kind_of.get(vr) != kind for vr in vrs) or any(
            not -(2**31) <= v < 2**31 for v in values)


# ------------------------------------------------------------------ observation
def snapshot(get, by_kind: dict) -> dict:
    """Every variable by FMI type: {type: [(status, value as text) per variable]}, from
    ``get(kind, vrs) -> (status, values)``; one call per type, one per variable where the
    call is refused (an output that cannot be computed)."""
    out = {}
    for kind in by_kind:
        vrs = by_kind[kind]
        status, values = get(kind, vrs)
        if status != OK:
            pairs = [get(kind, [vr]) for vr in vrs]
            out[kind] = [(s, _text(v[0]) if s == OK else None) for s, v in pairs]
        else:
            out[kind] = [(OK, _text(v)) for v in values]
    return out


def _text(value) -> str:
    if isinstance(value, bool):  # FMI 3.0's Boolean, the library's 0/1
        value = int(value)
    return value.hex() if isinstance(value, float) else repr(value)


def observe(f: Fuzz, inst) -> tuple:
    """The FMU's observable: every variable and the serialized state (its record)."""
    snap = snapshot(inst.get, f.by_kind)
    for kind, pairs in snap.items():
        for vr, (status, _) in zip(f.by_kind[kind], pairs, strict=True):
            assert status in ALLOWED, (kind, vr, status)
            # a get of a valid variable is refused only for an output it cannot compute
            assert status == OK or vr in f.outputs, ("a get of a valid variable failed", kind,
                                                     vr, inst.log[-3:])
    return snap, state_payload(inst.serialized())


def check_finite(f: Fuzz, observed: tuple, call) -> None:
    """No accepted call leaves a non-finite output (as an accepted get) or model state."""
    snap, record = observed
    for vr, (status, text) in zip(f.by_kind[f.real], snap[f.real], strict=True):
        if vr in f.outputs and status == OK:
            assert math.isfinite(float.fromhex(text)), ("an output is not finite", call, vr,
                                                        text)
    r = Record.decode(record, f.m.unit_variables)
    assert math.isfinite(r.start_time) and math.isfinite(r.time), ("state times", call, r)
    if r.has_model and r.model:
        for name, fmt in MESH_MODEL:
            if fmt == "d":
                assert math.isfinite(r.model[name]), ("mesh state not finite", call, name)
    elif r.has_model:  # the Driveline: shaft angle, speed, torque, time, last step
        for x in struct.unpack_from("<5d", r.rest, 0):
            assert math.isfinite(x), ("driveline state not finite", call, r.rest[:40])


# ------------------------------------------------------------------ calls
def vr_lists(f: Fuzz, kind: str):
    own = f.by_kind[kind] or f.bad_vrs  # GearMeshRattle has no String variable
    other = [vr for k, vrs in f.by_kind.items() if k != kind for vr in vrs]
    pool = st.one_of(st.sampled_from(own), st.sampled_from(own), st.sampled_from(own),
                     st.sampled_from(other or own), st.sampled_from(f.bad_vrs),
                     st.integers(0, 2**32 - 1))
    return st.lists(pool, min_size=0, max_size=5)


def value_strategy(f: Fuzz, kind: str):
    if kind != f.integer and f.library[kind] == "Integer":
        return wide_ints  # FMI 3.0's Int64 (Enumerations): beyond the library's 32 bits too
    return {"Real": floats_any, "Integer": ints_any, "Boolean": ints_any,
            "String": strings_any}[f.library[kind]]


def vr_lists_with_glue(f: Fuzz, kind: str):
    """vr_lists, and on FMI 3.0 now and then the glue's own variable time."""
    if not f.glue_vrs:
        return vr_lists(f, kind)
    return st.one_of(vr_lists(f, kind), vr_lists(f, kind), vr_lists(f, kind),
                     vr_lists(f, kind).map(lambda vrs: [*vrs, *sorted(f.glue_vrs)]))


def call_strategy(f: Fuzz):
    sets = [vr_lists_with_glue(f, k).flatmap(
        lambda vrs, k=k: st.tuples(st.just("set"), st.just(k), st.just(vrs),
                                   st.lists(value_strategy(f, k), min_size=len(vrs),
                                            max_size=len(vrs))))
            for k in f.kinds]
    gets = [st.tuples(st.just("get"), st.just(k), vr_lists_with_glue(f, k)) for k in f.kinds]
    realistic_inputs = st.tuples(st.just("inputs"), st.sampled_from([0.0, 0.5, 1.0, 1.3]))
    step = st.tuples(st.just("step"),
                     st.one_of(st.just("next"), st.just("next"), st.just("next"), floats_any),
                     st.one_of(st.sampled_from([H, H, H, 5e-5, 1e-3, 1e-2, 1e-8]),
                               floats_any))
    life = st.sampled_from([("enter",), ("exit",), ("terminate",), ("reset",), ("cancel",),
                            ("derivative",)])
    setup = st.tuples(st.just("setup"), floats_any, st.booleans(), floats_any)
    slot = st.integers(0, SLOTS - 1)
    deserialize = st.tuples(st.just("deserialize"), slot, st.integers(0, 10**6),
                            st.sampled_from([*INTACT, *INTACT, *DAMAGED]), floats_any,
                            wide_ints)
    states = st.one_of(
        st.tuples(st.just("get_state"), slot),
        st.tuples(st.just("set_state"), slot),
        st.tuples(st.just("free_state"), slot),
        st.tuples(st.just("serialize"), slot,
                  st.sampled_from([0, 0, 1, 4096, -1, -HEADER, -10**6])),
        deserialize)
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
    single = st.one_of(*sets, *gets, realistic_inputs, step, life, setup, states, states,
                       states, logging, status, instantiate)
    # Sequences a master makes, so that the fuzz also reaches (and leaves) stepping.
    initialize = st.builds(lambda scale: [("setup", 0.0, False, 0.0), ("enter",),
                                          ("defaults",), ("inputs", scale), ("exit",)],
                           st.sampled_from([0.0, 1.0, 1.0, 1.3]))
    run = st.builds(lambda n, scale, h: [c for _ in range(n)
                                         for c in (("inputs", scale), ("step", "next", h))],
                    st.integers(1, 6), st.sampled_from([1.0, 1.0, 0.5]),
                    st.sampled_from([H, H, 5e-5, 1e-3]))
    # A rollback: save, step on, restore, serialize; and an edited record re-sealed and set.
    rollback = st.builds(lambda i, extra, free: [("get_state", i), ("inputs", 1.0),
                                                 ("step", "next", H), ("set_state", i),
                                                 ("serialize", i, extra)]
                         + ([("free_state", i)] if free else []),
                         slot, st.sampled_from([0, 0, 7]), st.booleans())
    # A master's run of the default unit from its start (the pristine steps).
    session = st.builds(lambda n, h: [("setup", 0.0, False, 0.0), ("enter",), ("defaults",),
                                      ("inputs", 1.0), ("exit",)]
                        + [c for _ in range(n) for c in (("inputs", 1.0), ("step", "next", h))],
                        st.integers(1, 4), st.sampled_from(PRISTINE_STEPS))
    # Inputs at their declared bounds and steps on them: the costliest work of a step.
    costly = st.builds(lambda w, a, tau, n, h: [c for _ in range(n)
                                                for c in (("extreme", w, a, tau),
                                                          ("step", "next", h))],
                       st.sampled_from(EXTREME_SPEEDS), st.sampled_from(EXTREME_ACCELERATIONS),
                       st.sampled_from(EXTREME_LOADS), st.integers(1, 3),
                       st.sampled_from([H, H, 5e-5, 1e-3]))
    resealed = st.builds(lambda d: [d, ("set_state", d[1])],
                         st.tuples(st.just("deserialize"), slot, st.integers(0, 10**6),
                                   st.sampled_from(INTACT[2:]), floats_any, wide_ints))
    one = single.map(lambda c: [c])
    # sampled_from weighs its choices evenly (one_of favours its first branches)
    return st.sampled_from([one, one, one, one, initialize, session, run, run, rollback,
                            resealed, costly, mixed_set(f)]).flatmap(lambda s: s)


def mixed_set(f: Fuzz):
    """A set whose last entry is refused (an output, another type, unknown): nothing of it
    may be stored."""
    settable = [vr for vr in f.by_kind[f.real] if vr not in f.outputs]
    refused_entry = st.sampled_from([*sorted(f.outputs), *f.by_kind[f.integer], *f.bad_vrs,
                                     *sorted(f.glue_vrs)])
    return st.builds(lambda vrs, bad: [*vrs, bad],
                     st.lists(st.sampled_from(settable), min_size=1, max_size=3),
                     refused_entry).flatmap(
        lambda vrs: st.lists(floats_any, min_size=len(vrs), max_size=len(vrs)).map(
            lambda values: [("set", f.real, vrs, values)]))


def backbone(f: Fuzz):
    """What every example begins with, so that what a run must exercise is there by
    construction, not by the draw: a master's start and one pristine step, every state
    operation once (a state got, set back, serialized; a record deserialized, intact or edited
    and re-sealed, and set; the first state freed) and a set with a refused last entry."""
    return st.builds(lambda tour, refused: [*tour, *refused], state_tour(), mixed_set(f))


def state_tour():
    """A master's start, one pristine step and every state operation once."""
    slot = st.integers(0, SLOTS - 1)
    start = [("setup", 0.0, False, 0.0), ("enter",), ("defaults",), ("inputs", 1.0), ("exit",),
             ("inputs", 1.0)]
    return st.builds(
        lambda h, a, b, extra, kind, seal, t, n: [
            *start, ("step", "next", h),
            ("get_state", a), ("set_state", a), ("serialize", a, extra),
            ("deserialize", b, seal, kind, t, n), ("set_state", b), ("free_state", a)],
        st.sampled_from(PRISTINE_STEPS), slot, slot, st.sampled_from([0, 0, 7]),
        st.sampled_from(INTACT), st.integers(0, 10**6), floats_any,
        wide_ints).filter(lambda tour: tour[-6][1] != tour[-3][1])


def realistic(f: Fuzz, scale: float, t: float) -> dict:
    """Inputs consistent with time t (scaled), so that steps do proceed."""
    if "pinion.w" in f.inputs:
        w = 86.92 * scale
        return {"pinion.phi": w * t, "pinion.w": w, "pinion.a": 0.0, "wheel.tau_load": 0.15}
    return {"wheel.phi": 44.57 * scale * t, "wheel.w": 44.57 * scale}


def extreme(f: Fuzz, w: float, a: float, tau: float, t: float) -> dict:
    """Inputs at or near their declared bounds at time t (the angle consistent with the
    speed)."""
    if "pinion.w" in f.inputs:
        return {"pinion.phi": w * t, "pinion.w": w, "pinion.a": a, "wheel.tau_load": tau}
    return {"wheel.phi": w * t, "wheel.w": w}


def damaged(blob: bytes, how: str, at: int) -> bytes:
    if how == "flip" and len(blob) > HEADER:
        i = HEADER + at % (len(blob) - HEADER)
        return blob[:i] + bytes([blob[i] ^ 0x40]) + blob[i + 1:]
    if how == "truncate":  # cut within the state itself: a blob serialized into a larger
        # buffer carries zeros after it, and a cut among them leaves the whole state
        whole = min(len(blob), HEADER + len(state_payload(blob)))
        return blob[:at % max(1, whole)]
    if how == "pad":
        return blob + bytes(at % 5000)
    if how == "guid":
        return blob[:32] + b"{00000000-0000-0000-0000-000000000000}".ljust(64, b"\0") + blob[96:]
    if how == "garbage":
        return bytes((at * 7 + i) % 256 for i in range(at % 300))
    return blob


def resealed(m: Model, blob: bytes, how: str, at: int, real: float, integer: int) -> bytes:
    """``blob`` with its record edited and the envelope made valid again (length, checksum):
    a byte changed, the record cut or extended, or one field of it set to a drawn value."""
    payload = state_payload(blob)
    if how == "reseal extend":
        return with_payload(blob, payload + bytes((at * 13 + i) % 256
                                                  for i in range(1 + at % 64)))
    if not payload:  # a state whose record was cut to nothing and serialized again
        return with_payload(blob, payload)
    if how == "reseal flip":
        i = at % len(payload)
        return with_payload(blob, payload[:i] + bytes([payload[i] ^ (1 + at % 255)])
                            + payload[i + 1:])
    if how == "reseal truncate":
        return with_payload(blob, payload[:at % len(payload)])
    try:
        r = Record.decode(payload, m.unit_variables)
    except (ValueError, struct.error):  # no whole record (an edited one, serialized again)
        return resealed(m, blob, "reseal flip", at, real, integer)
    fields = (["phase", "motion_set", "start_time", "time", "has_model"]
              + [("value", n) for n in r.values] + [("model", n) for n in r.model]
              # the Driveline's leading doubles, those the (possibly cut) record still holds
              + ([("rest", k) for k in range(min(5, len(r.rest) // 8))]
                 if r.has_model and not r.model else []))
    choice = fields[at % len(fields)]
    if choice in ("phase", "motion_set", "has_model"):
        setattr(r, choice, integer % 2**32)
    elif choice in ("start_time", "time"):
        setattr(r, choice, real)
    elif choice[0] == "value":
        old = r.values[choice[1]]
        r.values[choice[1]] = (real if isinstance(old, float) else str(integer)
                               if isinstance(old, str) else max(-(2**63), min(2**63 - 1,
                                                                              integer)))
    elif choice[0] == "model":
        old = r.model[choice[1]]
        r.model[choice[1]] = real if isinstance(old, float) else max(-(2**63),
                                                                   min(2**63 - 1, integer))
    else:  # one of the Driveline's five leading doubles
        rest = bytearray(r.rest)
        struct.pack_into("<d", rest, 8 * choice[1], real)
        r.rest = bytes(rest)
    return with_payload(blob, r)


class Example:
    """One example: the FMU instance, its shadow, the state slots and what is known."""

    def __init__(self, f: Fuzz):
        self.f = f
        self.inst = f.m.instantiate(b"fuzz")
        assert self.inst is not None, f.m.pending_log
        self.shadow = (Shadow(f.m.identifier, f.m.root / "resources") if f.use_shadow
                       else None)
        self.slots: list[c_void_p | None] = [None] * SLOTS
        self.records: list[bytes | None] = [None] * SLOTS  # the shadow's view of each slot
        self.own: list[bool] = [False] * SLOTS  # a state of this instance, not edited
        self.slot_pristine: list[bool] = [False] * SLOTS
        self.blobs: list[tuple[bytes, bool]] = []  # serialized states, pristine or not
        self.pristine = False
        self.init_progress = 0
        self.motion_fresh = False  # consistent inputs set for the coming step
        self.costly = 0  # costly refusals of steps so far
        #: FMI 3.0: the start time the next fmi3EnterInitializationMode passes (its "setup")
        self.start = 0.0
        self.observed = observe(f, self.inst)
        self.compare()

    def compare(self, call=None) -> None:
        """The FMU's observable is the shadow's."""
        if self.shadow is None:
            return
        expected = (snapshot(self.f.shadow_get(self.shadow), self.f.by_kind),
                    self.shadow.save())
        assert self.observed[0] == expected[0], ("the FMU's values are not the library's",
                                                 call, _diff(self.observed[0], expected[0]))
        assert self.observed[1] == expected[1], ("the FMU's state is not the library's", call)

    def close(self) -> None:
        for state in self.slots:
            if state is not None and state.value is not None and self.f.calls % 2:
                self.inst.free_state(state)  # every other example leaves them to FreeInstance
        self.inst.free()
        if self.shadow is not None:
            self.shadow.free()

    # -- state slots
    def get_state(self, i: int, implicit: bool = False) -> int:
        status, state = self.inst.get_state(into=self.slots[i])
        assert status in (OK, WARNING), ("getFMUstate refused", self.inst.log[-3:])
        self.slots[i] = state
        self.records[i] = self.observed[1]  # the record of the current state
        self.own[i], self.slot_pristine[i] = True, self.pristine
        if implicit:
            self.f.count("get_state", status)
        return status

    def run(self, call) -> None:
        f, inst, shadow = self.f, self.inst, self.shadow
        m = f.m
        fmi2 = m.dialect.standard == "2.0"
        if call[0] == "setup" and not fmi2:  # FMI 3.0: the start time of the next enter
            self.start = call[1]
            self.track_initialization(call, OK)
            return
        f.calls += 1
        print("CALL", repr(call)[:300], file=sys.stderr, flush=True)
        before = self.observed
        record = Record.decode(before[1], m.unit_variables)
        mode, next_t = MODES[record.phase], record.time
        n_log = len(inst.log)
        op = call[0]
        expect_error = False
        must_succeed = False
        expected = None  # the shadow's status for calls that reach the model
        face_refusal = False  # refused by the face before the model (its own message)
        readback = None
        keeps_pristine = False
        if op == "step" and self.costly >= COSTLY_PER_EXAMPLE:
            f.steps_skipped += 1
            return
        if op in ("set_state", "free_state", "serialize") and self.slots[call[1]] is None:
            self.get_state(call[1], implicit=True)  # a state op always acts on a state
        if op == "set":
            _, kind, vrs, values = call
            own = set(f.by_kind[kind])
            expect_error = any(vr not in own for vr in vrs) or (
                kind == "String" and any(_bad_utf8(v) for v in values))
            # refused by the face before the library: the shim's hidden variables, strings
            # that are not UTF-8, FMI 3.0's time (never settable) and its integer kinds
            glue = bool(f.glue_vrs.intersection(vrs)) or f.wrong_integer(kind, vrs, values)
            face_refusal = glue or bool(f.hidden.intersection(vrs)) or (
                kind == "String" and any(_bad_utf8(v) for v in values))
            status = inst.set(kind, vrs, values)
            if shadow is not None:
                library = [int(bool(v)) for v in values] if (
                    kind == "Boolean" and f.bool_booleans) else values
                expected = ERROR if glue else shadow.set(f.library[kind], vrs, library)
            readback = (kind, vrs, values)
        elif op == "get":
            _, kind, vrs = call
            status, _ = inst.get(kind, vrs)
            own = set(f.by_kind[kind]) | (f.glue_vrs if kind == f.real else set())
            valid = all(vr in own for vr in vrs)
            must_succeed = valid and not any(vr in f.outputs for vr in vrs)
            expect_error = not valid
            glue = f.wrong_integer(kind, vrs)
            face_refusal = glue or bool(f.hidden.intersection(vrs))
            if shadow is not None and not f.glue_vrs.intersection(vrs):
                expected = ERROR if glue else shadow.get(f.library[kind], vrs)[0]
            keeps_pristine = True
        elif op == "inputs":
            values = realistic(f, call[1], next_t)
            status = inst.set_named(values)
            if shadow is not None:
                expected = OK
                for name, value in values.items():
                    expected = max(expected, shadow.set("Real", [m.vr(name)], [value]))
            keeps_pristine = call[1] == 1.0
            self.motion_fresh = status == OK
        elif op == "extreme":
            values = extreme(f, *call[1:], next_t)
            status = inst.set_named(values)
            if shadow is not None:
                expected = OK
                for name, value in values.items():
                    expected = max(expected, shadow.set("Real", [m.vr(name)], [value]))
            self.motion_fresh = status == OK
        elif op == "defaults":  # every parameter back to its start value
            status = OK
            if mode in ("instantiated", "initialization"):
                for kind, vrs, values in f.defaults:
                    status = max(status, inst.set(kind, vrs, values))
                    if shadow is not None:
                        shadow.set(f.library[kind], vrs, values)
                assert status == OK, inst.log[n_log:]
        elif op == "step":
            _, t, h = call
            t = next_t if t == "next" else t
            # docs/fmi.md: the communication point must continue the last step within
            # 1e-9 of the step plus a few ulps (flagged here only well beyond that)
            slack = 2 * (1e-9 * abs(h) + 16 * math.ulp(max(abs(t), abs(next_t))))
            expect_error = mode != "stepping" or not math.isfinite(t) or not (
                abs(t - next_t) <= slack)
            # the default unit on consistent inputs steps on: a master's valid step
            must_succeed = (self.pristine and mode == "stepping" and call[1] == "next"
                            and h in PRISTINE_STEPS)
            status = inst.step(t, h)
            if shadow is not None:
                expected = shadow.step(t, h)
            if status in (OK, WARNING):
                assert mode == "stepping"
            if must_succeed:
                f.pristine_steps += 1
            if status == ERROR and any(reason in m for m in inst.messages(n_log, ERROR)
                                       for reason in COSTLY_REFUSALS):
                self.costly += 1
            keeps_pristine = must_succeed
        elif op == "setup":
            _, start, _, stop = call
            expect_error = mode != "instantiated" or not math.isfinite(start)
            status = inst.setup(start, stop=stop)
            if shadow is not None:
                expected = shadow.setup(start)
        elif op in ("enter", "exit", "terminate", "reset"):
            expect_error = {"enter": mode != "instantiated",
                            "exit": mode != "initialization",
                            "terminate": mode not in ("stepping", "initialization"),
                            "reset": False}[op]
            # the default parameters and consistent inputs initialize
            must_succeed = op == "exit" and self.init_progress == 4
            if op == "enter" and not fmi2:  # FMI 3.0: setup and enter in one call
                status = inst.enter(self.start)
                if shadow is not None:
                    expected = shadow.setup(self.start)
                    expected = shadow.enter() if expected == OK else expected
            else:
                status = getattr(inst, op)()
                if shadow is not None:
                    expected = getattr(shadow, op)()
        elif op == "cancel":  # FMI 2.0's fmi2CancelStep, FMI 3.0's fmi3EnterEventMode
            status = inst.call(m.dialect.not_provided)
            expect_error = keeps_pristine = True
        elif op == "derivative":
            status = inst.call("GetDirectionalDerivative", *m.dialect.derivative_arguments)
            expect_error = keeps_pristine = True
        elif op == "get_state":
            status = self.get_state(call[1])
            keeps_pristine = True
        elif op == "set_state":
            i = call[1]
            state = self.slots[i]
            must_succeed = self.own[i]
            status = inst.set_state(state)
            if shadow is not None:
                expected = shadow.restore(self.records[i])
            if not self.own[i]:
                f.count("set_resealed", status)
            keeps_pristine = self.own[i] and self.slot_pristine[i]
        elif op == "free_state":
            state = self.slots[call[1]]
            status = inst.free_state(state)
            assert status == OK and state.value is None
            self.slots[call[1]] = self.records[call[1]] = None
            keeps_pristine = True
        elif op == "serialize":
            _, i, extra = call
            status, data = inst.serialize(self.slots[i], extra=extra)
            expect_error = extra < 0
            must_succeed = extra >= 0
            if status == OK:
                size = inst.state_size(self.slots[i])[1]
                assert data[size:] == bytes(len(data) - size)
                if shadow is not None:
                    assert state_payload(data) == self.records[i], (
                        "the serialized state is not the record the library saved", call)
                self.blobs.append((data, self.own[i] and self.slot_pristine[i]))
            keeps_pristine = True
        elif op == "deserialize":
            _, i, at, how, real, integer = call
            source, pristine = (self.blobs[at % len(self.blobs)] if self.blobs
                                else (inst.serialized(), self.pristine))
            data = (resealed(m, source, how, at, real, integer) if how.startswith("reseal")
                    else damaged(source, how, at))
            status, state = inst.deserialize(data, into=self.slots[i])
            if how in DAMAGED and data != source:
                expect_error = True
            else:
                must_succeed = True  # a valid envelope: its content is checked at set
            if status in (OK, WARNING):
                self.slots[i] = state
                self.records[i] = state_payload(data)
                self.own[i] = how in ("as is", "pad")
                self.slot_pristine[i] = self.own[i] and pristine
            keeps_pristine = True
        elif op == "logging":
            _, on, cats = call
            expect_error = any(c is None or _bad_utf8(c) for c in cats)
            status = inst.logging(on, cats)
            keeps_pristine = True
        elif op == "status" and not fmi2:  # FMI 3.0's time: the state's, in every mode
            status, t = inst.time()
            assert status == OK and t.hex() == record.time.hex(), (call, t, record.time)
            keeps_pristine = True
        elif op == "status":
            _, which, kind = call
            status = _status_call(inst, which, kind)
            expect_error = not (which == "Boolean" and kind == 3) and not (
                which == "Real" and kind == 2 and mode in ("stepping", "terminated"))
            keeps_pristine = True
        elif op == "instantiate":
            assert _bad_instantiate(m, call[1]) is None, call
            assert any(s >= ERROR for s, _, _ in m.pending_log), m.pending_log
            return
        else:
            raise AssertionError(call)
        # -- what the call answered
        self.track_initialization(call, status)
        if op == "exit" and must_succeed:
            self.pristine = status == OK
        elif op == "set_state" and status != ERROR:  # restored: as pristine as the state was
            self.pristine = self.own[call[1]] and self.slot_pristine[call[1]]
        else:
            self.pristine = self.pristine and keeps_pristine and status != ERROR
        f.by_status[status] = f.by_status.get(status, 0) + 1
        f.count(op, status)
        # the library's answer first (what a model predicts), then what holds whatever the
        # model (also without the shadow)
        if expected is not None:
            f.compared += 1
            assert status == expected, ("the FMU's status is not the library's", call, status,
                                        expected, inst.log[n_log:],
                                        shadow.message() if expected else "")
            if status == ERROR and not face_refusal:
                assert shadow.message() in inst.messages(n_log, ERROR), (
                    "the FMU's message is not the library's", call, shadow.message(),
                    inst.log[n_log:])
        assert status in ALLOWED, (call, status, inst.log[n_log:])
        if expect_error:
            assert status == ERROR, (call, mode, status, inst.log[n_log:])
        if must_succeed:
            assert status in (OK, WARNING), ("a valid call was refused", call, mode,
                                             inst.log[n_log:])
        if status == ERROR:
            f.refusals += 1
            assert inst.messages(n_log, ERROR), ("refused without a message", call)
        if op in ("free_state",):
            return
        after = observe(f, inst)
        self.observed = after
        self.compare(call)
        if status == ERROR and op not in ("get_state",):
            assert after[0] == before[0], ("a refused call changed variables", call)
            assert after[1] == before[1], ("a refused call changed the state", call)
        if status in (OK, WARNING):
            check_finite(f, after, call)
        if readback is not None and status != ERROR:
            kind, vrs, values = readback
            st_, got = inst.get(kind, vrs)
            assert st_ == OK
            last = {}
            for vr, v in zip(vrs, values, strict=True):
                last[vr] = v
            for vr, g in zip(vrs, got, strict=True):
                assert _same(f.library[kind], g, last[vr]), (call, vr, g, last[vr])

    def track_initialization(self, call, status: int) -> None:
        """Progress through setup(0) -> enter -> defaults -> inputs(1.0) -> exit (FMI 3.0's
        setup: the start time of its enter)."""
        steps = {0: ("setup",), 1: ("enter",), 2: ("defaults",), 3: ("inputs",)}
        op = call[0]
        expected_ops = steps.get(self.init_progress)
        if (status == OK and expected_ops is not None and op == expected_ops[0]
                and (op != "setup" or call[1] == 0.0) and (op != "inputs" or call[1] == 1.0)):
            self.init_progress += 1
        else:
            self.init_progress = 1 if (op == "setup" and status == OK and call[1] == 0.0) else 0


def _diff(a: dict, b: dict) -> list:
    return [(kind, i, x, y) for kind in a for i, (x, y) in enumerate(zip(a[kind], b[kind],
                                                                         strict=True))
            if x != y][:5]


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
        "model exchange": lambda: m.instantiate_other("model exchange") or None,
        "latin-1 name": lambda: m.instantiate(name=b"\xdcbersetzung"),
        "blank name": lambda: m.instantiate(name=b" "),
        "wrong guid": lambda: m.instantiate(guid=b"{not-the-guid}"),
        "unzip root": lambda: m.instantiate(location=("file://" + str(root)).encode()),
        "http": lambda: m.instantiate(location=b"http://localhost/resources"),
        "relative": lambda: m.instantiate(location=b"resources"),
        "missing": lambda: m.instantiate(location=b"/nonexistent/resources"),
    }[how]()


def run_example(f: Fuzz, calls: list) -> None:
    example = Example(f)
    try:
        for call in calls:
            example.run(call)
    finally:
        example.close()


def minimum_counts(examples: int) -> dict:
    """What a run must have made at least: each state operation, pristine steps."""
    n = max(5, examples // 10)
    return {**{op: n for op in STATE_OPS}, "pristine steps": max(5, examples // 5)}


def main(fmu: Path, examples: int, seed_value: int, work: Path, use_shadow: bool = True,
         shrink: bool = True) -> dict:
    model = Model(unpack(fmu, work / fmu.stem))
    clock = CallClock()
    model.lib = clock.wrap(model.lib)  # every call into the FMU timed
    assert CO_SIMULATION == 1
    table = work / "speed.csv"
    table.write_text("time,speed\n0,80\n0.5,95\n1,85\n")
    f = Fuzz(model, table, use_shadow)
    extra_strings = st.sampled_from([str(table).encode()])
    global strings_any
    strings_any = st.one_of(strings_any, extra_strings)

    @seed(seed_value)
    @settings(max_examples=examples, deadline=None, database=None,
              suppress_health_check=list(HealthCheck),
              phases=[Phase.generate, Phase.shrink] if shrink else [Phase.generate])
    @given(backbone(f), st.lists(call_strategy(f), min_size=3, max_size=14))
    def fuzz(tour, segments):
        run_example(f, [*tour, *(call for segment in segments for call in segment)])

    fuzz()
    counts = {op: sum(f.by_op.get(op, [0, 0])) for op in STATE_OPS}
    counts["pristine steps"] = f.pristine_steps
    summary = {"fmu": fmu.stem, "examples": examples, "seed": seed_value, "calls": f.calls,
               "refused": f.refusals, "compared with the library": f.compared,
               "counts": counts, "steps skipped after costly refusals": f.steps_skipped,
               **clock.summary(),
               "by_call": f.by_op,
               "statuses": {name: f.by_status.get(s, 0) for s, name in
                            ((OK, "OK"), (WARNING, "Warning"), (DISCARD, "Discard"),
                             (ERROR, "Error"), (FATAL, "Fatal"), (PENDING, "Pending"))}}
    short = {op: (counts[op], n) for op, n in minimum_counts(examples).items()
             if counts[op] < n}
    assert not short, f"too few of these calls (made, needed): {short}; {summary}"
    return summary


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    fmu_path, n_examples, seed_arg, folder = args[:4]
    summary = main(Path(fmu_path), int(n_examples), int(seed_arg), Path(folder),
                   use_shadow="--no-shadow" not in sys.argv and
                   os.environ.get("RATTLE_FUZZ_SHADOW", "1") != "0",
                   shrink="--no-shrink" not in sys.argv)
    print(json.dumps(summary))
