"""The README's commands and code are what CI and users run."""

import os
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")


def shell_blocks():
    return re.findall(r"```sh\n(.*?)```", README, flags=re.S)


def test_ci_runs_the_readme_test_command():
    test_cmd = next(b.strip() for b in shell_blocks() if "pytest" in b)
    assert test_cmd in (ROOT / ".ci" / "run").read_text()


def test_readme_main_command_runs_the_paper_scenario():
    main_cmd = next(b.strip() for b in shell_blocks() if "paper_scenario" in b)
    assert "examples/paper_scenario.py" in main_cmd and "pip install" in main_cmd


def test_readme_python_blocks_run():
    for block in re.findall(r"```python\n(.*?)```", README, flags=re.S):
        exec(compile(block, "README.md", "exec"), {})


def test_readme_variable_listing_command_runs_on_both_flavours(fmus, native_fmus, tmp_path):
    """`fmpy info dist/GearMeshRattle.fmu` as the README gives it, on each FMU of each flavour
    (the README's `.venv/bin/` is this interpreter's folder)."""
    import shutil
    import subprocess
    import sys

    command = next(b.strip() for b in shell_blocks() if "fmpy info" in b)
    bindir = Path(sys.executable).parent
    for flavour in (fmus, native_fmus):
        for name, path in flavour.items():
            folder = tmp_path / f"{name}_{path.parent.name}"
            (folder / "dist").mkdir(parents=True)
            shutil.copy2(path, folder / "dist" / "GearMeshRattle.fmu")
            run = subprocess.run(command.replace(".venv/bin/", f"{bindir}/"), shell=True,
                                 cwd=folder, capture_output=True, text=True, timeout=120)
            assert run.returncode == 0, run.stderr
            assert f"Model Name         {name}" in run.stdout
            unit_io = {"GearMeshRattle": ("pinion.w", "mesh.W"),
                       "Driveline": ("wheel.w", "wheel.tau_load")}[name]
            assert all(f"  {v} " in run.stdout for v in unit_io), run.stdout


#: What a fresh clone does not have: everything the build, the tests and a run leave behind.
BUILT = ("*.so", "*.so.id", "*.dll", "__pycache__", "*.egg-info", ".venv", "dist", "out",
         ".git", ".hypothesis", ".pytest_cache", ".ruff_cache")


@pytest.mark.slow
def test_the_main_command_runs_in_a_clone_with_no_model_library(fmus, tmp_path):
    """The README's main command on a fresh clone: no model library has been built yet (the
    tests' own session built one next to this checkout's sources, which hid that the scenario
    checked its parameters with the library before building anything).  The scenario runs from
    a copy of the sources without any built file, short, on this session's FMUs, and leaves
    the copy's library built."""
    import shutil
    import subprocess
    import sys

    copy = tmp_path / "clone"
    shutil.copytree(ROOT, copy, ignore=shutil.ignore_patterns(*BUILT))
    library = copy / "fmu_src" / "drive_rattle" / "rattle_model.so"
    assert not library.exists()
    env = {k: v for k, v in os.environ.items() if k != "RATTLE_MODEL_LIBRARY"}
    env["PYTHONPATH"] = str(copy / "fmu_src")  # ahead of the editable install's path
    run = subprocess.run(
        [sys.executable, "examples/paper_scenario.py", "--stop-time", "0.5", "--transient",
         "0.1", "--window", "0.2", "--fmu-dir", str(fmus["GearMeshRattle"].parent), "--out",
         str(tmp_path / "out")], cwd=copy, env=env, capture_output=True, text=True,
        timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    assert library.is_file() and "The paper comparison" in run.stdout
    # it says what it is doing while it works, each phase with its time, and the total
    assert "paper scenario [" in run.stderr and "co-simulating the FMUs" in run.stderr
    assert "done in" in run.stderr.splitlines()[-1]
