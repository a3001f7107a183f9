"""Virtual environments of their own for the masters that pin an old fmpy.

gemseo-fmu requires ``fmpy<=0.3.19`` and cofmupy ``fmpy==0.3.20``: installed beside this
project they would hold its fmpy (and numpy, scipy) years back.  Each runs instead in a
virtual environment that holds only the master and what it requires (``PINNED``), created on
first use and cached, with this project's packages on its ``PYTHONPATH`` (``master_env``): the
master's own process imports ``drive_rattle_cosim.masters`` from here and the master from its
environment.

    python -m drive_rattle_cosim.environments gemseo     # prints the environment's python

The tests run gemseo-fmu and cofmupy so (tests/cosim/test_masters.py); the cache folder is
``$RATTLE_MASTER_VENVS``, else ``drive-rattle/masters`` in the user's cache folder
(``$XDG_CACHE_HOME``, default ``~/.cache``): outside any checkout, so that no tool that walks
the sources (ruff, the structure tests) walks an environment.
"""

from __future__ import annotations

import fcntl
import hashlib
import os
import shutil
import subprocess
import sys
import venv
from pathlib import Path

#: The masters that need an environment of their own -> what it installs (exact versions:
#: the numbers they are held to are those of these releases).
PINNED = {
    "gemseo": ("gemseo-fmu==3.1.1", "fmpy==0.3.19"),
    "cofmupy": ("cofmupy==1.0.0", "fmpy==0.3.20"),
}
#: Longest each step of an environment's installation may take [s] (uv's or pip's, from the
#: package index).
INSTALL_TIMEOUT = 1200.0


def cache_folder() -> Path:
    if "RATTLE_MASTER_VENVS" in os.environ:
        return Path(os.environ["RATTLE_MASTER_VENVS"]).resolve()
    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return (cache / "drive-rattle" / "masters").resolve()


def _bin(folder: Path, name: str) -> Path:
    return folder / ("Scripts" if sys.platform == "win32" else "bin") / name


def _uv() -> str | None:
    """uv's program: the one installed beside this interpreter (the test extra's ``uv``
    package puts it there), else one on PATH, else None."""
    beside = Path(sys.executable).with_name("uv.exe" if sys.platform == "win32" else "uv")
    return str(beside) if beside.is_file() else shutil.which("uv")


def master_python(name: str, cache: Path | None = None) -> Path:
    """The python of ``name``'s environment (of ``PINNED``), created on first use (one
    process at a time: a lock file beside it) and reused while its requirements and this
    Python's version are the same.  uv creates and fills it where it is installed
    (:func:`_uv`), pip otherwise: the same releases (both resolve ``PINNED`` to the newest
    that fit), in a quarter of the CPU time or less -- uv leaves the bytecode to each
    module's first import, where pip compiles every module it installs (gemseo-fmu's
    environment, with pip's download cache filled: 64 CPU-s with pip, 17 with uv, 7.6 once
    uv's cache holds the wheels).  RuntimeError with the installer's output when it cannot
    be made."""
    if name not in PINNED:
        raise ValueError(f"master {name!r} has no environment of its own; allowed: "
                         f"{', '.join(PINNED)}")
    cache = Path(cache) if cache is not None else cache_folder()
    key = hashlib.sha256("\n".join((sys.version, *PINNED[name])).encode()).hexdigest()[:12]
    folder = cache / f"{name}-{key}"
    python = _bin(folder, "python")
    ready = folder / "ready"
    cache.mkdir(parents=True, exist_ok=True)
    with open(cache / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file is closed
        if ready.is_file():
            return python
        shutil.rmtree(folder, ignore_errors=True)
        uv = _uv()
        if uv is not None:
            steps = [[uv, "venv", "-q", "--python", sys.executable, str(folder)],
                     [uv, "pip", "install", "-q", "--python", str(python), *PINNED[name]]]
        else:
            venv.create(folder, with_pip=True, clear=True)
            steps = [[str(python), "-m", "pip", "install", "-q", "--disable-pip-version-check",
                      *PINNED[name]]]
        for step in steps:
            done = subprocess.run(step, capture_output=True, text=True, timeout=INSTALL_TIMEOUT)
            if done.returncode != 0:
                raise RuntimeError(f"the environment of {name} ({' '.join(PINNED[name])}) "
                                   f"could not be made in {folder}: {' '.join(step[:3])} "
                                   f"failed:\n{done.stdout}{done.stderr}")
        ready.write_text("\n".join(PINNED[name]) + "\n", encoding="utf-8")
    return python


def master_env(base: dict | None = None) -> dict:
    """The environment variables of a master's process: ``base`` (default: this process's)
    with this project's packages first on ``PYTHONPATH``."""
    env = dict(os.environ if base is None else base)
    packages = str(Path(__file__).resolve().parents[1])
    env["PYTHONPATH"] = os.pathsep.join([packages, *filter(None, [env.get("PYTHONPATH")])])
    return env


def main(argv=None) -> int:
    import argparse

    ap = argparse.ArgumentParser(prog="python -m drive_rattle_cosim.environments",
                                 description="Create (once) the environment of a master that "
                                             "pins an old fmpy and print its python.")
    ap.add_argument("master", choices=sorted(PINNED))
    args = ap.parse_args(argv)
    try:
        print(master_python(args.master))
    except RuntimeError as err:
        print(f"drive_rattle_cosim.environments: {err}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
