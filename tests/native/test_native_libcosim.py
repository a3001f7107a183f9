"""The native FMUs in libcosim (a native C++ master) through the SSP: the same numbers as the
fmpy harness and the in-process twin, bit for bit."""

from __future__ import annotations

import pytest

from drive_rattle.interface import DRIVELINE, MESH
from drive_rattle.parameters import DrivelineParameters, MeshParameters
from drive_rattle_cosim.harness import CoSimulation
from drive_rattle_cosim.ssp import write_ssp
from drive_rattle_cosim.system import simulate

from ..cosim.test_ssp import OUTPUTS, PARAMS, run_in_libcosim


@pytest.fixture(scope="module")
def native_ssp(native_fmus, tmp_path_factory):
    return write_ssp(tmp_path_factory.mktemp("native_ssp") / "DriveRattle.ssp",
                     native_fmus[MESH], native_fmus[DRIVELINE], PARAMS, step=1e-4)


def unit_parameters(unit: str) -> dict:
    return {k.partition(".")[2]: v for k, v in PARAMS.items() if k.startswith(f"{unit}.")}


def test_libcosim_runs_the_native_pair_as_the_harness_and_the_twin(native_ssp, native_fmus):
    stop = 0.05  # 500 communication steps
    lc = run_in_libcosim(native_ssp, stop)
    with CoSimulation(native_fmus[MESH], native_fmus[DRIVELINE], PARAMS, step=1e-4) as sim:
        harness = sim.run(stop, [*OUTPUTS, f"{MESH}.mesh.impacts_drive"])
    twin = simulate(MeshParameters.from_public(unit_parameters(MESH)),
                    DrivelineParameters.from_public(unit_parameters(DRIVELINE)), stop_time=stop)
    assert harness[f"{MESH}.mesh.impacts_drive"][-1] >= 3
    # libcosim records from the first point after the start (it initializes in its first step)
    assert lc["time"] == harness.time[1:] == twin.time[1:].tolist()
    for qualified in OUTPUTS:
        name = qualified.partition(".")[2]
        assert lc["columns"][qualified] == harness[qualified][1:], qualified
        assert harness[qualified] == twin.signals[name].tolist(), qualified
