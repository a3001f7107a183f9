"""Sweeps on dask: designs, metrics against closed forms, a 2-worker run, failure, resume; one
writer per result file, rows cut short, a full disk, exit statuses and requests refused before
any work."""

import errno
import math
import subprocess
import sys
import time

import numpy as np
import pytest

from drive_rattle_cosim import sweep
from drive_rattle_cosim.sweep import (
    BANDS,
    MAX_CASES,
    Case,
    ResultFileBusyError,
    ResultWriter,
    SweepInterruptedError,
    grid_design,
    latin_hypercube_design,
    rattle_metrics,
    read_results,
    run_case,
    run_sweep,
)

RANGES = {"GearMeshRattle.gear.backlash": (0.05e-3, 0.2e-3), "Driveline.vehicle.drag": (0.1, 0.3)}


def test_grid_design():
    cases = grid_design(RANGES, 3)
    assert len(cases) == 9 and len({c.case_id for c in cases}) == 9
    values = sorted({c.parameters["Driveline.vehicle.drag"] for c in cases})
    assert values == pytest.approx([0.1, 0.2, 0.3])
    assert grid_design(RANGES, 3) == cases  # ids are stable across runs
    with pytest.raises(ValueError, match="range"):
        grid_design({"Driveline.vehicle.drag": (1.0, 0.0)}, 2)
    # a parameter held at one value is one value of the grid, not a repeated case
    held = grid_design({**RANGES, "Driveline.shaft.k": (0.3, 0.3)}, 3)
    assert len(held) == 9 and len({c.case_id for c in held}) == 9


def test_latin_hypercube_is_stratified_and_reproducible():
    cases = latin_hypercube_design(RANGES, 10, seed=3)
    assert cases == latin_hypercube_design(RANGES, 10, seed=3)
    for name, (lo, hi) in RANGES.items():
        strata = sorted(int((c.parameters[name] - lo) / (hi - lo) * 10) for c in cases)
        assert strata == list(range(10))  # one sample per stratum in every dimension


def test_rattle_metrics_against_closed_forms():
    T, fs = 1.0, 10_000
    t = np.arange(int(T * fs) + 1) / fs
    f0, A = 300.0, 2.0
    W = 5.0 + A * np.sin(2 * np.pi * f0 * t)
    # Three drive onsets (speeds 1, 2, 3 mm/s) and one coast onset (4 mm/s).
    drive = np.zeros(t.size, dtype=int)
    coast = np.zeros(t.size, dtype=int)
    v = np.zeros(t.size)
    for k, (flank, speed) in zip((100, 2000, 5000, 8000),
                                 [(1, 1e-3), (1, 2e-3), (-1, 4e-3), (1, 3e-3)], strict=True):
        (drive if flank > 0 else coast)[k:] += 1
        v[k:] = speed
    signals = {"mesh.W": W, "mesh.W_peak": W, "mesh.n_contact": (W > 5.0).astype(int),
               "mesh.impacts_drive": drive, "mesh.impacts_coast": coast, "mesh.v_impact": v,
               "wheel.phi": 44.5 * t, "mesh.delta_peak": np.zeros(t.size)}
    m = 0.76
    out = rattle_metrics(t, signals, m)
    assert out["impacts_per_s_drive"] == pytest.approx(3.0)
    assert out["impacts_per_s_coast"] == pytest.approx(1.0)
    assert out["rattle_index_W"] == pytest.approx(0.5 * m * (1 + 4 + 16 + 9) * 1e-6)
    assert out["peak_impact_speed"] == 4e-3 and out["mean_impact_speed"] == pytest.approx(2.5e-3)
    assert out["mean_wheel_speed"] == pytest.approx(44.5)
    assert out["rms_normal_force"] == pytest.approx(math.sqrt(25 + A * A / 2), rel=1e-3)
    assert out["contact_fraction"] == pytest.approx(0.5, abs=1e-3)
    # The sinusoid's power A^2/2 lands in the band that contains f0.
    band = next(f"band_{int(lo)}_{int(hi)}_Hz_dB" for lo, hi in BANDS if lo <= f0 < hi)
    assert out[band] == pytest.approx(10 * math.log10(A * A / 2), abs=0.3)


def test_the_library_engine_gives_the_fmus_numbers(flavour_fmus):
    """The model library's compiled loop and the FMUs of either flavour in the fmpy harness
    give the same metrics, bit for bit (only the wall time and the engine's name differ)."""
    case = Case.of({"GearMeshRattle.gear.backlash": 0.12e-3, "Driveline.vehicle.drag": 0.06})
    library = run_case(case, None, 0.4, 1e-4, transient=0.1, window=0.1)
    fmu = run_case(case, flavour_fmus["GearMeshRattle"].parent, 0.4, 1e-4, transient=0.1,
                   window=0.1)
    assert not library["error"] and not fmu["error"], (library["error"], fmu["error"])
    assert (library["engine"], fmu["engine"]) == ("library", "fmu")
    assert library["impacts_per_s_drive"] > 0  # a rattling case
    for key in library:
        if key not in ("wall_seconds", "engine"):
            assert library[key] == fmu[key] or (library[key] != library[key]
                                                and fmu[key] != fmu[key]), key


