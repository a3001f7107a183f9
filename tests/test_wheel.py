"""What users install is what is tested: the sdist and the wheel built from this checkout, the
wheel installed (not editable) in a fresh virtual environment, and used from an empty folder
with no clone in sight -- the build of every FMU and SSP, the README's Python example, and a
sweep on a dask cluster whose scheduler and two workers run from that environment (the cluster
recipe of docs/cosim.md: workers that have the package installed and nothing else).

The wheel is built from the sdist (``uv build``), so a file the sdist lacks fails here too.
Installing the environment's dependencies needs the package index (uv's cache serves them
after the first run).
"""

from __future__ import annotations

import csv
import os
import re
import subprocess
import sys
import tarfile
import zipfile
from pathlib import Path

import pytest

from tests.dask_cluster import scheduler_address

ROOT = Path(__file__).resolve().parents[1]
#: Every file the build needs, as the checkout holds it (relative to ROOT): the model's C
#: sources and headers, both faces', the slave modules, the templates, the references.
NEEDED = sorted(
    str(p.relative_to(ROOT)) for pattern in (
        "fmu_src/rattle_model/*.[ch]", "fmu_src/fmi_common/*.[ch]", "fmu_src/fmi2/*.[ch]",
        "fmu_src/fmi3/*.[ch]",
        "fmu_src/slaves/*.py", "modelDescription_templates/**/*.xml", "regression/*/*")
    for p in ROOT.glob(pattern))
#: Where each checkout folder lands in the wheel (pyproject.toml's [tool.setuptools.package-dir]).
IN_WHEEL = {"fmu_src/rattle_model": "drive_rattle_build/sources/rattle_model",
            "fmu_src/fmi_common": "drive_rattle_build/sources/fmi_common",
            "fmu_src/fmi2": "drive_rattle_build/sources/fmi2",
            "fmu_src/fmi3": "drive_rattle_build/sources/fmi3",
            "fmu_src/slaves": "drive_rattle_build/sources/slaves",
            "modelDescription_templates": "drive_rattle_build/templates",
            "regression": "drive_rattle_cosim/references"}


