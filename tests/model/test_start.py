"""start.c, the wheel's start: the static flank equilibrium for the initial load
(init.in_contact) against the oracle's equilibrium, with and without friction; a free
start's angle checked against the pinion."""

import pytest

from drive_rattle import COAST, DRIVE, MeshParameters, MeshUnit, ModelError
from tests.oracle.mesh import MeshModel

from .helpers import W_PINION


@pytest.mark.parametrize("load", [0.02, 0.15, 1.0, -0.3])
@pytest.mark.parametrize("friction", [False, True])
def test_static_load_sharing_of_the_start(load, friction):
    # init.in_contact: the wheel at the rigid ratio, in the flank equilibrium for the load --
    # sum W_i arm_w = load without friction, the mesh torque (friction included) = load with,
    # at the penetration the oracle's equilibrium finds.
    p = MeshParameters(friction_enabled=friction)
    g = p.derived()
    phi_p = 0.3
    unit = MeshUnit(p, phi_p, W_PINION, load)
    out = unit.outputs()
    flank = DRIVE if load > 0 else COAST
    assert out["wheel.w"] == W_PINION * g["ratio"]
    assert out["mesh.n_contact"] >= 1
    W = sum(out[f"pair[{k}].W"] for k in range(8))
    assert pytest.approx(out["mesh.W"], rel=1e-14) == W
    if not friction:
        assert flank * W * g["arm_wheel"] == pytest.approx(load, rel=1e-9)
        assert out["mesh.F"] == 0.0
    oracle = MeshModel(p)
    delta = oracle.equilibrium_penetration(phi_p, W_PINION, load)
    assert out["mesh.delta"] == pytest.approx(delta, rel=1e-9)
    loads = oracle.loads(flank, phi_p, W_PINION, out["wheel.phi"], out["wheel.w"], 0.0)
    assert loads.tau_wheel == pytest.approx(load, rel=1e-9)
    assert pytest.approx(out["mesh.W"], rel=1e-9) == loads.W


def test_a_free_start_inside_the_teeth_is_refused_at_initialization():
    from drive_rattle import MeshUnit

    with pytest.raises(ModelError) as err:
        MeshUnit(MeshParameters(init_in_contact=False, phi_start=0.01), 0.0, 0.0, 0.0)
    message = str(err.value)
    assert message.startswith("exitInitializationMode: ")
    assert "'wheel.phi_start' = 0.01" in message and "allowed: within the backlash" in message
