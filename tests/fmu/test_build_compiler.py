"""The build's C compiler: gcc, else the clang of the ziglang package, else a clear message
(the pythonfmu FMUs: the model library and the status shim)."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from drive_rattle_cosim.harness import CoSimulation
from drive_rattle_cosim.masters import COUPLING

ROOT = Path(__file__).resolve().parents[2]
BUILD = ROOT / "build_fmu.py"


def build_without_gcc(out: Path, hide_ziglang: bool = False, **env) -> subprocess.CompletedProcess:
    """`python build_fmu.py --out OUT` with nothing on PATH (no gcc, no cc), optionally with
    the ziglang package made unimportable too."""
    empty = out.parent / "empty_path"
    empty.mkdir(exist_ok=True)
    code = ("import runpy, sys\n"
            + ("sys.modules['ziglang'] = None\n" if hide_ziglang else "")
            + f"sys.argv = ['build_fmu.py', '--out', {str(out)!r}, '--no-fmutool', "
            "'--no-native', '--no-fmi3']\n"
            + f"runpy.run_path({str(BUILD)!r}, run_name='__main__')\n")
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=600, env={"HOME": os.environ.get("HOME", "/tmp"),
                                            "PATH": str(empty), **env})


def test_without_gcc_the_build_uses_ziglang_and_runs_the_same(fmus, tmp_path):
    pytest.importorskip("ziglang")
    out = tmp_path / "dist"
    run = build_without_gcc(out)
    assert run.returncode == 0, run.stdout + run.stderr
    assert (out / "DriveRattle.ssp").is_file() and (out / "DriveRattle_outputs.ssp").is_file()
    # The model library and the shim compiled by ziglang's clang compute what gcc's do, bit
    # for bit.
    results = []
    for folder in (out, fmus["GearMeshRattle"].parent):
        with CoSimulation(folder / "GearMeshRattle.fmu", folder / "Driveline.fmu") as sim:
            r = sim.run(0.06, [*COUPLING, "GearMeshRattle.mesh.W", "GearMeshRattle.mesh.h",
                               "GearMeshRattle.mesh.impacts_drive"])
        results.append(r.columns)
    assert results[0]["GearMeshRattle.mesh.impacts_drive"][-1] > 0  # contacts and impacts
    assert results[0] == results[1]


def test_without_any_compiler_the_build_says_what_to_install(tmp_path):
    run = build_without_gcc(tmp_path / "dist", hide_ziglang=True)
    assert run.returncode == 1
    assert "Traceback" not in run.stderr
    assert "no C compiler" in run.stderr and "pip install ziglang" in run.stderr
    assert "apt-get install gcc" in run.stderr


def test_a_cc_that_is_not_there_is_named(tmp_path):
    run = build_without_gcc(tmp_path / "dist", CC="no-such-cc")
    assert run.returncode == 1 and "Traceback" not in run.stderr
    assert "CC = 'no-such-cc' is not an executable" in run.stderr
