"""A cluster of dask processes that a test starts itself (tests/cosim/test_cluster.py,
tests/test_wheel.py): the scheduler's address from its ``--scheduler-file``, and the processes
stopped at the end."""

from __future__ import annotations

import json
import signal
import subprocess
import time
from pathlib import Path


def scheduler_address(scheduler_file: Path, timeout: float) -> str:
    """The scheduler's address from ``scheduler_file`` once the scheduler has written it, or
    TimeoutError after ``timeout`` [s].  The file exists before it holds anything (dask creates
    it, then writes the JSON), so a reader that waits for the file alone can read it empty."""
    end = time.monotonic() + timeout
    while True:
        try:
            return json.loads(Path(scheduler_file).read_text(encoding="utf-8"))["address"]
        except (OSError, ValueError, KeyError):
            if time.monotonic() > end:
                raise TimeoutError(f"the scheduler wrote no address to {scheduler_file} "
                                   f"within {timeout:g} s") from None
            time.sleep(0.1)


def stop(processes: list[subprocess.Popen], timeout: float = 20.0) -> None:
    """Stop ``processes`` (in the order they were started: the scheduler first) in the
    reverse order, each with SIGTERM, killed when it has not ended after ``timeout`` [s].  A
    worker told to stop once its scheduler has gone waits for it to come back, so the
    scheduler is the last: told all at once, one of four clusters of tests/cosim/test_cluster.py
    had a worker killed after the 20 s (20.1 s to stop, against 0.3 s); one by one in reverse,
    six of six stopped in 0.4-0.5 s."""
    for process in reversed(processes):
        if process.poll() is None:
            process.send_signal(signal.SIGTERM)
            try:
                process.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
