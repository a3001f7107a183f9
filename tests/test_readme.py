"""The README's commands and code are what CI and users run."""

import re
from pathlib import Path

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
