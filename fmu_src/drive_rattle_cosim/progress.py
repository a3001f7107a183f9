"""What a long command is doing while it works: a line when each phase starts and one when it
ends, with its time and the time since the command started, and the total at the end.

    phases = Phases("paper scenario")
    with phases.phase("building the FMUs"):
        ...
    phases.done()

prints (to stderr, so that the command's results on stdout stay clean)::

    paper scenario [   0.0 s] building the FMUs ...
    paper scenario [  41.3 s] building the FMUs: 41.3 s
    paper scenario [  63.0 s] done in 63.0 s

A progress bar inside a phase (tqdm, shown only where stderr is a terminal) is the phase's
own: the harness's co-simulation has one (``CoSimulation.run(progress=True)``).
"""

from __future__ import annotations

import contextlib
import sys
import time
from collections.abc import Iterator
from typing import TextIO


class Phases:
    """The phases of one command, timed from its construction."""

    def __init__(self, command: str, stream: TextIO | None = None, enabled: bool = True):
        self.command = command
        self.stream = stream
        self.enabled = enabled
        self.started = time.perf_counter()
        #: (phase, seconds) of every finished phase, in order.
        self.times: list[tuple[str, float]] = []

    def _say(self, text: str) -> None:
        if self.enabled:
            elapsed = time.perf_counter() - self.started
            print(f"{self.command} [{elapsed:6.1f} s] {text}", file=self.stream or sys.stderr,
                  flush=True)

    @contextlib.contextmanager
    def phase(self, what: str) -> Iterator[None]:
        """Announce ``what``, run the block, and report its time (also when it raises)."""
        self._say(f"{what} ...")
        start = time.perf_counter()
        try:
            yield
        finally:
            seconds = time.perf_counter() - start
            self.times.append((what, seconds))
            self._say(f"{what}: {seconds:.1f} s")

    def done(self) -> float:
        """Report and return the total time [s]."""
        total = time.perf_counter() - self.started
        self._say(f"done in {total:.1f} s")
        return total
