"""The system as SSP, run by libcosim (a native C++ master), against the fmpy harness."""

import json
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from drive_rattle_cosim.harness import CoSimulation
from drive_rattle_cosim.ssp import SSD_NAME, check_bindings, validate_ssd, write_ssp

OUTPUTS = ["GearMeshRattle.wheel.w", "GearMeshRattle.wheel.phi", "GearMeshRattle.mesh.W",
           "GearMeshRattle.mesh.delta_peak", "Driveline.wheel.tau_load", "Driveline.pinion.w"]
PARAMS = {"GearMeshRattle.gear.backlash": 0.1e-3, "GearMeshRattle.friction.enabled": True,
          "Driveline.vehicle.drag": 0.15, "Driveline.engine.amplitude[1]": 300.0}

LIBCOSIM_RUN = """
import json, sys
from drive_rattle_cosim.ssp import run_libcosim
r = run_libcosim(sys.argv[1], float(sys.argv[2]), json.loads(sys.argv[3]))
print(json.dumps({"time": r.time, "columns": r.columns}))
"""


def run_in_libcosim(ssp: Path, stop_time: float) -> dict:
    # libcosim runs in its own process: libcosim and fmpy loading the same pythonfmu binaries
    # in one process sometimes abort at interpreter exit (see /docs/cosim.md).
    out = subprocess.run([sys.executable, "-c", LIBCOSIM_RUN, str(ssp), repr(stop_time),
                          json.dumps(OUTPUTS)], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def ssp_dir(fmus, tmp_path_factory):
    return write_ssp(tmp_path_factory.mktemp("ssp") / "system", fmus["GearMeshRattle"],
                     fmus["Driveline"], PARAMS, step=1e-4)


def test_ssd_is_schema_valid_and_complete(ssp_dir, fmus, tmp_path):
    validate_ssd(ssp_dir / SSD_NAME)
    text = (ssp_dir / SSD_NAME).read_text()
    assert text.count("<ssd:Connection ") == 6
    assert 'baseStepSize="0.0001"' in text
    assert (ssp_dir / "resources" / "GearMeshRattle.fmu").is_file()
    zipped = write_ssp(tmp_path / "system.ssp", fmus["GearMeshRattle"], fmus["Driveline"], PARAMS)
    with zipfile.ZipFile(zipped) as z:
        assert set(z.namelist()) == {SSD_NAME, "resources/GearMeshRattle.fmu",
                                     "resources/Driveline.fmu"}
    from fmpy.ssp.ssd import read_ssd

    ssd = read_ssd(str(zipped), validate=True)
    assert len(ssd.system.connections) == 6


@pytest.mark.parametrize("params, fragment", [
    ({"GearMeshRattle.gear.teeth": 20}, "no such parameter"),
    ({"GearMeshRattle.wheel.w": 1.0}, "no such parameter"),
    ({"GearMeshRattle.friction.enabled": 1.5}, "is Real"),
])
def test_bindings_are_checked_against_the_fmus(fmus, params, fragment):
    with pytest.raises(ValueError, match=fragment):
        check_bindings(fmus, params)


def test_libcosim_and_harness_agree_bit_for_bit(ssp_dir, fmus):
    stop = 0.03  # 300 communication steps: several impacts
    lc = run_in_libcosim(ssp_dir, stop)
    with CoSimulation(fmus["GearMeshRattle"], fmus["Driveline"], PARAMS, step=1e-4) as sim:
        ref = sim.run(stop, [*OUTPUTS, "GearMeshRattle.mesh.impacts_drive"])
    assert ref["GearMeshRattle.mesh.impacts_drive"][-1] >= 3
    # libcosim records from the first point after the start (it initializes in its first step);
    # both masters are Jacobi on the same integer-nanosecond grid, so the numbers are identical.
    assert lc["time"] == ref.time[1:]
    for name in OUTPUTS:
        assert lc["columns"][name] == ref[name][1:], name