def test_a_second_client_on_the_same_result_file_is_refused(tmp_path):
    out = tmp_path / "sweep.csv"
    first = ResultWriter(out, ["a.b"])
    try:
        with pytest.raises(ResultFileBusyError, match="being written by another sweep") as err:
            ResultWriter(out, ["a.b"])
        assert str(out) in str(err.value)
    finally:
        first.close()
    assert not (tmp_path / "sweep.csv.lock").exists()
    # a client that dies holding the file leaves its lock file, and no lock: the next takes it
    died = subprocess.run([sys.executable, "-c", CLIENT_THAT_DIES, str(out)], timeout=60)
    assert died.returncode == 9 and (tmp_path / "sweep.csv.lock").exists()
    ResultWriter(out, ["a.b"]).close()
    assert not (tmp_path / "sweep.csv.lock").exists()


#: A client that takes the result file and dies without closing it.
CLIENT_THAT_DIES = """
import os, sys
from drive_rattle_cosim.sweep import ResultWriter
ResultWriter(sys.argv[1], ["a.b"])
os._exit(9)
"""

#: A client that takes the result file on "try <when>" at the wall-clock time <when> (busy
#: waiting, so that two clients start within microseconds) and reports "won", "refused
#: <message>" or "error <message>"; "release" closes the file it holds.
RACING_CLIENT = """
import sys, time
from drive_rattle_cosim.sweep import ResultWriter
writer = None
for line in sys.stdin:
    command, _, when = line.strip().partition(" ")
    if command == "try":
        while time.time() < float(when):
            pass
        try:
            writer = ResultWriter(sys.argv[1], ["a.b"])
            print("won", flush=True)
        except Exception as err:
            refused = "being written by another sweep" in str(err)
            text = " ".join(str(err).split())
            print(("refused " if refused else f"error {type(err).__name__} ") + text, flush=True)
    elif command == "release":
        if writer is not None:
            writer.close()
            writer = None
        print("released", flush=True)
"""


def test_two_clients_starting_together_one_gets_the_file(tmp_path):
    """Two clients start on one result file at the same microsecond, 200 times, on a lock
    file left by a dead client (three trials in four) or on none: each time exactly one
    writes, and the other is refused with a sentence naming the file (no FileNotFoundError).
    (A client that removed a dead client's lock file and tried again let both write in 3 to
    11 of these 200 trials.)"""
    out = tmp_path / "sweep.csv"
    lock = tmp_path / "sweep.csv.lock"
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()  # a process id of a client that is no more
    clients = [subprocess.Popen([sys.executable, "-c", RACING_CLIENT, str(out)],
                                stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
               for _ in range(2)]
    outcomes = []
    try:
        for trial in range(200):
            if trial % 4:
                lock.write_text(f"{gone.pid}\n", encoding="utf-8")
            when = time.time() + 0.01
            for client in clients:
                client.stdin.write(f"try {when!r}\n")
                client.stdin.flush()
            answers = sorted(client.stdout.readline().strip() for client in clients)
            outcomes.append(answers)
            for client in clients:
                client.stdin.write("release\n")
                client.stdin.flush()
                assert client.stdout.readline().strip() == "released"
    finally:
        for client in clients:
            client.stdin.close()
            client.wait(timeout=60)
    for answers in outcomes:
        assert answers[0].startswith("refused ") and answers[1] == "won", outcomes
        assert str(out) in answers[0]
    assert not lock.exists()


def test_a_lock_file_removed_while_it_is_taken_is_opened_again(tmp_path, monkeypatch):
    """A writer that ends between a client's opening the lock file and its locking it
    removes the file: the client then holds a lock on a file that is no more, and must open
    the lock file again (or a third client would get the result file too)."""
    out = tmp_path / "sweep.csv"
    lock = tmp_path / "sweep.csv.lock"
    lock.write_text("1\n", encoding="utf-8")
    real = sweep._try_lock
    calls = []

    def finishing_writer_removes_it(fd):
        calls.append(fd)
        if len(calls) == 1:
            lock.unlink()
        return real(fd)

    monkeypatch.setattr(sweep, "_try_lock", finishing_writer_removes_it)
    writer = ResultWriter(out, ["a.b"])
    try:
        assert len(calls) == 2 and lock.exists()
        monkeypatch.setattr(sweep, "_try_lock", real)
        with pytest.raises(ResultFileBusyError):
            ResultWriter(out, ["a.b"])
    finally:
        writer.close()


def test_sweep_on_two_workers_records_failures_and_resumes(tmp_path):
    bad = Case.of({"GearMeshRattle.gear.backlash": -1.0, "Driveline.vehicle.drag": 0.2})
    cases = [*grid_design(RANGES, 2), bad]
    out = tmp_path / "sweep.csv"
    fmu_dir = None  # the model library's compiled loop
    # Interrupted after two cases...
    first = run_sweep(cases, out, fmu_dir, stop_time=0.01, workers=2, progress=False,
                      stop_after=2)
    assert first["done"] == 2 and len(read_results(out)) == 2
    # ...and resumed: only the remaining three run, every case appears once.
    second = run_sweep(cases, out, fmu_dir, stop_time=0.01, workers=2, progress=False)
    assert second["skipped"] == 2 and second["done"] == 3
    rows = read_results(out)
    assert sorted(r["case_id"] for r in rows) == sorted(c.case_id for c in cases)
    failed = [r for r in rows if r["error"]]
    assert len(failed) == 1 and "gear.backlash" in failed[0]["error"], [
        r["error"] for r in failed]
    for r in rows:
        if not r["error"]:
            assert math.isfinite(r["rattle_index_W"]) and r["mean_wheel_speed"] > 40
    # A third run has nothing to do.
    third = run_sweep(cases, out, fmu_dir, stop_time=0.01, workers=1, progress=False)
    assert third["done"] == 0 and third["skipped"] == 5
