"""GearMeshRattle: the gear-mesh impact and flank-friction model (Theodossiades et al. 2008) as
an FMI 2.0 co-simulation slave.  Thin: the physics is drive_rattle, the FMI glue
drive_rattle_fmi; this module only maps the two."""

from drive_rattle.interface import MESH_INPUTS, MESH_OUTPUTS, mesh_outputs
from drive_rattle.parameters import MeshParameters
from drive_rattle.stepper import StepResult, WheelState, WheelStepper
from drive_rattle_fmi.slave import RattleSlave


class GearMeshRattle(RattleSlave):
    """Helical gear mesh with backlash: Hertzian impacts of every tooth pair on both flanks and
    mixed boundary/viscous flank friction; pinion kinematics in, wheel motion and torques out."""

    description = (
        "Transmission drive rattle: gear-mesh impact (Hertz, every tooth pair, both flanks) and "
        "flank friction of a helical pair with backlash; kinematic pinion, wheel integrated "
        "inside (Theodossiades, Rahnejat, De la Cruz, Kelly, ENOC 2008)")
    PARAMETERS = MeshParameters
    INPUTS = MESH_INPUTS
    OUTPUTS = MESH_OUTPUTS

    def _build(self, params, inputs):
        return WheelStepper(params, inputs["pinion.phi"], inputs["pinion.w"],
                            inputs["wheel.tau_load"])

    def _step(self, t, h, inputs):
        self._model.step(h, inputs["pinion.phi"], inputs["pinion.w"], inputs["pinion.a"],
                         inputs["wheel.tau_load"])

    def _outputs(self, model):
        return mesh_outputs(model)

    def _quick_outputs(self, model):
        return {"wheel.phi": model.state.phi, "wheel.w": model.state.w}

    def _model_state(self, model):
        last = model.last
        return {
            "wheel": list(model.state.as_tuple()),
            "pinion": list(model.pinion),
            "last": [last.tau_wheel_mean, last.tau_pinion_mean, last.W_peak, last.delta_peak,
                     last.onsets_drive, last.onsets_coast],
        }

    def _restore_model_state(self, model, state):
        model.state = WheelState.from_tuple(state["wheel"])
        model.pinion = tuple(state["pinion"])
        tw, tp, wp, dp, nd, nc = state["last"]
        model.last = StepResult(tw, tp, wp, dp, int(nd), int(nc))
