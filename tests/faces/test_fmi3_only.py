"""What only FMI 3.0 has, on its face (fmu_src/fmi3/fmi3_functions.c), call by call through the
raw driver: its types (Float64, Int32, Enumerations as Int64, Boolean, String) and the value
types the units lack, nValues, the independent variable time, fmi3DoStep's output pointers,
and the cost of its calls at costly states.  What it is asked alike with the FMI 2.0 faces is
in test_glue.py (and test_instantiate.py, test_values.py, test_states.py) and in the boundary
rows and fuzzer (tests/adversarial/test_fmi_boundary.py: among them FMU states taken before
the first step, their time and outputs restored, row 16)."""

from __future__ import annotations

import ctypes
import itertools
import sys
from ctypes import c_double, c_uint
from pathlib import Path

import pytest

from drive_rattle.parameters import MeshParameters, specs

from .calls import last, started
from .raw_fmi import ERROR, OK, Model, unpack

ROOT = Path(__file__).resolve().parents[2]

pytestmark = pytest.mark.parametrize("face", ["fmi3"], indirect=True)


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


def test_values_counted_and_types_the_units_lack(mesh):
    """nValues must equal nValueReferences (every variable is a scalar); the value types the
    units have no variable of, and clocks, are refused (asking for nothing is not); nothing
    changed.  NULL arrays: test_glue.py."""
    inst = mesh.instantiate(b"glue")
    L, vr = mesh.lib, (c_uint * 1)(mesh.vr("gear.backlash"))
    out = (c_double * 1)()
    assert L.fmi3GetFloat64(inst.c, vr, 1, out, 2) == ERROR
    assert last(inst)[2].startswith("fmi3GetFloat64: nValues = 2 but nValueReferences = 1: "
                                    "every variable of this FMU is a scalar")
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


# ------------------------------------------------------------------ the step
def test_do_step_output_pointers_null_refused(mesh):
    """fmi3DoStep writes its four outputs through the host's pointers: a NULL one is refused
    (with the pointer named), nothing moves, and the next step is the one expected.  Its
    outputs and refusals otherwise: test_glue.py."""
    inst = started(mesh)
    assert inst.step(0.0, 1e-4) == OK
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


# ------------------------------------------------------------------ the cost of a call
def test_the_slowest_call_at_costly_states_within_its_bound(face_fmus, tmp_path):
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
    for name, fmu in face_fmus.items():
        model = Model(unpack(fmu, tmp_path / name))
        model.lib = clock.wrap(model.lib)
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
            record = Record.decode(state_payload(blob), model.unit_variables)
            record.model["pinion_w"] = 1.001e7
            st, state = inst.deserialize(with_payload(blob, record))
            assert st == OK and inst.set_state(state) == OK, inst.log[-2:]
            assert inst.step(1e-4, 1e-4) == ERROR and "budget" in last(inst)[2]
            inst.free_state(state)
            inst.free()
    summary = clock.summary()
    print(slowest_line("FMI 3.0", summary))
    assert summary["nearest the bound"]["fraction"] <= LOADED, summary["nearest the bound"]
