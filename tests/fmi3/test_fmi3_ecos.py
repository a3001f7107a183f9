"""A second FMI 3.0 master: Vico's ecos (pip ``ecospy`` 0.7.2, a C++ engine on fmi4c; it needs
Debian's ``libtbb12``) runs the FMI 3.0 pair coupled and gives, on its own grid (time
accumulated, ``t += step``), the numbers of the harness on the FMI 3.0 pair on that grid -- and
so of the FMI 2.0 native face -- bit for bit, a Float64 parameter set through its parameter set too.
ecos 0.7.2 does not handle FMI 3.0 Enumerations: it skips those variables with a warning
("Variable named 'contact.dissipation' is of unsupported type, skipping"), so the integer codes
cannot be set in ecos (docs/fmi3.md)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from drive_rattle.interface import DRIVELINE, MESH
from drive_rattle_cosim.harness import CoSimulation

from ..faces.twin import bits

ROOT = Path(__file__).resolve().parents[2]
STOP, STEP = 0.02, 1e-4  # 200 communication steps


def run_ecos(folder: Path, parameters: dict, tmp_path: Path) -> tuple[dict, str]:
    pytest.importorskip("ecospy", reason="ecospy is not installed")
    out = tmp_path / "ecos.json"
    run = subprocess.run([sys.executable, "-m", "tests.fmi3.ecos_run", str(folder), repr(STOP),
                          repr(STEP), json.dumps(parameters), str(out)], cwd=ROOT,
                         capture_output=True, text=True, timeout=600)
    if "libtbb" in run.stderr:
        pytest.skip(f"ecos cannot load: {run.stderr.strip()[-300:]} (Debian: apt-get install "
                    "libtbb12)")
    assert run.returncode == 0, run.stdout + run.stderr
    return json.loads(out.read_text(encoding="utf-8")), run.stdout + run.stderr


@pytest.mark.parametrize("parameters", [{}, {f"{MESH}.gear.backlash": 1.2e-4,
                                             f"{DRIVELINE}.engine.amplitude[1]": 2000.0}],
                         ids=["paper scenario", "backlash and order 2 set"])
def test_ecos_runs_the_pair_as_fmpy_does(fmi3_fmus, parameters, tmp_path):
    folder = fmi3_fmus[MESH].parent
    result, log = run_ecos(folder, parameters, tmp_path)
    with CoSimulation(fmi3_fmus[MESH], fmi3_fmus[DRIVELINE], parameters) as pair:
        mine = pair.run(STOP, grid="accumulated")
    assert result["time"] == [t.hex() for t in mine.time]
    assert set(result["columns"]) == set(mine.columns)
    for name, column in mine.columns.items():
        assert result["columns"][name] == bits([column])[0], name
    # what ecos 0.7.2 does with the Enumerations: it skips them, saying so
    for name in ("contact.hertz_law", "contact.dissipation", "friction.form",
                 "friction.shear_speed"):
        assert f"Variable named '{name}' is of unsupported type, skipping" in log
