"""The harness command line, end to end."""

import csv
import subprocess
import sys


def test_cli_runs_and_writes_csv_with_units(fmus, tmp_path):
    out = tmp_path / "run.csv"
    run = subprocess.run(
        [sys.executable, "-m", "drive_rattle_cosim.harness", "--mesh", str(fmus["GearMeshRattle"]),
         "--driveline", str(fmus["Driveline"]), "--stop-time", "0.01", "--step", "2e-4",
         "--set", "GearMeshRattle.gear.backlash=1.2e-4", "--set", "Driveline.vehicle.drag=0.2",
         "--record", "GearMeshRattle.wheel.w", "--record", "Driveline.wheel.tau_load",
         "--out", str(out)], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    rows = list(csv.reader(out.open()))
    assert rows[0] == ["time [s]", "GearMeshRattle.wheel.w [rad/s]",
                       "Driveline.wheel.tau_load [N.m]"]
    assert len(rows) == 52 and float(rows[-1][0]) == 0.01
    assert float(rows[1][2]) == 0.2


def test_cli_reports_bad_parameter(fmus, tmp_path):
    run = subprocess.run(
        [sys.executable, "-m", "drive_rattle_cosim.harness", "--mesh", str(fmus["GearMeshRattle"]),
         "--driveline", str(fmus["Driveline"]), "--set", "GearMeshRattle.gear.backlash=-1",
         "--out", str(tmp_path / "x.csv")], capture_output=True, text=True, timeout=300)
    assert run.returncode == 1
    assert "gear.backlash" in run.stderr and "allowed" in run.stderr
