"""Soak: the tests that draw at random (``-m seeded``: the boundary fuzzers and the property
tests), run again and again on fresh seeds until the time is up.

    .venv/bin/python tests/soak.py --minutes 10 [--layer "not sanitize"] [-k EXPR]

The README's test command runs these tests on fixed seeds (tests/seeds.py, the hypothesis
profile ``ci``), so that one commit gives one answer; the soak looks for what those seeds do
not reach.  Each round draws one seed for all of them (``RATTLE_FUZZ_SEED`` for the fuzzers,
``--hypothesis-seed`` under the profile ``soak`` for the property tests) and every failing
test is printed with the command that replays it.  Exit status 1 when any round failed.
"""

from __future__ import annotations

import argparse
import os
import random
import shlex
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def failures(report: Path) -> list[str]:
    """The node ids of the failed or erroring tests of a JUnit XML report."""
    if not report.is_file():
        return []
    out = []
    for case in ET.parse(report).getroot().iter("testcase"):
        if case.find("failure") is not None or case.find("error") is not None:
            path = case.get("file") or case.get("classname", "").replace(".", "/") + ".py"
            out.append(f"{path}::{case.get('name')}")
    return out


def replay_command(test: str, seed: int) -> str:
    return (f"RATTLE_FUZZ_SEED={seed} HYPOTHESIS_PROFILE=soak {shlex.quote(sys.executable)} "
            f"-m pytest -p no:cacheprovider --hypothesis-seed={seed} {shlex.quote(test)}")


def soak_round(seed: int, marker: str, keyword: str | None, folder: Path) -> tuple[int, list]:
    """One run of the seeded tests on ``seed``: (pytest's exit code, the failed tests)."""
    report = folder / f"round-{seed}.xml"
    env = {**os.environ, "RATTLE_FUZZ_SEED": str(seed), "HYPOTHESIS_PROFILE": "soak"}
    cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-m", marker,
           f"--hypothesis-seed={seed}", f"--junitxml={report}"]
    if keyword:
        cmd += ["-k", keyword]
    done = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True)
    return done.returncode, failures(report)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="tests/soak.py", description=__doc__.split("\n\n")[0])
    ap.add_argument("--minutes", type=float, default=10.0,
                    help="how long to go on starting rounds (a round runs to its end)")
    ap.add_argument("--layer", default="",
                    help='a marker expression added to "seeded", e.g. "not sanitize"')
    ap.add_argument("-k", dest="keyword", default=None, help="pytest's -k, to narrow the tests")
    args = ap.parse_args(argv)
    if not args.minutes > 0:
        ap.error(f"--minutes = {args.minutes}: allowed: a positive number")
    marker = f"seeded and ({args.layer})" if args.layer else "seeded"
    deadline = time.monotonic() + 60.0 * args.minutes
    rounds, failed = 0, []
    with tempfile.TemporaryDirectory(prefix="rattle_soak_") as scratch:
        while time.monotonic() < deadline:
            seed = random.SystemRandom().randrange(2**32)
            start = time.monotonic()
            code, tests = soak_round(seed, marker, args.keyword, Path(scratch))
            rounds += 1
            print(f"round {rounds}: seed {seed}, {'passed' if code == 0 else 'FAILED'} "
                  f"({time.monotonic() - start:.0f} s)", flush=True)
            if code not in (0, 5) and not tests:  # 5: nothing collected
                tests = [f"(pytest itself failed: exit code {code})"]
            for test in tests:
                failed.append((seed, test))
                print(f"  FAILED {test}\n  replay: {replay_command(test, seed)}", flush=True)
    print(f"soak: {rounds} rounds, {len(failed)} failures")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
