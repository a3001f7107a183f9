"""NullMeshRattle: the GearMeshRattle interface with no physics -- the FMI overhead floor of the
benchmark (R0).  The wheel follows the pinion rigidly; every other output stays 0."""

from drive_rattle.interface import MESH_INPUTS, MESH_OUTPUTS
from drive_rattle.parameters import MeshParameters
from drive_rattle_fmi.slave import RattleSlave


class _Rigid:
    def __init__(self, ratio, phi_p, w_p):
        self.ratio, self.phi, self.w = ratio, ratio * phi_p, ratio * w_p


class NullMeshRattle(RattleSlave):
    """Same variables as GearMeshRattle; the wheel is rigidly geared to the pinion."""

    description = "Null model of GearMeshRattle (benchmark overhead floor)"
    PARAMETERS = MeshParameters
    INPUTS = MESH_INPUTS
    OUTPUTS = MESH_OUTPUTS

    def _build(self, params, inputs):
        return _Rigid(params.z_pinion / params.z_wheel, inputs["pinion.phi"], inputs["pinion.w"])

    def _step(self, t, h, inputs):
        m = self._model
        m.phi = m.ratio * (inputs["pinion.phi"] + h * (inputs["pinion.w"]
                                                     + 0.5 * h * inputs["pinion.a"]))
        m.w = m.ratio * (inputs["pinion.w"] + h * inputs["pinion.a"])

    def _outputs(self, model):
        out = {s.name: (0.0 if s.fmi_type == "Real" else 0) for s in MESH_OUTPUTS}
        out["wheel.phi"], out["wheel.w"] = model.phi, model.w
        return out

    def _model_state(self, model):
        return [model.phi, model.w]

    def _restore_model_state(self, model, state):
        model.phi, model.w = state
