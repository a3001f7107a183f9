"""The committed regression references pass on the native FMI 2.0 FMUs, packed in the FMU and
in the repository (that every face is the model library bit for bit, alone and coupled:
tests/faces/test_equivalence.py; their states: tests/faces/test_states.py)."""

from __future__ import annotations

import subprocess
import sys

import pytest

from drive_rattle.interface import MODELS
from drive_rattle_cosim.regression import REFERENCE_ROOT, check


# ------------------------------------------------------------------ regression references
@pytest.mark.parametrize("model", MODELS)
def test_regression_references_pass(native_fmus, model):
    for source in (None, REFERENCE_ROOT):  # packed in the FMU, and the committed folder
        checks = check(native_fmus[model], source)
        assert checks and all(c.passed for c in checks), [c for c in checks if not c.passed]


def test_regression_cli(native_fmus):
    run = subprocess.run([sys.executable, "-m", "drive_rattle_cosim.regression", "check",
                          *(str(native_fmus[m]) for m in MODELS)],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stdout.count(": pass") == 2
