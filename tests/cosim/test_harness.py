"""The harness command line, end to end, and its refusals of a bad request before any work."""

import csv
import os
import re
import subprocess
import sys
import tempfile
import zipfile

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


@pytest.mark.parametrize("face", ["fmus", "fmi3_fmus"])
def test_cli_sets_an_enumeration_by_its_item_name_and_a_boolean_by_its_word(face, request,
                                                                            tmp_path):
    """``contact.dissipation=hunt_crossley_damping`` reaches the FMU (FMI 2.0: an Integer;
    FMI 3.0: an Int64) as its code 2, and ``friction.enabled=false`` as false (the values read
    back from the unit)."""
    fmus = request.getfixturevalue(face)
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


def run_cli(mesh, driveline, out, *args, env=None):
    return subprocess.run([sys.executable, "-m", "drive_rattle_cosim.harness", "--mesh",
                           str(mesh), "--driveline", str(driveline), "--out", str(out), *args],
                          capture_output=True, text=True, timeout=600, env=env)


def test_the_fmi3_pair_writes_the_native_pairs_csv(native_fmus, fmi3_fmus, tmp_path):
    """The command on the FMI 3.0 FMUs and on the native FMI 2.0 FMUs, every output at the
    default step and stop: the same file, byte for byte (the same model library under two
    standards, one loop: every float written as its shortest round trip)."""
    files = {}
    for flavour, fmus in (("native", native_fmus), ("fmi3", fmi3_fmus)):
        files[flavour] = tmp_path / f"{flavour}.csv"
        run = run_cli(fmus["GearMeshRattle"], fmus["Driveline"], files[flavour])
        assert run.returncode == 0, run.stderr
    native = files["native"].read_bytes()
    assert native.count(b"\n") == 1002 and native.count(b",", 0, native.index(b"\n")) == 35
    assert files["fmi3"].read_bytes() == native


def without_binary(fmu, target):
    """A copy of ``fmu`` without its binary for this machine (as an FMU for another platform)."""
    with zipfile.ZipFile(fmu) as source, zipfile.ZipFile(target, "w") as copy:
        for info in source.infolist():
            if not info.filename.startswith(("binaries/linux64/", "binaries/x86_64-linux/")):
                copy.writestr(info, source.read(info))
    return target


def with_token(fmu, target, token: str):
    """A copy of ``fmu`` whose modelDescription names another GUID / instantiation token, which
    the binary refuses at instantiation."""
    with zipfile.ZipFile(fmu) as source, zipfile.ZipFile(target, "w") as copy:
        for info in source.infolist():
            data = source.read(info)
            if info.filename == "modelDescription.xml":
                data = re.sub(rb'(guid|instantiationToken)="[^"]*"',
                              rb'\1="' + token.encode() + b'"', data)
            copy.writestr(info, data)
    return target


FAILURES = {
    "no binary for this platform": (
        lambda fmus, tmp: (without_binary(fmus["GearMeshRattle"], tmp / "m.fmu"),
                           fmus["Driveline"], {}),
        "cannot load"),
    "a token the binary refuses": (
        lambda fmus, tmp: (fmus["GearMeshRattle"],
                           with_token(fmus["Driveline"], tmp / "d.fmu", "{0}"), {}),
        "does not match this FMU's"),
    "a parameter refused in initialization": (
        lambda fmus, tmp: (fmus["GearMeshRattle"], fmus["Driveline"],
                           {"GearMeshRattle.gear.backlash": -1.0}),
        "'gear.backlash' = -1 is out of range"),
}


@pytest.mark.parametrize("failure", list(FAILURES))
@pytest.mark.parametrize("standard", ["FMI 2.0", "FMI 3.0"])
def test_a_failed_load_leaves_no_temporary_folder(native_fmus, fmi3_fmus, tmp_path, monkeypatch,
                                                  standard, failure):
    """Every FMU is unpacked into a temporary folder of its own; a load or an initialization
    that fails removes them all, says why in one CoSimulationError, and leaves the working
    folder where it was."""
    fmus = native_fmus if standard == "FMI 2.0" else fmi3_fmus
    make, message = FAILURES[failure]
    mesh, driveline, parameters = make(fmus, tmp_path)
    private = tmp_path / "tmp"
    private.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(private))
    cwd = os.getcwd()
    with pytest.raises(harness.CoSimulationError) as err:
        harness.CoSimulation(mesh, driveline, parameters)
    assert message in str(err.value) and "\n" not in str(err.value), err.value
    assert os.listdir(private) == [] and os.getcwd() == cwd
    with harness.CoSimulation(fmus["GearMeshRattle"], fmus["Driveline"]) as sim:
        assert len(os.listdir(private)) == 2
        sim.run(0.001)
    assert os.listdir(private) == []


def test_the_cli_on_an_fmu_it_cannot_load_says_so_in_one_line(fmi3_fmus, tmp_path):
    """The command on an FMU without a binary for this machine: exit status 1, one line naming
    the missing library, no traceback, nothing left in its temporary folder."""
    private = tmp_path / "tmp"
    private.mkdir()
    mesh = without_binary(fmi3_fmus["GearMeshRattle"], tmp_path / "m.fmu")
    run = run_cli(mesh, fmi3_fmus["Driveline"], tmp_path / "x.csv",
                  env={**os.environ, "TMPDIR": str(private)})
    assert run.returncode == 1, run.stderr
    assert re.fullmatch(r"error: GearMeshRattle: cannot load \S+m\.fmu: Cannot find shared "
                        r"library \S+/binaries/x86_64-linux/GearMeshRattle\.so\.\n", run.stderr), \
        run.stderr
    assert os.listdir(private) == [] and not (tmp_path / "x.csv").exists()
