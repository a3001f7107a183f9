"""The unit's binary record (record.c; rm_save and rm_restore, unit.c): a restored unit
continues exactly, also in another unit never initialized and without its speed table's file;
the onset counters saturate at the record's bound; a refused record changes nothing; a record
beyond what legal inputs reach is refused; a state without a model restores its outputs."""

import math
import struct

import pytest

from drive_rattle import (
    COAST,
    DRIVE,
    DrivelineParameters,
    DrivelineUnit,
    MeshParameters,
    MeshUnit,
    ModelError,
    Unit,
)
from drive_rattle.library import DRIVELINE, MESH
from tests.adversarial.records import Record

from .helpers import H, assert_refused_and_unchanged, history, pinion_with_order


def fluctuating_pinion(k):
    return pinion_with_order(k * H, 86.92, 2000.0, 2 * 830 / 60)


def run_mesh(unit, k0, n, load=0.15):
    """n steps from step k0 of the fluctuating pinion: every output (floats as hex) and the
    events of every step."""
    rows = []
    for k in range(k0, k0 + n):
        phi, w, a = fluctuating_pinion(k)
        unit.advance(H, {"pinion.phi": phi, "pinion.w": w, "pinion.a": a,
                         "wheel.tau_load": load})
        report = unit.report()
        rows.append(({name: (v.hex() if isinstance(v, float) else v)
                      for name, v in unit.outputs().items()}, report.events, unit.time))
    return rows


MESH_STARTS = {
    "paper": {},
    "free start": {"init_in_contact": False, "phi_start": 0.0, "w_start": 44.5},
    "damped, spur, form 2": {"dissipation": 2, "damping": 300.0, "beta": 0.0,
                             "friction_form": 2, "sigma": 1e-7},
    # the contact's dissipation set at its onset is part of the record
    "squeeze film, Barus, EHL film": {"dissipation": 3, "viscous_law": 1, "film": 1,
                                      "shear_speed": 1},
    "mesh damping ratio, form 1": {"dissipation": 4, "friction_form": 1},
}


@pytest.mark.parametrize("changes", MESH_STARTS.values(), ids=MESH_STARTS)
def test_a_restored_mesh_unit_continues_exactly(changes):
    p = MeshParameters(**changes)
    unit = MeshUnit(p, *fluctuating_pinion(0)[:2], 0.15)
    run_mesh(unit, 0, 30)
    saved = unit.save()
    first = run_mesh(unit, 30, 60)
    assert any(events for _, events, _ in first)
    unit.restore(saved)
    assert unit.save() == saved
    assert run_mesh(unit, 30, 60) == first
    # ...and restored into another unit of the kind, never initialized (nothing is solved:
    # the free start's check against the pinion, which has moved, is not made again)
    with Unit(MESH, initialize=False) as other:
        other.restore(saved)
        assert other.save() == saved and other.phase == "stepping"
        assert run_mesh(other, 30, 60) == first


def test_the_onset_counters_stop_at_2_53_and_such_a_state_restores():
    """The cumulative counters saturate at 2^53, the largest count the record accepts: a unit
    restored with its counters one below and at that bound counts up to it and no further,
    and the state it then saves restores (a fuzzer found the state saved one past the bound
    and refused on restore)."""
    unit = MeshUnit(MeshParameters(), *fluctuating_pinion(0)[:2], 0.15)
    run_mesh(unit, 0, 10)
    variables = {name: (v.vr, v.type, v.causality) for name, v in unit.variables.items()}
    record = Record.decode(unit.save(), variables)
    cap = 2**53
    record.model["n_drive"], record.model["n_coast"] = cap - 1, cap
    unit.restore(record.encode())
    rows = run_mesh(unit, 10, 400)
    kinds = [(e.kind, e.flank) for _, events, _ in rows for e in events]
    assert kinds.count(("onset", DRIVE)) >= 2 and kinds.count(("onset", COAST)) >= 1
    saved = unit.save()
    after = Record.decode(saved, variables).model
    assert (after["n_drive"], after["n_coast"]) == (cap, cap)
    with Unit(MESH, initialize=False) as other:
        other.restore(saved)
        assert other.save() == saved
    # the FMI Integer outputs (32 bits) show the counts clipped, as before
    assert unit.outputs()["mesh.impacts_drive"] == 2**31 - 1


def run_driveline(unit, k0, n):
    rows = []
    for k in range(k0, k0 + n):
        w = 44.57 + 0.3 * math.sin(k / 7)
        unit.advance(H, {"wheel.phi": 44.57 * k * H, "wheel.w": w})
        rows.append({name: v.hex() for name, v in unit.outputs().items()})
    return rows


@pytest.mark.parametrize("table", [False, True])
def test_a_restored_driveline_continues_exactly_even_without_its_speed_table(table, tmp_path):
    changes = {}
    if table:
        path = tmp_path / "speed.csv"
        path.write_text("time,speed\n0,80\n0.004,95\n0.008,85\n")
        changes = {"speed_table": str(path)}
    unit = DrivelineUnit(DrivelineParameters(**changes), 0.0, 44.57)
    run_driveline(unit, 0, 20)
    saved = unit.save()
    first = run_driveline(unit, 20, 100)
    if table:
        path.unlink()  # the record holds the table
    unit.restore(saved)
    assert run_driveline(unit, 20, 100) == first
    with Unit(DRIVELINE, initialize=False) as other:
        other.restore(saved)
        assert run_driveline(other, 20, 100) == first


