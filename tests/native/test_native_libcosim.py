"""The native FMUs in libcosim (a native C++ master) through the SSP: the same numbers as the
fmpy harness, and as the pythonfmu pair, bit for bit."""

from __future__ import annotations

import pytest

from drive_rattle_cosim.harness import CoSimulation
from drive_rattle_cosim.ssp import write_ssp

from ..cosim.test_ssp_libcosim import OUTPUTS, PARAMS, run_in_libcosim


@pytest.fixture(scope="module")
def native_ssp(native_fmus, tmp_path_factory):
    return write_ssp(tmp_path_factory.mktemp("native_ssp") / "DriveRattle.ssp",
                     native_fmus["GearMeshRattle"], native_fmus["Driveline"], PARAMS, step=1e-4)


def test_libcosim_runs_the_native_pair_as_the_harness_does(native_ssp, native_fmus, fmus):
    stop = 0.05  # 500 communication steps
    lc = run_in_libcosim(native_ssp, stop)
    runs = {}
    for flavour, pair in (("native", native_fmus), ("pythonfmu", fmus)):
        with CoSimulation(pair["GearMeshRattle"], pair["Driveline"], PARAMS, step=1e-4) as sim:
            runs[flavour] = sim.run(stop, [*OUTPUTS, "GearMeshRattle.mesh.impacts_drive"])
    assert runs["native"]["GearMeshRattle.mesh.impacts_drive"][-1] >= 3
    # libcosim records from the first point after the start (it initializes in its first step)
    assert lc["time"] == runs["native"].time[1:]
    for name in OUTPUTS:
        assert lc["columns"][name] == runs["native"][name][1:], name
        assert runs["native"][name] == runs["pythonfmu"][name], name
