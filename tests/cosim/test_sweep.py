"""Sweeps on dask: designs, metrics against closed forms, a 2-worker run, failure, resume; one
writer per result file, rows cut short, a full disk, exit statuses and requests refused before
any work."""

import errno
import math
import re
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


@pytest.mark.slow
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


@pytest.fixture(scope="module")
def scheduler():
    """The address of a one-worker dask cluster in this process (threads: starts in a
    second), shared by the sweeps of this module that need no worker processes."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        yield cluster.scheduler_address


SHORT = {"stop_time": 0.005, "progress": False}  # 50 steps: 16 for the spectrum and more


def whole_rows_of(cases, out, scheduler):
    """A result file holding ``cases`` (run now), its bytes."""
    run_sweep(cases, out, scheduler=scheduler, **SHORT)
    return out.read_bytes()


def test_the_fmi3_fmus_give_the_library_engines_rows(fmi3_fmus, tmp_path, scheduler, capsys):
    """The command with ``--engine fmu`` on the FMI 3.0 FMUs runs every case (exit status 0,
    no error) and writes the library engine's rows, bit for bit (only the wall time and the
    engine's name differ)."""
    args = ["--param", "GearMeshRattle.gear.backlash=0.08e-3:0.12e-3",
            "--param", "Driveline.vehicle.drag=0.06:0.08", "--grid", "2", "--stop-time", "0.2",
            "--transient", "0.05", "--window", "0.05", "--scheduler", scheduler]
    rows = {}
    for engine, where in (("fmu", ["--fmu-dir", str(fmi3_fmus["GearMeshRattle"].parent)]),
                          ("library", [])):
        out = tmp_path / f"{engine}.csv"
        assert sweep.main([*args, "--engine", engine, *where, "--out", str(out)]) == 0, \
            capsys.readouterr().err
        rows[engine] = {r["case_id"]: r for r in read_results(out)}
    assert len(rows["fmu"]) == 4 and rows["fmu"].keys() == rows["library"].keys()
    for case_id, fmu in rows["fmu"].items():
        library = rows["library"][case_id]
        assert fmu["error"] == "" and fmu["engine"] == "fmu", fmu["error"]
        assert library["impacts_per_s_drive"] > 0  # a rattling case
        for key, value in library.items():
            if key not in ("wall_seconds", "engine"):
                assert value == fmu[key] or (value != value and fmu[key] != fmu[key]), key


