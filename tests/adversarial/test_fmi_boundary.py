"""No host crash, leak or half-applied call at the FMI boundary, and no OK status with a
non-finite output or state, on every face (tests/faces/conftest.py: the pythonfmu and native
FMI 2.0 FMUs, the native FMI 3.0 FMUs).

Every row of the boundary's table is a function of boundary_rows.py and the randomized boundary
fuzzer is boundary_fuzz.py, each written once for both standards; both drive the built FMUs
through raw ctypes (tests/faces/raw_fmi.py) in a child process, so that a crash of the host is
a failed test (its exit code), not a dead test session.  The rows of one face run in one child
(``rows_run``: Python starts and imports once, not once per row), which reports a line per row;
each row's test reads its own line.  A row the child did not report (it crashed or hung before)
runs again alone in a child of its own, so that a crash is pinned on its row.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from ..seeds import fuzz_seed
from .call_clock import LOADED, slowest_line

HERE = Path(__file__).resolve().parent
ROWS_SCRIPT = HERE / "boundary_rows.py"
FUZZ_SCRIPT = HERE / "boundary_fuzz.py"
ROWS = {
    1: "unpack folder named with a literal %20",
    2: "resource location not this FMU's resources folder",
    3: "NULL debug-logging category",
    4: "instance name and String values not UTF-8",
    5: "serialization buffer larger or smaller than the state",
    6: "getFMUstate into a non-NULL state: no leak",
    7: "own state restores without start solving or file reads",
    8: "multi-value set with one bad entry stores nothing",
    9: "speed table: FIFO, /dev/zero, oversize, too long a name",
    10: "extreme legal output shaft: stable and physical",
    11: "last successful time after a refused step; other interfaces refused",
    12: "corrupt, forged and foreign states refused",
    13: "counters saturate at the 32-bit integer limit",
    14: "non-UTF-8 unpack path; value references >= 2^31 reported unsigned",
    15: "no OK with a non-finite output or state",
    16: "a state taken before the first step restores its outputs",
}
#: Seconds for one row alone, and for all rows of a face in one child (about 10-25 s).
ROW_TIMEOUT = 300
ALL_ROWS_TIMEOUT = 1200
#: Examples per FMU and run: about 6000 calls per FMU, 5 to 20 s on the CI machine.
FUZZ_EXAMPLES = 250


def _child(args: list, timeout: float) -> subprocess.CompletedProcess:
    # (absolute: the child runs in this folder)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(HERE), *(
        os.path.abspath(p) for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p)])}
    return subprocess.run([sys.executable, *map(str, args)], capture_output=True, text=True,
                          timeout=timeout, cwd=HERE, env=env)


def _exit(code: int | None) -> str:
    if code is None:
        return f"killed after {ALL_ROWS_TIMEOUT} s"
    return f"exit code {code}{' (the host crashed)' if code < 0 else ''}"


@dataclass
class RowsRun:
    """What the child that ran every row of one face reported: each row's line ("ok" or
    "FAILED: <reason>") and its part of stderr (the traceback of a failure)."""

    lines: dict[int, str]
    stderr: dict[int, str]
    returncode: int | None  # None: killed at its timeout


@pytest.fixture(scope="module")
def rows_run(face, face_fmus, tmp_path_factory) -> RowsRun:
    folder = tmp_path_factory.mktemp(f"rows-{face.name}")
    try:
        run = _child([ROWS_SCRIPT, "all", face_fmus["GearMeshRattle"], face_fmus["Driveline"],
                      folder, "--keep-going"], ALL_ROWS_TIMEOUT)
        stdout, stderr, code = run.stdout, run.stderr, run.returncode
    except subprocess.TimeoutExpired as timeout:
        stdout, stderr, code = (_text(timeout.stdout), _text(timeout.stderr), None)
    lines = {int(m[1]): m[2] for m in re.finditer(r"^row (\d+) (ok|FAILED: .*)$", stdout, re.M)}
    parts = re.split(r"^=== row (\d+)$", stderr, flags=re.M)
    return RowsRun(lines, {int(k): text for k, text in zip(parts[1::2], parts[2::2],
                                                           strict=True)}, code)


def _text(out) -> str:
    return out.decode(errors="replace") if isinstance(out, bytes) else out or ""


@pytest.mark.parametrize("row", list(ROWS), ids=[f"row{k}-{v}" for k, v in ROWS.items()])
@pytest.mark.slow
def test_boundary_row(row, face, face_fmus, rows_run, tmp_path):
    """The row's line from the child that ran every row of the face; without one (that child
    crashed or hung first) the row alone in a child of its own, so that a crash is its row's."""
    line = rows_run.lines.get(row)
    if line is None:  # the face's child died before this row's line: the row alone
        run = _child([ROWS_SCRIPT, row, face_fmus["GearMeshRattle"], face_fmus["Driveline"],
                      tmp_path], ROW_TIMEOUT)
        assert run.returncode == 0, (
            f"row {row} ({ROWS[row]}) failed on the {face.name} face, run alone after the "
            f"child of every row ended without its line ({_exit(rows_run.returncode)}): "
            f"{_exit(run.returncode)}\nstdout:\n{run.stdout[-2000:]}\n"
            f"stderr:\n{run.stderr[-4000:]}")
        assert f"row {row} ok" in run.stdout, run.stdout[-2000:]
        return
    assert line == "ok", (f"row {row} ({ROWS[row]}) failed on the {face.name} face: {line}\n"
                          f"{rows_run.stderr.get(row, '')[-4000:]}")


