"""The in-process twin of the harness (drive_rattle_cosim.system): the FMUs in the fmpy
harness give exactly the twin's numbers, every signal at every point, from the start and from a
later start time."""

import pytest

from drive_rattle.library import DRIVELINE, MESH
from drive_rattle.parameters import DrivelineParameters, MeshParameters
from drive_rattle_cosim.harness import CoSimulation
from drive_rattle_cosim.system import SIGNALS, simulate


@pytest.mark.parametrize("parameters, start_time", [
    ({}, 0.0),
    ({"GearMeshRattle.gear.backlash": 2e-4, "GearMeshRattle.contact.dissipation": 2,
      "Driveline.engine.amplitude[1]": 1200.0, "Driveline.vehicle.drag": 0.3}, 0.25),
])
def test_the_harness_equals_the_in_process_twin_bit_for_bit(fmus, parameters, start_time):
    """The FMUs in the harness (initialization exchange, Jacobi steps on integer nanoseconds)
    give exactly the twin's numbers, every signal at every point: the FMI face adds nothing."""
    per_unit = {MESH: {}, DRIVELINE: {}}
    names = {MESH: "GearMeshRattle", DRIVELINE: "Driveline"}
    for qualified, value in parameters.items():
        unit, _, name = qualified.partition(".")
        per_unit[MESH if unit == names[MESH] else DRIVELINE][name] = value
    stop = start_time + 0.02
    ref = simulate(MeshParameters.from_public(per_unit[MESH]),
                   DrivelineParameters.from_public(per_unit[DRIVELINE]),
                   stop_time=stop, step=1e-4, start_time=start_time)
    with CoSimulation(fmus["GearMeshRattle"], fmus["Driveline"], parameters,
                      start_time=start_time) as sim:
        res = sim.run(stop)
    assert res.time == ref.time.tolist() and len(ref.time) == 201
    compared = 0
    for column in res.columns:
        name = column.split(".", 1)[1]
        if name in SIGNALS:
            assert res[column] == ref.signals[name].tolist(), column
            compared += 1
    assert compared >= 30