def test_a_row_cut_short_is_dropped_and_its_case_runs_again(tmp_path, scheduler):
    cases = grid_design(RANGES, 2)
    out = tmp_path / "sweep.csv"
    data = whole_rows_of(cases[:3], out, scheduler)
    lines = data.splitlines(keepends=True)
    assert len(lines) == 4 and all(line.endswith(b"\r\n") for line in lines)
    # a clean file is left as it is by opening it
    ResultWriter(out, sorted(RANGES)).close()
    assert out.read_bytes() == data
    # the last row cut short (no newline), as a full disk or a killed client leaves it
    out.write_bytes(data[:-len(lines[-1]) // 2])
    assert len(read_results(out)) == 2  # the whole rows, read while the file is torn
    counts = run_sweep(cases, out, scheduler=scheduler, **SHORT)
    assert (counts["skipped"], counts["done"]) == (2, 2)
    rows = read_results(out)
    assert sorted(r["case_id"] for r in rows) == sorted(c.case_id for c in cases)
    assert all(not r["error"] and math.isfinite(r["rattle_index_W"]) for r in rows)
    assert out.read_bytes().count(b"\n") == 5  # the header and each case once


def test_a_last_row_of_another_length_is_dropped(tmp_path, scheduler):
    """A last line with its newline but not the header's field count (two rows run into
    one) is no whole row either."""
    cases = grid_design(RANGES, 2)[:2]
    out = tmp_path / "sweep.csv"
    data = whole_rows_of(cases, out, scheduler)
    head, last = data.rsplit(b"\r\n", 2)[0] + b"\r\n", data.splitlines(keepends=True)[-1]
    out.write_bytes(head + last[:-2] + b"," + last)  # 2 x the fields, then the newline
    ResultWriter(out, sorted(RANGES)).close()
    assert out.read_bytes() == head
    assert [r["case_id"] for r in read_results(out)] == [cases[0].case_id]


class FullDisk:
    """The writer's file on a disk that fills up: ``room`` more bytes are written, then every
    write fails with ENOSPC after writing what fits."""

    def __init__(self, file, room: int):
        self.file, self.room = file, room

    def write(self, data):
        if len(data) > self.room:
            written = self.file.write(bytes(data[:self.room]))
            self.room = 0
            if written:
                return written
            raise OSError(errno.ENOSPC, "No space left on device")
        self.room -= len(data)
        return self.file.write(data)

    def __getattr__(self, name):
        return getattr(self.file, name)


def test_a_full_disk_ends_the_sweep_with_the_resume_command(tmp_path, scheduler,
                                                            monkeypatch):
    cases = grid_design(RANGES, 2)
    out = tmp_path / "sweep.csv"
    whole_rows_of(cases[:1], out, scheduler)
    row = len(out.read_bytes().splitlines(keepends=True)[-1])
    opened = ResultWriter._open

    def on_a_full_disk(self):  # room for one more row and half of the next
        opened(self)
        self._file = FullDisk(self._file, row + row // 2)

    monkeypatch.setattr(ResultWriter, "_open", on_a_full_disk)
    with pytest.raises(SweepInterruptedError) as err:
        run_sweep(cases, out, scheduler=scheduler, resume_hint="run `sweep --out x` again",
                  **SHORT)
    message = str(err.value)
    assert "\n" not in message and str(out) in message and "No space left" in message
    assert "run `sweep --out x` again" in message, message
    assert not (tmp_path / "sweep.csv.lock").exists()  # the lock is let go
    assert out.read_bytes().endswith(b"\r\n") and len(read_results(out)) == 2
    monkeypatch.setattr(ResultWriter, "_open", opened)  # room again: the resume runs the rest
    counts = run_sweep(cases, out, scheduler=scheduler, **SHORT)
    assert (counts["skipped"], counts["done"]) == (2, 2)
    assert sorted(r["case_id"] for r in read_results(out)) == sorted(c.case_id for c in cases)


def sweep_cli(capsys, *args):
    """``python -m drive_rattle_cosim.sweep`` in this process: (exit status, stdout,
    stderr)."""
    try:
        status = sweep.main(list(args))
    except SystemExit as end:
        status = end.code
    captured = capsys.readouterr()
    return status, captured.out, captured.err


def test_a_sweep_with_failed_cases_exits_non_zero_with_their_count(tmp_path, scheduler,
                                                                  capsys):
    """A communication step above the mesh's solver.h_comm_max is refused by the unit: of the
    two cases, the one with the smaller limit fails, at every run of the sweep."""
    out = tmp_path / "sweep.csv"
    args = ("--param", "GearMeshRattle.solver.h_comm_max=5e-5:2e-4", "--grid", "2",
            "--stop-time", "0.005", "--scheduler", scheduler, "--out", str(out))
    status, stdout, stderr = sweep_cli(capsys, *args)
    assert status == sweep.EXIT_CASES_FAILED, stderr
    assert "2 cases run (1 failed)" in stdout and "1 of 2 cases failed" in stderr
    status, stdout, stderr = sweep_cli(capsys, *args)  # resumed: nothing new, still failed
    assert status == sweep.EXIT_CASES_FAILED and "1 of them failed" in stdout
    assert "1 of 2 cases failed" in stderr
    status, stdout, stderr = sweep_cli(capsys, "--param",
                                       "GearMeshRattle.solver.h_comm_max=2e-4:3e-4",
                                       *args[2:-1], str(tmp_path / "good.csv"))
    assert status == sweep.EXIT_OK and stderr == "" and "(0 failed)" in stdout


def test_a_retried_case_keeps_one_row(tmp_path, scheduler, capsys):
    """``--retry-failed`` runs a failed case again and its new row replaces the failed one:
    every case once in the file (its failed row and the retry's were both kept)."""
    out = tmp_path / "sweep.csv"
    args = ["--param", "GearMeshRattle.solver.h_comm_max=5e-5:2e-4", "--grid", "2",
            "--stop-time", "0.005", "--scheduler", scheduler, "--out", str(out)]
    assert sweep_cli(capsys, *args)[0] == sweep.EXIT_CASES_FAILED
    before = read_results(out)
    status, stdout, _ = sweep_cli(capsys, *args, "--retry-failed")
    assert status == sweep.EXIT_CASES_FAILED and "1 cases run (1 failed)" in stdout
    after = read_results(out)
    assert sorted(r["case_id"] for r in after) == sorted(r["case_id"] for r in before)
    assert len({r["case_id"] for r in after}) == len(after) == 2
    ran = [repr(r) for r in before if not r["error"]]  # repr: nan equals nan
    assert [repr(r) for r in after if not r["error"]] == ran


P, D, K = "GearMeshRattle.gear.backlash", "Driveline.vehicle.drag", "Driveline.shaft.k"
RANGE = f"{P}=1e-4:2e-4"
#: Requests refused before any work: the arguments and a text the one-line message holds.
BAD_REQUESTS = [
    (["--param", RANGE, "--grid", "2", "--workers", "0"], "workers = 0; allowed"),
    (["--param", RANGE, "--grid", "2", "--workers", "-1"], "workers = -1; allowed"),
    (["--param", RANGE, "--grid", "0"], "= 0; allowed: a whole number >= 2"),
    (["--param", RANGE, "--grid", "1"], "= 1; allowed: a whole number >= 2"),
    (["--param", RANGE, "--grid", "-3"], "= -3; allowed: a whole number >= 2"),
    (["--param", RANGE, "--grid", "2.5"], "'2.5' is not a whole number; allowed"),
    (["--param", RANGE, "--lhs", "0"], "= 0; allowed: a whole number >= 1"),
    (["--param", RANGE, "--lhs", "1e8"], f"100000000 cases; allowed: at most {MAX_CASES}"),
    (["--param", RANGE, "--param", f"{D}=0.1:0.2", "--param", f"{K}=0.1:0.3", "--grid",
      "2000"], f"8000000000 cases; allowed: at most {MAX_CASES}"),
    (["--param", f"{P}=1e-4:1e-4", "--grid", "3"], "range of one point"),
    (["--param", f"{P}=2e-4:1e-4", "--grid", "3"], "down to 0.0001; allowed: LO < HI"),
    (["--param", f"{P}=-1:1e-4", "--grid", "3"], "= -1 is out of range; allowed: [0, 0.005]"),
    (["--param", f"{P}=0x10:1", "--grid", "3"], "'0x10' is not a number; allowed"),
    (["--param", f"{P}", "--grid", "3"], "is not NAME=LO:HI or NAME=VALUE"),
    (["--param", "GearMeshRattle.gear.backlas=1e-4:2e-4", "--grid", "2"],
     f"did you mean {P}"),
    (["--param", "gear.backlash=1e-4:2e-4", "--grid", "2"], f"did you mean {P}"),
    (["--param", RANGE, "--param", f"{P}=1e-4:3e-4", "--grid", "2"], "given twice"),
    (["--param", "GearMeshRattle.friction.enabled=0:1", "--grid", "2"],
     "is a Boolean; allowed: Real and Integer"),
    (["--param", "GearMeshRattle.gear.z_pinion=18:22", "--grid", "4"],
     "falls between whole numbers"),
    (["--param", "GearMeshRattle.gear.z_pinion=18:22", "--lhs", "4"], "Integer parameter"),
    (["--param", RANGE, "--grid", "2", "--stop-time", "nan"], "stop time nan s; allowed"),
    (["--param", RANGE, "--grid", "2", "--stop-time", "0"], "stop time 0.0 s; allowed"),
    (["--param", RANGE, "--grid", "2", "--stop-time", "-1"], "stop time -1.0 s; allowed"),
    (["--param", RANGE, "--grid", "2", "--stop-time", "0.01005"], "a whole number of steps"),
    (["--param", RANGE, "--grid", "2", "--step", "0"], "step 0.0 s must be a positive"),
    (["--param", RANGE, "--grid", "2", "--step", "nan"], "step nan s must be a positive"),
    (["--param", RANGE, "--grid", "2", "--step=-1e-4"], "step -0.0001 s must be"),
    (["--param", RANGE, "--grid", "2", "--step", "1e-10"], "whole number of nanoseconds"),
    (["--param", RANGE, "--grid", "2", "--stop-time", "1e6"], "steps; allowed: at most"),
    (["--param", RANGE, "--grid", "2", "--window", "0"], "window = 0.0 s; allowed: > 0"),
    (["--param", RANGE, "--grid", "2", "--window", "nan"], "window = nan s; allowed: > 0"),
    (["--param", RANGE, "--grid", "2", "--window", "0.5"], "does not fit"),
    (["--param", RANGE, "--grid", "2", "--window", "0.001"], "allowed: 16 steps"),
    (["--param", RANGE, "--grid", "2", "--transient", "0.3"], "transient = 0.3 s; allowed"),
    (["--param", RANGE, "--grid", "2", "--transient", "0.5"], "transient = 0.5 s; allowed"),
    (["--param", RANGE, "--grid", "2", "--transient", "-1"], "transient = -1.0 s; allowed"),
    (["--param", RANGE, "--grid", "2", "--transient", "inf"], "transient = inf s; allowed"),
    (["--param", RANGE, "--grid", "2", "--transient", "0.2995"], "allowed: 16 steps"),
    (["--param", RANGE, "--grid", "2", "--transient", "0.1", "--window", "0.25"],
     "does not fit"),
]


@pytest.mark.parametrize("args, message", BAD_REQUESTS, ids=[
    " ".join(a).replace("GearMeshRattle.", "").replace("Driveline.", "").replace("--param ", "")
    for a, _ in BAD_REQUESTS])
def test_a_bad_request_is_refused_before_any_work(tmp_path, capsys, monkeypatch, args,
                                                  message):
    import dask.distributed

    def no_cluster(*args, **kwargs):
        raise AssertionError("a cluster was started for a request to refuse")

    monkeypatch.setattr(dask.distributed, "LocalCluster", no_cluster)
    monkeypatch.setattr(dask.distributed, "Client", no_cluster)
    out = tmp_path / "sweep.csv"
    status, stdout, stderr = sweep_cli(capsys, *args, "--out", str(out))
    assert status == 2 and stdout == "", stderr
    lines = stderr.splitlines()
    assert len(lines) == 1 and message in lines[0], stderr
    assert not out.exists() and not (tmp_path / "sweep.csv.lock").exists()


def test_run_sweep_refuses_what_it_cannot_do(tmp_path):
    """The library function checks what Python callers give it, with the same sentences."""
    out = tmp_path / "sweep.csv"
    cases = grid_design(RANGES, 2)
    for kwargs, message in [
        ({"cases": [*cases, cases[0]]}, "repeat case"),
        ({"cases": []}, "no cases"),
        ({"cases": [Case.of({"GearMeshRattle.gear.backlas": 1e-4})]}, "did you mean"),
        ({"workers": 0}, "workers = 0"),
        ({"workers": 1.5}, "workers = 1.5"),
        ({"step": 0.0}, "must be a positive whole number"),
        ({"transient": 0.5}, "transient = 0.5 s"),
        ({"window": 0.001}, "allowed: 16 steps"),
    ]:
        with pytest.raises(ValueError, match=message):
            run_sweep(**{"cases": cases, "out": out, "progress": False, **kwargs})
        assert not out.exists()
    with pytest.raises(ValueError, match="every parameter held fixed"):
        latin_hypercube_design({P: (1e-4, 1e-4)}, 3)


def test_the_documented_limits_are_the_codes():
    from pathlib import Path

    from drive_rattle_cosim.spectral_lines import MIN_SAMPLES

    doc = (Path(__file__).resolve().parents[2] / "docs" / "cosim.md").read_text(
        encoding="utf-8")
    assert f"**{MAX_CASES:,} cases** (`MAX_CASES`)" in doc
    assert f"at most {sweep.MAX_POINTS:,} points (`MAX_POINTS`" in doc
    assert f"at least {MIN_SAMPLES} steps (`spectral_lines.MIN_SAMPLES`" in doc
    statuses = re.findall(r"\*\*(\d)\*\* (?:every case|the sweep could|the request|the sweep "
                          r"ran)", doc)
    assert statuses == [str(s) for s in (sweep.EXIT_OK, sweep.EXIT_STOPPED,
                                         sweep.EXIT_BAD_REQUEST, sweep.EXIT_CASES_FAILED)]


def test_an_out_that_is_no_result_file_is_refused_and_left_as_it_was(tmp_path, capsys):
    """Even a file with no whole line, which a result file cut short in its header would
    be, is left alone unless it is the start of this sweep's header."""
    notes = tmp_path / "notes.txt"
    notes.write_bytes(b"hello, world: no newline at all \xff")
    for out, message in [(notes, f"{notes} is not a result file of this sweep"),
                         (tmp_path, f"cannot write the result file {tmp_path} (Is a directory"),
                         (notes / "sweep.csv", f"(File exists: {notes}); allowed")]:
        status, stdout, stderr = sweep_cli(capsys, "--param", RANGE, "--grid", "2",
                                           "--out", str(out))
        assert status == 2 and stdout == "" and len(stderr.splitlines()) == 1, stderr
        assert message in stderr, stderr
    assert notes.read_bytes() == b"hello, world: no newline at all \xff"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.txt"]  # no lock left