def _run(args, cwd: Path, env: dict | None = None, timeout: float = 900):
    done = subprocess.run([str(a) for a in args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=timeout)
    assert done.returncode == 0, f"{args}\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
    return done


def _in_wheel(name: str) -> str:
    for folder, target in IN_WHEEL.items():
        if name.startswith(folder + "/"):
            return target + name[len(folder):]
    raise AssertionError(name)


def _uv() -> str:
    """uv, installed beside this interpreter by the test extra (pyproject.toml)."""
    return str(Path(sys.executable).with_name("uv"))


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """(the wheel, the fresh environment's bin folder, an empty folder to work in).

    uv builds the sdist and the wheel from it, each in an isolated environment holding only
    what pyproject.toml's [build-system] requires, as pip does for a user; it creates the
    environment and installs the wheel with its dependencies as ``pip install`` would, in a
    few seconds instead of about a minute.  The bytecode is left to each module's first
    import, as a user's Python writes it: compiled at install (pip's way, or uv's
    ``--compile-bytecode``) it covers every module of numpy, scipy and dask, most of which
    the test never imports (the test's CPU: 71 s with it, 56-63 s without)."""
    tmp = tmp_path_factory.mktemp("wheel")
    _run([_uv(), "build", "-q", "--out-dir", tmp, ROOT], tmp)
    sdist = next(tmp.glob("drive_rattle-*.tar.gz"))
    with tarfile.open(sdist) as tar:
        top = tar.getnames()[0].split("/")[0]
        held = {n.removeprefix(top + "/") for n in tar.getnames()}
    missing = [n for n in [*NEEDED, "LICENSE", "README.md", "pyproject.toml"] if n not in held]
    assert missing == [], f"the sdist lacks {missing}"
    wheel = next(tmp.glob("drive_rattle-*.whl"))
    venv = tmp / "venv"
    _run([_uv(), "venv", "-q", "--python", sys.executable, venv], tmp)
    bindir = venv / "bin"
    _run([_uv(), "pip", "install", "-q", "--python", bindir / "python",
          f"{wheel}[sweep]"], tmp, timeout=1800)
    user = tmp / "user"
    user.mkdir()
    return wheel, bindir, user


def _user_env(bindir: Path) -> dict:
    """The environment of a user of the installed wheel: nothing of this checkout.  The run's
    object cache stays: an object is taken from it only for the same compiler, flags, source
    and included headers by name and bytes (drive_rattle_build.compiler.object_keys), so a
    file the wheel lacks or holds otherwise is compiled from the wheel and fails or differs
    as it would for a user."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "RATTLE_MODEL_LIBRARY", "VIRTUAL_ENV")}
    env["PATH"] = f"{bindir}{os.pathsep}{env.get('PATH', '')}"
    return {**env, **_zig_cache_of_this_environment(bindir)}


def _zig_cache_of_this_environment(bindir: Path) -> dict:
    """ZIG_LIB_DIR set to this environment's ziglang, where the fresh environment installed the
    same release.  ziglang keys its cache of each cross target's C runtime by the path of its
    lib folder, so the fresh copy would build them all again (about two minutes of CPU for
    x86_64-windows alone), though its files are the same: pointed at this copy's folder, zig
    finds them built.  The build under test is the wheel's either way."""
    from importlib.metadata import version

    import ziglang

    theirs = _run([bindir / "python", "-c", "from importlib.metadata import version; "
                   "print(version('ziglang'))"], bindir).stdout.strip()
    if theirs != version("ziglang"):
        return {}
    return {"ZIG_LIB_DIR": str(Path(ziglang.__file__).parent / "lib")}


@pytest.mark.slow
def test_the_wheel_holds_everything_the_build_needs(installed):
    wheel, _, _ = installed
    with zipfile.ZipFile(wheel) as z:
        names = set(z.namelist())
    missing = [n for n in NEEDED if _in_wheel(n) not in names]
    assert missing == [], f"the wheel lacks {missing}"
    assert any(n.endswith(".dist-info/licenses/LICENSE") for n in names)
    assert not any(n.endswith((".so", ".dll", ".pyc")) or "egg-info" in n for n in names)
    print(f"the wheel holds {len(names)} files")


@pytest.mark.slow
def test_an_installed_wheel_builds_and_runs_everything(installed):
    """In an empty folder: ``drive-rattle-build`` writes every FMU and SSP; the README's
    Python example runs (the model library built from the installed sources on first use);
    a sweep on a cluster of the environment's own scheduler and two workers, on the built
    native FMUs, finishes every case."""
    _, bindir, user = installed
    env = _user_env(bindir)
    built = _run([bindir / "drive-rattle-build", "--out", "dist"], user, env, timeout=1800)
    for name in ("GearMeshRattle.fmu", "Driveline.fmu", "DriveRattle.ssp",
                 "DriveRattle_outputs.ssp", "native/GearMeshRattle.fmu", "native/Driveline.fmu",
                 "native/DriveRattle.ssp", "fmi3/GearMeshRattle.fmu", "fmi3/Driveline.fmu",
                 "fmi3/DriveRattle.ssp", "fmi3/DriveRattle_outputs.ssp"):
        assert (user / "dist" / name).is_file(), (name, built.stdout)
    with zipfile.ZipFile(user / "dist" / "native" / "GearMeshRattle.fmu") as z:
        assert "documentation/licenses/license.txt" in z.namelist()
        assert "resources/regression/GearMeshRattle_ref.csv" in z.namelist()

    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    example = next(b for b in re.findall(r"```python\n(.*?)```", readme, flags=re.S)
                   if "simulate(" in b)
    done = _run([bindir / "python", "-c", example], user, env)
    time_s, speed, impacts = done.stdout.split()
    assert float(time_s) == 0.5 and 40.0 < float(speed) < 50.0 and int(float(impacts)) >= 0

    cluster = user / "cluster"
    cluster.mkdir()
    scheduler_file = cluster / "scheduler.json"
    processes = []
    try:
        processes.append(subprocess.Popen(
            [bindir / "dask", "scheduler", "--host", "127.0.0.1", "--port", "0",
             "--no-dashboard", "--scheduler-file", scheduler_file], cwd=cluster, env=env,
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        address = scheduler_address(scheduler_file, 120)
        for k in range(2):
            folder = cluster / f"worker{k}"
            folder.mkdir()
            processes.append(subprocess.Popen(
                [bindir / "dask", "worker", address, "--nthreads", "1", "--no-dashboard",
                 "--host", "127.0.0.1", "--local-directory", folder], cwd=folder, env=env,
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        out = user / "sweep.csv"
        done = _run([bindir / "python", "-m", "drive_rattle_cosim.sweep", "--scheduler",
                     address, "--param", "GearMeshRattle.gear.backlash=0.08e-3:0.12e-3",
                     "--grid", "2", "--stop-time", "0.05", "--engine", "fmu", "--fmu-dir",
                     user / "dist" / "native", "--out", out], user, env)
    finally:
        for process in processes:
            process.kill()
            process.wait()
    with out.open(encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 2 and all(not r["error"] for r in rows), (rows, done.stdout)
