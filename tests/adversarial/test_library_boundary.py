"""The model library's own boundary, in process (drive_rattle.units): the messages and the
"a refused call changes nothing" rule that both FMI faces pass on verbatim.  The same cases
through the built FMUs of both flavours: boundary_rows.py (row 15)."""

from __future__ import annotations

import re
import struct

import pytest

from drive_rattle.library import DRIVELINE, MESH, ModelError
from drive_rattle.units import Unit

#: A geometry whose exact Hertz law the library cannot tabulate to its tolerance (found by a
#: random search over the parameter ranges).
UNTABULATED = {"contact.hertz_law": 0, "gear.z_pinion": 40, "gear.z_wheel": 193,
               "gear.m_n": 0.0012056139780054268, "contact.crowning": 0.0006260396805984489,
               "gear.b": 0.006508412840421393}


def test_the_exact_hertz_refusal_names_the_value_and_what_is_allowed():
    with pytest.raises(ModelError) as err:
        Unit(MESH, UNTABULATED)
    text = str(err.value)
    assert text.startswith("exitInitializationMode: parameter 'contact.hertz_law' = 0 "), text
    assert "cannot be tabulated" in text
    assert "allowed for this geometry: contact.hertz_law = 1 (equivalent sphere)" in text
    Unit(MESH, {**UNTABULATED, "contact.hertz_law": 1}).close()  # what it says works


def _records(tmp_path) -> list[tuple[str, Unit]]:
    table = tmp_path / "speed.csv"
    table.write_text("time,speed\n0,80\n0.01,95\n0.02,85\n", encoding="utf-8")
    stepped = Unit(MESH)
    stepped.advance(1e-4)
    drive = Unit(DRIVELINE, {"engine.speed_table": str(table)})
    drive.advance(1e-4)
    ended = Unit(DRIVELINE)
    ended.advance(1e-4)
    ended.terminate()
    return [("mesh instantiated", Unit(MESH, initialize=False)), ("mesh stepping", stepped),
            ("driveline with a speed table", drive), ("driveline terminated", ended)]


def test_a_truncated_record_says_where_it_ends(tmp_path):
    """Every prefix of a record is refused as truncated -- "the record ends before <what>" --
    never with another field's reason (it said "motion inputs not finite", "flank in contact
    = 0: expected ...", "mode does not go with no model state")."""
    for name, unit in _records(tmp_path):
        record = unit.save()
        fresh = Unit(unit.kind, initialize=False)
        before = fresh.save()
        for length in range(1, len(record)):
            with pytest.raises(ModelError) as err:
                fresh.restore(record[:length])
            text = str(err.value)
            assert text.startswith("setFMUstate: the FMU state is invalid: the record ends "
                                   "before "), (name, length, text)
            assert text.endswith("; nothing changed")
        assert fresh.save() == before
        with pytest.raises(ModelError, match="the record is empty"):
            fresh.restore(b"")
        fresh.restore(record)  # whole, it restores
        assert fresh.save() == record


def test_a_saved_table_longer_than_any_file_is_refused_with_its_length(tmp_path):
    _, drive = _records(tmp_path)[2]
    record = bytearray(drive.save())
    rows = (3).to_bytes(8, "little")
    at = record.find(rows)  # the table's row count, followed by its times
    assert at > 0 and record.count(rows) == 1
    record[at:at + 8] = (2**40).to_bytes(8, "little")
    fresh = Unit(DRIVELINE, initialize=False)
    with pytest.raises(ModelError, match=r"the saved speed table's length = 1099511627776 rows:"
                                         r" expected an integer in \[0, 1048576\]"):
        fresh.restore(bytes(record))


@pytest.mark.parametrize("kind, motion, other", [
    (MESH, "pinion.w", "wheel.tau_mesh"), (MESH, "pinion.phi", 99999),
    (DRIVELINE, "wheel.w", "pinion.w"), (DRIVELINE, "wheel.phi", 99999)])
def test_a_refused_set_of_a_motion_input_changes_nothing(kind, motion, other):
    """A refused fmi2SetReal naming a motion input left the inputs marked as set (the unit then
    stopped reading them as held): the record and the next step show the difference."""
    import ctypes

    unit = Unit(kind)
    unit.advance(1e-4)
    record = unit.save()
    vrs = [unit.variables[motion].vr,
           unit.variables[other].vr if isinstance(other, str) else other]
    array = (ctypes.c_uint * 2)(*vrs)
    with pytest.raises(ModelError, match="nothing of this call was stored"):
        unit.call("rm_set_real", array, 2, (ctypes.c_double * 2)(123.0, 0.0))
    assert unit.save() == record
    # ... and the next step is the one of an untouched unit (the inputs held)
    twin = Unit(kind, initialize=False)
    twin.restore(record)
    unit.advance(1e-4)
    twin.advance(1e-4)
    assert unit.save() == twin.save() and unit.outputs() == twin.outputs()


@pytest.mark.parametrize("value", [0.0, 0.5])
def test_poisson_ratios_at_the_edges_of_their_range_are_accepted(value):
    """material.nu_* is declared [0, 0.5]: both edges are legal."""
    Unit(MESH, {"material.nu_pinion": value, "material.nu_wheel": value}).close()


@pytest.mark.parametrize("value, text", [(float("inf"), "inf"), (float("-inf"), "-inf"),
                                         (float("nan"), "nan"), (1e308, "1e+308")])
def test_a_refusal_names_any_value_given(value, text):
    """An infinite input is named in the refusal (the old kernel's message crashed on it)."""
    unit = Unit(MESH)
    record = unit.save()
    unit.set({"wheel.tau_load": value})
    with pytest.raises(ModelError, match=rf"input 'wheel.tau_load' = {re.escape(text)} is "):
        unit.advance(1e-4)
    unit.set({"wheel.tau_load": 0.15})
    assert unit.time == 0.0 and unit.save()[:40] == record[:40]


def test_a_step_beyond_the_longest_run_is_refused_so_every_saved_state_restores():
    """rm_restore accepts a time up to the start time + 4e9 s; a step that would end later is
    refused (it was accepted, and the state it left was then refused on restore)."""
    unit = Unit(MESH)
    unit.advance(1e-4)
    record = bytearray(unit.save())
    start, = struct.unpack_from("<d", record, 24)
    struct.pack_into("<d", record, 32, start + 4e9 - 5e-4)  # the header's time
    unit.restore(bytes(record))
    before = unit.save()
    with pytest.raises(ModelError) as err:
        unit.advance(1e-3)
    assert "ends beyond the longest run the unit supports; allowed: up to the start time 0 s" \
           " + 4e+09 s" in str(err.value), str(err.value)
    assert unit.save() == before  # nothing changed
    unit.advance(5e-4)  # to the bound: accepted, and what it leaves restores
    assert unit.time == start + 4e9
    saved = unit.save()
    with Unit(MESH, initialize=False) as other:
        other.restore(saved)
        assert other.save() == saved
