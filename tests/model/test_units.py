"""The Python API's units (fmu_src/drive_rattle/units.py): the compiled coupled loop's run
(``run_coupled`` and its ``CoupledRun``)."""

from drive_rattle import DrivelineParameters, DrivelineUnit, MeshParameters, MeshUnit
from drive_rattle.units import coupled_start_inputs, run_coupled


def _pair():
    mp, dp = MeshParameters(), DrivelineParameters()
    m_in, wheel = coupled_start_inputs(mp, dp)
    return (MeshUnit(mp, m_in["pinion.phi"], m_in["pinion.w"], m_in["wheel.tau_load"],
                     m_in["pinion.a"]),
            DrivelineUnit(dp, wheel["wheel.phi"], wheel["wheel.w"]))


def test_a_run_makes_its_lists_once():
    """``time`` and ``columns`` are the points t_k = k step and the recorded values, made on
    first use and then the same objects: a study that reads them once per step stays linear
    in the run's length (the benchmark read ``time`` twice per step when it was rebuilt on
    every access, and did not finish)."""
    mesh, drive = _pair()
    run = run_coupled(mesh, drive, 100_000, 50, ["GearMeshRattle.wheel.w"])
    assert run.time == [k * 100_000 / 1e9 for k in range(51)]
    assert run.time is run.time and run.columns is run.columns
    assert len(run.columns["GearMeshRattle.wheel.w"]) == 51
