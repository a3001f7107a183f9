"""Regression kit: committed cross-check references, packed into the FMUs, and a check tight
enough to catch a 1 % change of a physical parameter."""

import re
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from drive_rattle.parameters import DrivelineParameters, MeshParameters
from drive_rattle_cosim.regression import (
    REFERENCE_ROOT,
    ReferenceFileError,
    check,
    read_opt,
    reference_files,
)

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


def cut_short(text: str) -> str:
    """The file as a full disk leaves it: the last row cut in the middle."""
    return text[:len(text) - len(text.splitlines()[-1]) // 2 - 1]


def nan_cell(text: str) -> str:
    """One cell of row 5 (line 5) NaN."""
    lines = text.splitlines(keepends=True)
    cells = lines[4].split(",")
    cells[3] = "nan"
    lines[4] = ",".join(cells)
    return "".join(lines)


#: A reference spoilt (file, how) and what the one sentence must say.
SPOILT = [
    ("_ref.csv", lambda text: "", "is empty"),
    ("_in.csv", lambda text: text.splitlines(keepends=True)[0], "has a header and no rows"),
    ("_ref.csv", cut_short, "row 502 has"),
    ("_in.csv", cut_short, "row 502 has 4 fields, the header 5"),
    ("_ref.csv", lambda text: b"\x89PNG\r\n\x1a\n\xff\x00".decode("latin-1"),
     "is not UTF-8 text (byte 0x89 at offset 0)"),
    ("_ref.csv", nan_cell, "row 5, column 'wheel.phi': 'nan' is not a finite number"),
    ("_in.csv", lambda text: text.replace("0.0833", "0,0833", 1),
     "row 2 has 6 fields, the header 5"),
    ("_in.csv", lambda text: text.replace("\n0.0001,", "\n0.0001x,", 1),
     "row 3, column 'time': '0.0001x' is not a finite number"),
    ("_in.csv", lambda text: text.replace("pinion.w", "pinion.speed", 1),
     "'pinion.speed' is not one of the FMU's variables"),
    ("_ref.csv", lambda text: text.replace("time", "t", 1), "first column is 't'"),
    ("_in.csv", lambda text: text.replace("pinion.a", "pinion.w", 1), "a column name repeats"),
    ("_ref.opt", lambda text: text.replace("StopTime", "Stop", 1), "lacks StopTime"),
    ("_ref.opt", lambda text: text.replace("1e-06", "tight", 1), "line 4: 'RelTol,tight'"),
]


@pytest.mark.parametrize("suffix, spoil, message", SPOILT,
                         ids=[f"{s}:{m[:30]}" for s, _, m in SPOILT])
def test_a_reference_that_cannot_be_trusted_is_refused_naming_the_file(fmus, tmp_path, suffix,
                                                                       spoil, message):
    model = "GearMeshRattle"
    shutil.copytree(REFERENCE_ROOT / model, tmp_path / model)
    path = tmp_path / model / f"{model}{suffix}"
    path.write_bytes(spoil(path.read_text(encoding="utf-8")).encode("latin-1"))
    with pytest.raises(ReferenceFileError) as err:
        check(fmus[model], tmp_path)
    text = str(err.value)
    assert text.startswith(f"reference {path} ") and message in text and "allowed:" in text, text


def test_cli_refuses_a_spoilt_reference_in_one_line(fmus, tmp_path):
    model = "GearMeshRattle"
    shutil.copytree(REFERENCE_ROOT / model, tmp_path / model)
    path = tmp_path / model / f"{model}_ref.csv"
    path.write_text(nan_cell(path.read_text(encoding="utf-8")), encoding="utf-8")
    run = subprocess.run([sys.executable, "-m", "drive_rattle_cosim.regression", "check",
                          str(fmus[model]), "--reference-dir", str(tmp_path)],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 2 and run.stdout == "", run.stdout + run.stderr
    assert re.fullmatch(rf"[^\n]*error: reference {re.escape(str(path))} row 5, column "
                        r"'wheel.phi': 'nan' is not a finite number[^\n]*\n", run.stderr), \
        run.stderr
