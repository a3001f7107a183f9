"""A master run in a process of its own (run_master.py): libcosim and fmpy in one process can
abort at exit, and a master's crash must not take the test session with it.  The masters that
pin an old fmpy (gemseo-fmu, cofmupy) run in environments of their own
(``drive_rattle_cosim.environments``), created on first use and cached."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from drive_rattle_cosim.environments import PINNED, master_env, master_python

RUNNER = Path(__file__).with_name("run_master.py")


def start_master(kind: str, **args) -> subprocess.Popen:
    """The master ``kind`` (of run_master.py) started on ``args``."""
    own = next((name for name in PINNED if kind.startswith(name)), None)
    python, env = (master_python(own), master_env()) if own else (sys.executable, None)
    return subprocess.Popen([str(python), str(RUNNER), kind, json.dumps(args)], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


def finish(process: subprocess.Popen) -> tuple[dict, str]:
    """(result, everything the master printed)."""
    out, _ = process.communicate(timeout=600)
    assert process.returncode == 0, out
    return json.loads(out.strip().splitlines()[-1]), out


def run_master(kind: str, **args) -> tuple[dict, str]:
    return finish(start_master(kind, **args))
