"""Driveline: the simple driveline around the gear mesh as an FMI 2.0 co-simulation slave --
input-shaft kinematics from engine orders or a measured speed table, and the output shaft to
the reflected vehicle inertia.  Thin: physics in drive_rattle, FMI glue in drive_rattle_fmi."""

from dataclasses import dataclass
from pathlib import Path

from drive_rattle.driveline import Driveline as DrivelineModel
from drive_rattle.driveline import DrivelineParameters, OutputShaft, ShaftState
from drive_rattle.interface import DRIVELINE_INPUTS, DRIVELINE_OUTPUTS
from drive_rattle_fmi.boundary import (
    HeldInputTracking,
    continue_when_held_parameter,
    settle_first_step_parameter,
)
from drive_rattle_fmi.slave import WARNING, RattleSlave


@dataclass(frozen=True)
class DrivelineUnitParameters(DrivelineParameters):
    """The driveline's parameters, and how the unit reads its inputs
    (drive_rattle_fmi.boundary)."""

    settle_first_step: bool = settle_first_step_parameter(
        "when wheel.phi or wheel.w of the first doStep differ from those at the end of "
        "initialization (a master that exchanges no values during initialization), first "
        "start the output shaft anew in steady state behind them, as at initialization; "
        "false = step from the initialized shaft")
    continue_when_held: bool = continue_when_held_parameter(
        "when the master set neither wheel.phi nor wheel.w since the last step (it holds "
        "them, e.g. fmpy simulate of this FMU alone), the wheel runs on at constant speed "
        "from where the last step left it (at the first step: from wheel.phi at wheel.w); "
        "false = take held values literally (the wheel jumps back to the held angle at every "
        "step)")


class Driveline(HeldInputTracking, RattleSlave):
    """Engine-order (or measured) pinion kinematics out; wheel angle and speed in, output-shaft
    load torque out."""

    description = (
        "Driveline around the drive-rattle gear mesh: input-shaft kinematics from engine orders "
        "or a measured speed table, output shaft as a torsional spring-damper to a reflected "
        "vehicle inertia with drag")
    PARAMETERS = DrivelineUnitParameters
    INPUTS = DRIVELINE_INPUTS
    OUTPUTS = DRIVELINE_OUTPUTS
    MOTION_INPUTS = ("wheel.phi", "wheel.w")

    def _build(self, params, inputs):
        resources = Path(self.resources) if self.resources else None
        wheel = (inputs["wheel.phi"], inputs["wheel.w"])
        model = DrivelineModel(params, self._start_time, *wheel, resources)
        model.fmi_initial_inputs = wheel  # compared with the first step's
        model.fmi_first_step = True
        model.fmi_wheel_end = wheel  # where the wheel runs on from when the inputs are held
        return model

    def _step(self, t, h, inputs):
        model = self._model
        p = model.params
        phi_w, w_w = inputs["wheel.phi"], inputs["wheel.w"]
        if p.continue_when_held and self._motion_held():
            phi_w, w_w = model.fmi_wheel_end
        settled = None
        if (model.fmi_first_step and p.settle_first_step
                and (phi_w, w_w) != model.fmi_initial_inputs):
            settled, model.shaft = model.shaft, OutputShaft(p, phi_w, w_w)
        try:
            model.step(t, h, phi_w, w_w)
        except Exception:
            if settled is not None:  # a rejected step leaves the unit as it was
                model.shaft = settled
            raise
        # The output shaft moves the wheel at its step-start speed within a step.
        model.fmi_wheel_end = (phi_w + w_w * h, w_w)
        model.fmi_first_step = False
        self._motion_step_done()
        if settled is not None:
            self._report(WARNING, (
                "doStep at the first step: the inputs (wheel.phi = {!r} rad, wheel.w = {!r} "
                "rad/s) differ from those at the end of initialization ({!r}, {!r}): the "
                "output shaft was started anew in steady state behind them "
                "(init.settle_first_step; a master that exchanges no values during "
                "initialization)").format(phi_w, w_w, *model.fmi_initial_inputs))

    def _outputs(self, model):
        return model.outputs()

    _quick_outputs = _outputs  # all cheap, and all read by the mesh every step

    def _model_state(self, model):
        return {"shaft": [model.shaft.state.phi, model.shaft.state.w, model.shaft.tau_load],
                "time": model.time, "last_step": model.last_step,
                "fmi": {"initial_inputs": list(model.fmi_initial_inputs),
                        "first_step": model.fmi_first_step,
                        "wheel_end": list(model.fmi_wheel_end)}}

    def _restore_model_state(self, model, state):
        phi, w, tau = state["shaft"]
        model.shaft.state = ShaftState(phi, w)
        model.shaft.tau_load = tau
        model.time = state["time"]
        model.last_step = state["last_step"]
        fmi = state["fmi"]
        model.fmi_initial_inputs = tuple(fmi["initial_inputs"])
        model.fmi_first_step = bool(fmi["first_step"])
        model.fmi_wheel_end = tuple(fmi["wheel_end"])
