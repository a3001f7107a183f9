"""The native FMI 2.0 FMUs are the model library under an FMI face (every face alone and
coupled: tests/faces/test_equivalence.py; their states: tests/faces/test_states.py): coupled
with a measured speed table, bit for bit the in-process twin (``drive_rattle_cosim.system.
simulate``, which runs the same C); the committed regression references pass, packed in the FMU
and in the repository."""

from __future__ import annotations

import math
import subprocess
import sys

import pytest

from drive_rattle.interface import DRIVELINE, MESH, MODELS
from drive_rattle.parameters import DrivelineParameters, MeshParameters
from drive_rattle_cosim.harness import CoSimulation
from drive_rattle_cosim.regression import REFERENCE_ROOT, check
from drive_rattle_cosim.system import SIGNALS, simulate

from .twin import bits


def harness_and_twin(native_fmus, mesh: dict, driveline: dict, stop: float):
    """The coupled native pair under the harness and the twin: (result, record)."""
    params = {**{f"{MESH}.{k}": v for k, v in mesh.items()},
              **{f"{DRIVELINE}.{k}": v for k, v in driveline.items()}}
    with CoSimulation(native_fmus[MESH], native_fmus[DRIVELINE], params) as sim:
        result = sim.run(stop)
    record = simulate(MeshParameters.from_public(mesh), DrivelineParameters.from_public(driveline),
                      stop_time=stop)
    return result, record


def assert_same(result, record) -> None:
    assert [t.hex() for t in result.time] == [t.hex() for t in record.time]
    compared = 0
    for qualified, column in result.columns.items():
        name = qualified.partition(".")[2]
        if qualified.startswith(f"{MESH}.") and name not in SIGNALS:
            continue  # the twin records the mesh's outputs and the driveline's
        if name in SIGNALS:
            assert bits([column]) == bits([record.signals[name]]), qualified
            compared += 1
    assert compared >= 30


def test_coupled_with_a_speed_table_is_the_twin(native_fmus, tmp_path):
    table = tmp_path / "speed run-up.csv"
    rows = [(k * 0.01, 80.0 + 15.0 * math.sin(40.0 * k * 0.01)) for k in range(11)]
    table.write_text("time [s],speed [rad/s]\n" + "".join(f"{t!r},{w!r}\n" for t, w in rows),
                     encoding="utf-8")
    result, record = harness_and_twin(native_fmus, {}, {"engine.speed_table": str(table)}, 0.08)
    assert_same(result, record)


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
