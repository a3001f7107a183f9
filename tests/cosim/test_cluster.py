"""A sweep on a real dask cluster: a scheduler and two workers started with the `dask` command
line, in folders without the project's dist/, reached by the sweep's --scheduler.  One worker is
killed mid-sweep, then the client too; the sweep is resumed and its CSV equals an uninterrupted
run's (the cases run here in-process)."""

import csv
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from drive_rattle_cosim.sweep import FmuBundle, grid_design, run_case
from tests.dask_cluster import scheduler_address, stop

pytest.importorskip("distributed")

RANGES = {"GearMeshRattle.gear.backlash": (0.08e-3, 0.16e-3), "Driveline.vehicle.drag": (0.1, 0.3)}
STOP, STEP = 0.05, 1e-4
DASK = str(Path(sys.executable).with_name("dask"))
#: A one-line log record of dask's own loggers ("2026-11-29 05:55:12,839 - distributed.client -
#: WARNING - ...").
DASK_LOG_RECORD = re.compile(
    r"\d{4}-\d\d-\d\d \d\d:\d\d:\d\d,\d+ - distributed\.[\w.]+ - [A-Z]+ - ")


def rows_of(path: Path) -> dict[str, dict]:
    """Rows by case id, without the wall-clock time (the only field that may differ)."""
    if not path.exists():
        return {}
    with path.open(newline="", encoding="utf-8") as f:
        return {r["case_id"]: {k: v for k, v in r.items() if k != "wall_seconds"}
                for r in csv.DictReader(f)}


def wait_for(condition, timeout: float, what: str) -> None:
    end = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > end:
            raise TimeoutError(f"gave up waiting for {what}")
        time.sleep(0.1)


@pytest.mark.slow
def test_sweep_on_a_cluster_survives_a_killed_worker_and_resumes(fmus, tmp_path):
    fmu_dir = fmus["GearMeshRattle"].parent
    cases = grid_design(RANGES, 3)  # 9 cases
    folders = {name: tmp_path / name for name in ("scheduler", "worker_a", "worker_b", "client")}
    for folder in folders.values():
        folder.mkdir()
    assert not any((f / "dist").exists() for f in folders.values())
    scheduler_file = tmp_path / "scheduler.json"
    processes = []

    def start(args, cwd):
        processes.append(subprocess.Popen(args, cwd=cwd, stdout=subprocess.DEVNULL,
                                          stderr=subprocess.DEVNULL))
        return processes[-1]

    out = folders["client"] / "sweep.csv"
    sweep = [sys.executable, "-m", "drive_rattle_cosim.sweep"]
    for name, (lo, hi) in RANGES.items():
        sweep += ["--param", f"{name}={lo!r}:{hi!r}"]
    sweep += ["--grid", "3", "--stop-time", repr(STOP), "--step", repr(STEP),
              "--engine", "fmu", "--fmu-dir", str(fmu_dir), "--out", str(out)]
    try:
        start([DASK, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
               "--scheduler-file", str(scheduler_file)], folders["scheduler"])
        address = scheduler_address(scheduler_file, 60)
        workers = {
            name: start([DASK, "worker", address, "--no-nanny", "--nthreads", "1",
                         "--no-dashboard", "--host", "127.0.0.1", "--local-directory",
                         str(folders[name])], folders[name])
            for name in ("worker_a", "worker_b")}
        from distributed import Client

        with Client(address, timeout=60) as client:
            client.wait_for_workers(2, timeout=60)
        sweep += ["--scheduler", address]

        first = start(sweep, folders["client"])
        wait_for(lambda: len(rows_of(out)) >= 1, 120, "the first case")
        workers["worker_a"].send_signal(signal.SIGKILL)  # a machine of the cluster dies
        done_at_kill = len(rows_of(out))
        # The sweep goes on on the other worker (dask reschedules the lost case)...
        wait_for(lambda: len(rows_of(out)) > done_at_kill or first.poll() is not None, 120,
                 "progress after the worker died")
        assert first.poll() is None or first.returncode == 0
        if first.poll() is None:  # ...and is interrupted in its turn
            first.send_signal(signal.SIGKILL)
            first.wait()
        interrupted = rows_of(out)
        assert 0 < len(interrupted) <= len(cases)

        resumed = subprocess.run(sweep, cwd=folders["client"], capture_output=True, text=True,
                                 timeout=300)
        assert resumed.returncode == 0, resumed.stderr
        assert f"{len(interrupted)} already done" in resumed.stdout
        # The FMUs reached the surviving worker as bytes, unpacked once into its own local
        # directory (removed with the worker).
        digest = FmuBundle.from_dir(fmu_dir).digest
        unpacked = list(folders["worker_b"].glob(f"**/drive_rattle_fmus_{digest}/*.fmu"))
        assert sorted(p.name for p in unpacked) == ["Driveline.fmu", "GearMeshRattle.fmu"]
    finally:
        stop(processes)

    rows = rows_of(out)
    with out.open(encoding="utf-8") as f:
        assert sum(1 for _ in f) == len(cases) + 1  # every case exactly once
    # Identical to running every case without interruption.
    columns = list(next(iter(rows.values())))
    for case in cases:
        reference = run_case(case, fmu_dir, STOP, STEP)
        assert not reference["error"], reference["error"]
        expected = {c: ("" if reference.get(c) is None else str(reference.get(c)))
                    for c in columns}
        assert rows[case.case_id] == expected, case


