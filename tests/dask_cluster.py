"""The address of a dask scheduler started with ``--scheduler-file``, for the tests that start
a cluster of their own processes (tests/cosim/test_cluster.py, tests/test_wheel.py)."""

from __future__ import annotations

import json
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
