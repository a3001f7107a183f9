"""Driveline: the simple driveline around the gear mesh as an FMI 2.0 co-simulation slave --
input-shaft kinematics from engine orders or a measured speed table, and the output shaft to
the reflected vehicle inertia.  Thin: physics in drive_rattle, FMI glue in drive_rattle_fmi."""

from pathlib import Path

from drive_rattle.driveline import Driveline as DrivelineModel
from drive_rattle.driveline import ShaftState
from drive_rattle.interface import DRIVELINE_INPUTS, DRIVELINE_OUTPUTS
from drive_rattle_fmi.boundary import DrivelineInputReading, DrivelineUnitParameters
from drive_rattle_fmi.slave import RattleSlave


class Driveline(DrivelineInputReading, RattleSlave):
    """Engine-order (or measured) pinion kinematics out; wheel angle and speed in, output-shaft
    load torque out."""

    description = (
        "Driveline around the drive-rattle gear mesh: input-shaft kinematics from engine orders "
        "or a measured speed table, output shaft as a torsional spring-damper to a reflected "
        "vehicle inertia with drag")
    PARAMETERS = DrivelineUnitParameters
    INPUTS = DRIVELINE_INPUTS
    OUTPUTS = DRIVELINE_OUTPUTS

    def _build(self, params, inputs):
        resources = Path(self.resources) if self.resources else None
        model = DrivelineModel(params, self._start_time, inputs["wheel.phi"], inputs["wheel.w"],
                               resources)
        return self._started(model, inputs)

    # _step: DrivelineInputReading (drive_rattle_fmi.boundary)

    def _outputs(self, model):
        return model.outputs()

    _quick_outputs = _outputs  # all cheap, and all read by the mesh every step

    def _model_state(self, model):
        return {"shaft": [model.shaft.state.phi, model.shaft.state.w, model.shaft.tau_load],
                "time": model.time, "last_step": model.last_step,
                "fmi": self._boundary_state(model)}

    def _restore_model_state(self, model, state):
        phi, w, tau = state["shaft"]
        model.shaft.state = ShaftState(phi, w)
        model.shaft.tau_load = tau
        model.time = state["time"]
        model.last_step = state["last_step"]
        self._restore_boundary(model, state["fmi"])
