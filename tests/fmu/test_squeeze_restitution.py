"""The squeeze-film impact law (contact.dissipation = 3) through the built GearMeshRattle FMU:
single impacts of the free wheel on a pinion at rest, from below the critical speed to
100 mm/s, rebound as the law of tests/oracle/dissipation.py says, and as the model library's
impacts that docs/model.md section 3.3's table shows (drive_rattle_cosim.squeeze_impacts)."""

import itertools

import pytest

from drive_rattle import DRIVE
from drive_rattle_cosim import squeeze_impacts
from drive_rattle_cosim.harness import Unit
from tests.model.helpers import free_parameters
from tests.oracle import dissipation
from tests.oracle.mesh import MeshModel

H = 1e-4


def fmu_restitution(fmu, v: float, name: str) -> float:
    """Release speed over approach speed of one impact at normal speed ``v`` [m/s] through the
    FMU: the wheel started 20 nm short of the drive flank, the pinion held at rest, no load;
    stepped until the flanks have parted after the onset (the wheel then flies at a constant
    speed)."""
    p = free_parameters(v, DRIVE, dissipation=3)
    u = Unit(fmu, name)
    try:
        u.set({"contact.dissipation": 3, "init.in_contact": False, "friction.enabled": False,
               "wheel.phi_start": p.phi_start, "wheel.w_start": p.w_start})
        u.slave.setupExperiment(startTime=0.0)
        u.slave.enterInitializationMode()
        u.set({"pinion.phi": 0.0, "pinion.w": 0.0, "pinion.a": 0.0, "wheel.tau_load": 0.0})
        u.slave.exitInitializationMode()
        names = ["wheel.w", "mesh.W", "mesh.delta"]
        vrs = [u.var(n).vr for n in names]
        impacts = u.var("mesh.impacts_drive").vr
        for k in range(2000):
            u.slave.doStep(k * H, H)
            w, W, delta = u.slave.getReal(vrs)
            hit = u.slave.getInteger([impacts])[0]
            if hit and W == 0.0 and delta == 0.0:
                return w / -p.w_start
        raise AssertionError(f"no release within {2000 * H} s at {v} m/s")
    finally:
        u.slave.terminate()
        u.slave.freeInstance()


def test_the_fmu_realizes_the_squeeze_film_law_from_sticking_to_100_mm_per_s(fmus):
    p = free_parameters(1e-3, DRIVE, dissipation=3)
    m = MeshModel(p)
    v_c = dissipation.critical_speed(m, dissipation.flank_area(m, DRIVE, 0.0))
    # the documented table's speeds, from the library's critical speed, which is the oracle's
    assert squeeze_impacts.library_critical_speed() == pytest.approx(v_c, rel=1e-9)
    speeds = squeeze_impacts.speeds(v_c)
    assert speeds == sorted(speeds) and speeds[2] < v_c < speeds[3]
    measured = [fmu_restitution(fmus["GearMeshRattle"], v, f"m{i}")
                for i, v in enumerate(speeds)]
    law = [dissipation.onset(m, DRIVE, 0.0, v).restitution for v in speeds]
    for v, e, want in zip(speeds, measured, law, strict=True):
        assert e == pytest.approx(want, abs=1e-3), (v, e, want)
    # no rebound below the critical speed; above it the restitution rises with the speed
    assert measured[:3] == [0.0, 0.0, 0.0]
    assert all(b > a for a, b in itertools.pairwise(measured[2:]))
    assert measured[-1] > 0.9
    # the FMU is the library's code: the documented table's impacts, to rounding
    library = [squeeze_impacts.measured_restitution(v) for v in speeds]
    assert measured == pytest.approx(library, abs=1e-9)
