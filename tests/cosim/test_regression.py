"""Regression kit: committed cross-check references, packed into the FMUs, and a check tight
enough to catch a 1 % change of a physical parameter."""

import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from drive_rattle.parameters import DrivelineParameters, MeshParameters
from drive_rattle_cosim.regression import REFERENCE_ROOT, check, read_opt, reference_files

MODELS = ["GearMeshRattle", "Driveline"]


@pytest.mark.parametrize("model", MODELS)
def test_references_are_committed_and_packed(fmus, model):
    files = reference_files(model)
    assert all(f.is_file() for f in files)
    opt = read_opt(files[2])
    assert opt["StopTime"] - opt["StartTime"] == pytest.approx(0.05)
    with zipfile.ZipFile(fmus[model]) as z:
        for f in files:
            assert z.read(f"resources/regression/{f.name}") == f.read_bytes()


@pytest.mark.parametrize("model", MODELS)
def test_built_fmus_pass_their_references(fmus, model):
    for source in (None, REFERENCE_ROOT):  # packed in the FMU, and the committed folder
        checks = check(fmus[model], source)
        assert checks and all(c.passed for c in checks), [c for c in checks if not c.passed]


@pytest.mark.parametrize("model, parameter, value", [
    ("GearMeshRattle", "gear.backlash", 0.10e-3 * 1.01),
    ("GearMeshRattle", "wheel.J", 1.3e-3 * 1.01),
    ("GearMeshRattle", "contact.crowning", MeshParameters().crowning * 1.01),
    ("GearMeshRattle", "contact.squeeze_fraction", MeshParameters().squeeze_fraction * 1.01),
    ("Driveline", "shaft.k", DrivelineParameters().k_shaft * 1.01),
    ("Driveline", "vehicle.drag", DrivelineParameters().drag * 1.01),
])
def test_one_percent_parameter_change_fails_the_check(fmus, model, parameter, value):
    checks = check(fmus[model], start_values={parameter: value})
    failed = [c for c in checks if not c.passed]
    assert failed, f"a 1 % change of {parameter} went unnoticed"


def test_cli_exit_codes(fmus):
    run = subprocess.run([sys.executable, "-m", "drive_rattle_cosim.regression", "check",
                          str(fmus["GearMeshRattle"]), str(fmus["Driveline"])],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stdout.count(": pass") == 2


def test_sequential_simulate_fmu_of_both_units_in_one_process(fmus):
    # fmpy deletes each FMU's unpacked folder after the run; the second FMU must still find
    # every module of the shared packages (they are imported eagerly).
    code = ("import sys; from fmpy import simulate_fmu\n"
            "for p in sys.argv[1:]: simulate_fmu(p, stop_time=1e-3, output_interval=1e-4)\n"
            "print('ok')")
    for order in (MODELS, MODELS[::-1]):
        run = subprocess.run([sys.executable, "-c", code, *(str(fmus[m]) for m in order)],
                             capture_output=True, text=True, timeout=300)
        assert run.returncode == 0 and run.stdout.strip() == "ok", run.stderr
        assert Path(fmus[order[0]]).exists()
