"""The wall time of every call into an FMU's binary, and the slowest against the bound of
docs/fmi.md ("How long a call can take"): no call runs longer than 50 ms per 1e-4 s of its
step (a shorter step, and a call that is no step, count as 1e-4 s).

``CallClock().wrap(lib)`` is a stand-in for a ctypes library whose functions are timed; the
fuzzers and the FMI 3.0 drivers hand it to their hosts in place of the library itself."""

from __future__ import annotations

import time

#: The bound: seconds per span of a step, and the span.
BOUND_SECONDS = 0.05
BOUND_SPAN = 1e-4
#: The functions whose third argument is the communication step size.
STEPS = ("fmi2DoStep", "fmi3DoStep")
#: Creating and freeing an instance are the face's own, not the unit's work (the pythonfmu
#: face starts its Python interpreter in its first fmi2Instantiate): timed apart.
INSTANCE_CALLS = ("fmi2Instantiate", "fmi2FreeInstance", "fmi3InstantiateCoSimulation",
                  "fmi3InstantiateModelExchange", "fmi3FreeInstance")


def bound(name: str, args: tuple) -> float:
    """The bound [s] of a call of ``name`` with ``args``."""
    h = args[2] if name in STEPS and len(args) > 2 else BOUND_SPAN
    try:
        spans = max(1.0, float(h) / BOUND_SPAN)
    except (TypeError, ValueError):
        spans = 1.0
    return BOUND_SECONDS * (spans if spans == spans and spans != float("inf") else 1.0)


class CallClock:
    """The slowest call seen, in seconds and as a fraction of its bound (the instance calls
    apart)."""

    def __init__(self):
        self.calls = 0
        self.slowest = (0.0, "", 0.0)  # (seconds, function, its bound)
        self.worst = (0.0, "", 0.0, 0.0)  # (seconds / bound, function, seconds, bound)
        self.instance = (0.0, "")  # the slowest of INSTANCE_CALLS

    def wrap(self, lib):
        return _Timed(lib, self)

    def record(self, name: str, args: tuple, seconds: float) -> None:
        self.calls += 1
        if name in INSTANCE_CALLS:
            self.instance = max(self.instance, (seconds, name))
            return
        limit = bound(name, args)
        if seconds > self.slowest[0]:
            self.slowest = (seconds, name, limit)
        if seconds / limit > self.worst[0]:
            self.worst = (seconds / limit, name, seconds, limit)

    def summary(self) -> dict:
        return {"calls timed": self.calls,
                "slowest call": {"seconds": self.slowest[0], "function": self.slowest[1],
                                 "bound": self.slowest[2]},
                "nearest the bound": {"fraction": self.worst[0], "function": self.worst[1],
                                      "seconds": self.worst[2], "bound": self.worst[3]},
                "slowest instance call": {"seconds": self.instance[0],
                                          "function": self.instance[1]}}


class _Timed:
    def __init__(self, lib, clock: CallClock):
        self._lib, self._clock = lib, clock

    def __getattr__(self, name):
        fn = getattr(self._lib, name)
        if not name.startswith("fmi"):
            return fn
        clock = self._clock

        def timed(*args):
            t0 = time.perf_counter()
            try:
                return fn(*args)
            finally:
                clock.record(name, args, time.perf_counter() - t0)
        return timed


#: The factor by which a call may exceed its bound (docs/fmi.md, "How long a call can take")
#: on a loaded machine: the bound is met on an idle one with room (a budget's step is some
#: 14 ms of CPU); 2 cores shared by several test runs stretch its wall time about 2.5 times.
LOADED = 4.0


def slowest_line(label: str, summary: dict) -> str:
    """The summary's slowest call and the call nearest its bound, in one line (printed by the
    tests for the closing notes)."""
    slowest, nearest = summary["slowest call"], summary["nearest the bound"]
    return (f"slowest call {label}: {slowest['seconds'] * 1e3:.1f} ms ({slowest['function']}, "
            f"bound {slowest['bound'] * 1e3:.0f} ms); nearest its bound: "
            f"{nearest['fraction']:.2f} of it ({nearest['function']}, "
            f"{nearest['seconds'] * 1e3:.1f} ms), {summary['calls timed']} calls")