@pytest.mark.slow
def test_losing_every_worker_ends_with_the_resume_command(fmus, tmp_path):
    """With the FMUs shipped as data, losing every worker loses them too: the sweep ends with
    one line saying how to resume (not a dask traceback), keeps its finished rows, and the
    same command resumes it on a new worker."""
    fmu_dir = fmus["GearMeshRattle"].parent
    scheduler_file = tmp_path / "scheduler.json"
    out = tmp_path / "sweep.csv"
    processes = []

    def start(args):
        processes.append(subprocess.Popen(args, cwd=tmp_path, stdout=subprocess.DEVNULL,
                                          stderr=subprocess.DEVNULL))
        return processes[-1]

    try:
        start([DASK, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
               "--scheduler-file", str(scheduler_file)])
        address = scheduler_address(scheduler_file, 60)

        def worker():
            return start([DASK, "worker", address, "--no-nanny", "--nthreads", "1",
                          "--no-dashboard", "--host", "127.0.0.1", "--local-directory",
                          str(tmp_path)])

        only = worker()
        from distributed import Client

        with Client(address, timeout=60) as client:
            client.wait_for_workers(1, timeout=60)
        sweep = [sys.executable, "-m", "drive_rattle_cosim.sweep"]
        for name, (lo, hi) in RANGES.items():
            sweep += ["--param", f"{name}={lo!r}:{hi!r}"]
        sweep += ["--grid", "3", "--stop-time", "0.2", "--engine", "fmu", "--fmu-dir",
                  str(fmu_dir), "--out", str(out), "--scheduler", address]
        first = subprocess.Popen(sweep, cwd=tmp_path, stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE, text=True)
        processes.append(first)
        wait_for(lambda: len(rows_of(out)) >= 1, 120, "the first case")
        only.send_signal(signal.SIGKILL)  # every worker dies, and the scattered FMUs with it
        worker()  # a new one joins
        _, err = first.communicate(timeout=180)
        assert first.returncode == 1, err
        # one line of ours; beside it dask's client may log a one-line record of its own
        # ("Couldn't gather 1 keys, rescheduling"), as the timing falls -- never a traceback
        lines = [line for line in err.splitlines()
                 if line.strip() and not DASK_LOG_RECORD.match(line)]
        assert len(lines) == 1 and "lost its workers" in lines[0], err
        assert "drive_rattle_cosim.sweep" in lines[0] and "again" in lines[0], lines[0]
        kept = rows_of(out)
        assert 1 <= len(kept) < 9
        resumed = subprocess.run(sweep, cwd=tmp_path, capture_output=True, text=True,
                                 timeout=300)
        assert resumed.returncode == 0, resumed.stderr
        assert f"{len(kept)} already done" in resumed.stdout
        assert len(rows_of(out)) == 9
    finally:
        stop(processes)