def test_refused_records_leave_the_unit_unchanged():
    unit = history()
    saved = unit.save()
    unit.step(H, 87.0 * 5 * H, 87.0, 0.0, 0.1)
    driveline = DrivelineUnit().save()
    flipped = bytearray(saved)
    flipped[8] ^= 0xFF  # the version
    for record in (saved[:-1], saved + b"\0", saved[: len(saved) // 2], driveline, b"",
                   b"RATLUNIT", bytes(flipped)):
        message = assert_refused_and_unchanged(unit, "rm_restore", record, len(record),
                                               match="state is invalid")
        assert message.endswith("nothing changed")
    unit.restore(saved)  # the good one still restores


# ------------------------------------------------------------------ values beyond reach
def edited(unit, **changes) -> bytes:
    """The unit's record with model fields (records.MESH_MODEL) or held inputs changed: the
    held inputs are "initial.<k>" (at the end of initialization) and "last.<k>" (the last
    step's motion inputs) of the boundary that follows the mesh's fields."""
    variables = {n: (v.vr, v.type, v.causality) for n, v in unit.variables.items()}
    record = Record.decode(unit.save(), variables)
    rest = bytearray(record.rest)
    for name, value in changes.items():
        if name.startswith(("initial.", "last.")):
            k = int(name.split(".")[1])
            at = 8 * k if name.startswith("initial.") else 32 + 8 * k
            rest[at:at + 8] = struct.pack("<d", value)
        else:
            record.model[name] = value
    record.rest = bytes(rest)
    return record.encode()


@pytest.mark.parametrize("changes, match", [
    # the last pinion speed: |pinion.w| + |pinion.a| solver.h_comm_max at most
    ({"pinion_w": -1e20}, r"the pinion speed = -1e\+20 rad/s: expected within "
                          r"\[-1.001e\+07, 1.001e\+07\] rad/s"),
    ({"pinion_w": 1.002e7}, r"the pinion speed = 1.002e\+07 rad/s"),
    # the inputs held by the boundary: within their declared ranges
    ({"initial.1": 2e4}, r"input 'pinion\.w' at the end of initialization = 2e\+04: "
                         r"expected within \[-10000, 10000\] rad/s"),
    ({"last.2": -1e8}, r"input 'pinion\.a' of the last step = -1e\+08: expected within "
                       r"\[-1e\+07, 1e\+07\] rad/s2"),
])
def test_a_record_beyond_what_legal_inputs_reach_is_refused(changes, match):
    """A record's pinion speed and held inputs beyond what the unit reaches from inputs in
    their declared ranges (a state with the last pinion speed at -1e20 rad/s made the next
    held 1e-4 s step run for 38 s) are refused, naming the field, the value and the range."""
    unit = history(MeshParameters(init_in_contact=False))  # solver.h_comm_max = 1 s
    unit.step(H, 87.0 * 5 * H, 87.0, 0.0, 0.1)  # a last step: its motion inputs are held
    record = edited(unit, **changes)
    assert_refused_and_unchanged(unit, "rm_restore", record, len(record), match=match)
    unit.restore(edited(unit))  # the same record unedited restores


def test_the_fastest_record_a_held_step_meets_is_refused_within_its_budget():
    """The fastest last pinion speed a record may hold, held for a 1e-4 s step: the pinion
    runs 1000 rad through the teeth, refused within the step's work budget (10000 substeps
    and 20000 evaluations of the loads per 1e-4 s) with a message naming it."""
    unit = history(MeshParameters(init_in_contact=False))
    unit.step(H, 87.0 * 5 * H, 87.0, 0.0, 0.1)
    unit.restore(edited(unit, pinion_w=1.001e7))
    with pytest.raises(ModelError, match="budget"):
        unit.call("rm_do_step", unit.time, H)


# ------------------------------------------------------------------ states without a model
def taken_before_the_first_step(kind, how):
    """A fresh unit's record taken in Instantiated Mode, or after terminate from
    Initialization Mode (no model either way), and that unit's outputs then."""
    unit = Unit(kind, initialize=False)
    if how == "terminated from initialization":
        unit.call("rm_setup", 3.0)
        unit.call("rm_enter_initialization")
        unit.terminate()
    return unit.save(), unit.outputs(), unit._lib.rm_time(unit._ptr)


@pytest.mark.parametrize("how", ["instantiated", "terminated from initialization"])
@pytest.mark.parametrize("kind", [MESH, DRIVELINE])
def test_a_state_taken_before_the_first_step_restores_its_outputs_and_time(kind, how):
    """Restored into a unit that ran, a state taken before any step outputs what it was taken
    with (a fresh unit's values), not the earlier run's (wheel.w came back 44.57 instead of
    0), and its time (rm_time) is the state's."""
    record, outputs, time = taken_before_the_first_step(kind, how)
    ran = Unit(kind)
    ran.advance(H)
    ran.advance(H)
    assert ran.outputs() != outputs  # the run moved them
    ran.restore(record)
    assert ran.outputs() == outputs
    assert ran._lib.rm_time(ran._ptr) == time == (0.0 if how == "instantiated" else 3.0)