@pytest.mark.slow  # 5 to 25 s per FMU, with the seed
@pytest.mark.seeded
@pytest.mark.parametrize("name", ["GearMeshRattle", "Driveline"])
def test_boundary_fuzzer(name, face, face_fmus, tmp_path):
    """Random call sequences against each FMU of each face, from the unit's fixed seed
    (tests/seeds.py; RATTLE_FUZZ_SEED replaces it, tests/soak.py draws fresh ones)."""
    seed = fuzz_seed(name)
    run = _child([FUZZ_SCRIPT, face_fmus[name], FUZZ_EXAMPLES, seed, tmp_path], 600)
    calls = [line for line in run.stderr.splitlines() if line.startswith("CALL ")]
    report = [line for line in run.stderr.splitlines() if not line.startswith("CALL ")]
    assert run.returncode == 0, (
        f"fuzzer failed on {name} of the {face.name} face with RATTLE_FUZZ_SEED={seed}: "
        f"{_exit(run.returncode)}\n"
        "last calls:\n" + "\n".join(calls[-15:]) + "\n" + "\n".join(report[-60:]))
    summary = json.loads(run.stdout.strip().splitlines()[-1])
    print(f"fuzzer {name} ({face.name}): seed {seed}, {summary['calls']} calls, "
          f"{summary['refused']} refused, {summary['compared with the library']} held against "
          f"the library, state calls {summary['counts']}, statuses {summary['statuses']}")
    assert summary["calls"] >= 2000
    assert summary["statuses"]["Fatal"] == summary["statuses"]["Discard"] == 0
    # Both outcomes were exercised: refusals and accepted calls; most calls were held against
    # the library's answer; the fuzzer itself enforced its minimum of every state call.
    assert summary["refused"] >= 200 and summary["statuses"]["OK"] >= 500
    assert summary["compared with the library"] >= summary["calls"] // 2
    # No call ran longer than its bound (docs/fmi.md: 50 ms per 1e-4 s of step), with a
    # margin of LOADED for a machine shared with other jobs (the fuzzer's own shadow runs
    # beside it).
    print(slowest_line(name, summary))
    assert summary["nearest the bound"]["fraction"] <= LOADED, summary["nearest the bound"]


@pytest.mark.parametrize("kind", ["GearMeshRattle", "Driveline"])
def test_the_fuzzer_reseals_any_record_it_can_meet(kind, monkeypatch):
    """The fuzzer's own editor of states (``boundary_fuzz.resealed``) on every record it can
    be handed: whole, cut at every length (a cut record re-sealed, restored, refused and
    serialized again is one), empty, and no record at all.  It failed twice on such inputs in
    a soak (a division by zero on an empty record; the Driveline's five leading doubles
    assumed in a cut one) -- a failure of the test, not of the FMU."""
    import types

    from drive_rattle.library import DRIVELINE, MESH
    from drive_rattle.units import Unit

    monkeypatch.syspath_prepend(str(HERE))
    import boundary_fuzz
    from raw_fmi import HEADER, fnv1a64, state_payload, with_payload

    unit = Unit({"GearMeshRattle": MESH, "Driveline": DRIVELINE}[kind])
    unit.advance(1e-4)
    record = unit.save()
    model = types.SimpleNamespace(unit_variables={
        name: (v.vr, v.type, v.causality) for name, v in unit.variables.items()})
    envelope = bytes(HEADER)
    for payload in [record[:n] for n in range(len(record) + 1)] + [b"no record at all"]:
        blob = with_payload(envelope, payload)
        for how in ("reseal flip", "reseal truncate", "reseal extend", "reseal field"):
            for at in (0, 1, 7, 33, 4360):
                edited = boundary_fuzz.resealed(model, blob, how, at, 1.5, 2**53)
                data = state_payload(edited)  # a valid envelope around the edited record
                assert edited[:16] == blob[:16] and len(edited) == HEADER + len(data)
                assert int.from_bytes(edited[24:32], "little") == fnv1a64(data), (how, at)


def test_the_fuzzer_cuts_a_state_short_of_its_record(monkeypatch):
    """The fuzzer's "truncate" damage on a state serialized into a larger buffer (its record,
    then zeros): every cut ends inside the state, never among the zeros after it -- a cut
    there leaves the whole state, which a unit rightly accepts (the fuzzer once expected a
    refusal of it: the Driveline's seed in tests/seeds.py)."""
    from drive_rattle.library import DRIVELINE
    from drive_rattle.units import Unit

    monkeypatch.syspath_prepend(str(HERE))
    import boundary_fuzz
    from raw_fmi import HEADER, with_payload

    unit = Unit(DRIVELINE)
    unit.advance(1e-4)
    state = with_payload(bytes(HEADER), unit.save())
    padded = state + bytes(7)
    for at in range(3 * len(padded)):
        assert len(boundary_fuzz.damaged(padded, "truncate", at)) < len(state), at
