"""The harness command line, end to end, and its refusals of a bad request before any work."""

import csv
import subprocess
import sys

import pytest

from drive_rattle_cosim import harness


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


def test_cli_sets_an_enumeration_by_its_item_name_and_a_boolean_by_its_word(fmus, tmp_path):
    """``contact.dissipation=hunt_crossley_damping`` reaches the FMU as its code 2, and
    ``friction.enabled=false`` as false (the values read back from the unit)."""
    out = tmp_path / "run.csv"
    run = subprocess.run(
        [sys.executable, "-m", "drive_rattle_cosim.harness", "--mesh", str(fmus["GearMeshRattle"]),
         "--driveline", str(fmus["Driveline"]), "--stop-time", "0.001",
         "--set", "GearMeshRattle.contact.dissipation=hunt_crossley_damping",
         "--set", "GearMeshRattle.friction.enabled=false",
         "--record", "GearMeshRattle.contact.dissipation",
         "--record", "GearMeshRattle.friction.enabled", "--out", str(out)],
        capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    rows = list(csv.reader(out.open()))
    assert {(r[1], r[2]) for r in rows[1:]} == {("2", "False")}


def test_cli_reports_bad_parameter(fmus, tmp_path):
    run = subprocess.run(
        [sys.executable, "-m", "drive_rattle_cosim.harness", "--mesh", str(fmus["GearMeshRattle"]),
         "--driveline", str(fmus["Driveline"]), "--set", "GearMeshRattle.gear.backlash=-1",
         "--out", str(tmp_path / "x.csv")], capture_output=True, text=True, timeout=300)
    assert run.returncode == 2
    assert "gear.backlash" in run.stderr and "allowed" in run.stderr
    assert len(run.stderr.splitlines()) == 1 and not (tmp_path / "x.csv").exists()


B = "GearMeshRattle.gear.backlash"


@pytest.mark.parametrize("args, message", [
    (["--set", f"{B}="], f"parameter '{B}' = '' is not a number; allowed: [0, 0.005] m"),
    (["--set", "=0x10"], "setting '=0x10' is not NAME=VALUE; allowed"),
    (["--set", f"{B}=0x10"], "= '0x10' is not a number; allowed: [0, 0.005] m"),
    (["--set", "GearMeshRattle.gear.z_pinion=20.5"],
     "'GearMeshRattle.gear.z_pinion' = '20.5' is not a whole number; allowed: [5, 400]"),
    (["--set", "GearMeshRattle.friction.enabled=maybe"],
     "= 'maybe' is not a truth value; allowed: true or false"),
    (["--set", "GearMeshRattle.contact.dissipation=None"], "did you mean 'none'?"),
    (["--set", "GearMeshRattle.contact.dissipation=7"], "= 7 is not one of"),
    (["--set", "GearMeshRattle.gear.backlas=1e-4"], f"did you mean {B}"),
    (["--set", "gear.backlash=1e-4"], f"did you mean {B}?"),
    (["--set", f"{B}=1e-4", "--set", f"{B}=2e-4"], "is set twice"),
    (["--set", f"{B}=-1"], "= -1 is out of range; allowed: [0, 0.005] m"),
    (["--step", "0"], "step 0.0 s must be a positive whole number of nanoseconds"),
    (["--stop-time", "nan"], "--stop-time nan s after --start-time 0.0 s; allowed"),
])
def test_a_bad_request_is_refused_before_the_fmus_load(tmp_path, capsys, args, message):
    missing = tmp_path / "no.fmu"  # never opened: the request is refused first
    with pytest.raises(SystemExit) as end:
        harness.main(["--mesh", str(missing), "--driveline", str(missing), *args,
                      "--out", str(tmp_path / "x.csv")])
    err = capsys.readouterr().err
    assert end.value.code == 2 and len(err.splitlines()) == 1 and message in err, err
