"""GearMeshRattle: the gear-mesh impact and flank-friction model (Theodossiades et al. 2008) as
an FMI 2.0 co-simulation slave.  Thin: the physics is drive_rattle, the FMI glue
drive_rattle_fmi; this module only maps the two."""

from dataclasses import dataclass
from pathlib import Path

from drive_rattle.interface import MESH_INPUTS, MESH_OUTPUTS, mesh_outputs
from drive_rattle.kernel import LIBRARY_NAME, CompiledWheelStepper, load_kernel
from drive_rattle.parameters import MeshParameters
from drive_rattle.stepper import StepResult, WheelState, WheelStepper
from drive_rattle_fmi.boundary import (
    HeldInputTracking,
    continue_when_held_parameter,
    settle_first_step_parameter,
)
from drive_rattle_fmi.slave import WARNING, RattleSlave


@dataclass(frozen=True)
class GearMeshRattleParameters(MeshParameters):
    """The physics parameters, and how the unit reads its inputs (drive_rattle_fmi.boundary)."""

    settle_first_step: bool = settle_first_step_parameter(
        "when the pinion inputs or wheel.tau_load of the first doStep differ from those at the "
        "end of initialization (a master that exchanges no values during initialization), "
        "first settle the wheel in the static flank equilibrium for them, as init.in_contact "
        "does at initialization (only with init.in_contact); false = step from the "
        "initialized wheel state")
    continue_when_held: bool = continue_when_held_parameter(
        "when the master set none of pinion.phi, pinion.w, pinion.a since the last step (it "
        "holds them, e.g. fmpy simulate of this FMU alone), the pinion runs on at constant "
        "speed from where the last step left it (at the first step: from pinion.phi at "
        "pinion.w; pinion.a unused); false = take held values literally (the pinion jumps "
        "back to the held angle at every step)")


class GearMeshRattle(HeldInputTracking, RattleSlave):
    """Helical gear mesh with backlash: Hertzian impacts of every tooth pair on both flanks and
    mixed boundary/viscous flank friction; pinion kinematics in, wheel motion and torques out."""

    description = (
        "Transmission drive rattle: gear-mesh impact (Hertz, every tooth pair, both flanks) and "
        "flank friction of a helical pair with backlash; kinematic pinion, wheel integrated "
        "inside (Theodossiades, Rahnejat, De la Cruz, Kelly, ENOC 2008)")
    PARAMETERS = GearMeshRattleParameters
    INPUTS = MESH_INPUTS
    OUTPUTS = MESH_OUTPUTS
    MOTION_INPUTS = ("pinion.phi", "pinion.w", "pinion.a")

    def _build(self, params, inputs):
        model = self._new_stepper(
            params, inputs["pinion.phi"], inputs["pinion.w"], inputs["wheel.tau_load"])
        # What the first step compares its inputs with (init.settle_first_step).
        model.fmi_initial_inputs = (inputs["pinion.phi"], inputs["pinion.w"],
                                    inputs["wheel.tau_load"])
        model.fmi_first_step = True
        return model

    def _new_stepper(self, params, phi_p, w_p, tau_load):
        if params.compiled:
            # This FMU's own kernel (the drive_rattle package in sys.modules may come from
            # another FMU of the process, whose folder the host may have deleted).
            lib = load_kernel(Path(self.resources or ".") / "drive_rattle" / LIBRARY_NAME)
            lib = lib or load_kernel()
            if lib is not None:
                return CompiledWheelStepper(params, phi_p, w_p, tau_load, library=lib)
            self._report(WARNING, "the compiled kernel is not available here: running the "
                                  "pure-Python core (same results, slower)")
        return WheelStepper(params, phi_p, w_p, tau_load)

    def _step(self, t, h, inputs):
        model = self._model
        p = model.params
        phi_p, w_p, a_p = inputs["pinion.phi"], inputs["pinion.w"], inputs["pinion.a"]
        tau_load = inputs["wheel.tau_load"]
        if p.continue_when_held and self._motion_held():
            (phi_p, w_p), a_p = model.pinion, 0.0
        settled = None
        if (model.fmi_first_step and p.settle_first_step and p.init_in_contact
                and (phi_p, w_p, tau_load) != model.fmi_initial_inputs):
            settled = self._settle(model, phi_p, w_p, tau_load)
        try:
            model.step(h, phi_p, w_p, a_p, tau_load)
        except Exception as err:
            if settled is not None:  # a rejected step leaves the unit as it was
                model.state, model.pinion = settled
            advised = self.DEFAULT_EXPERIMENT["stepSize"]
            if isinstance(err, ValueError) and h > advised:
                raise ValueError(
                    f"{err}. The communication step {h!r} s is {h / advised:.3g} times the "
                    f"default experiment's: use {advised!r} s (docs/tools.md: accuracy "
                    "against the step)") from None
            raise
        model.fmi_first_step = False
        self._motion_step_done()
        if settled is not None:
            self._report(WARNING, (
                "doStep at the first step: the inputs (pinion.phi = {!r} rad, pinion.w = {!r} "
                "rad/s, wheel.tau_load = {!r} N.m) differ from those at the end of "
                "initialization ({!r}, {!r}, {!r}): the wheel was settled in the flank "
                "equilibrium for them first (init.settle_first_step; a master that exchanges "
                "no values during initialization)").format(
                    phi_p, w_p, tau_load, *model.fmi_initial_inputs))

    @staticmethod
    def _settle(model, phi_p, w_p, tau_load):
        """Put the wheel in the flank equilibrium for these inputs; returns what it replaced
        (ValueError, with nothing changed, when there is no equilibrium)."""
        before = (WheelState(*model.state.as_tuple()), model.pinion)
        model.state = model.equilibrium_state(phi_p, w_p, tau_load)
        model.pinion = (phi_p, w_p)
        return before

    def _outputs(self, model):
        if isinstance(model, CompiledWheelStepper):
            return model.outputs()
        return mesh_outputs(model)

    def _quick_outputs(self, model):
        if isinstance(model, CompiledWheelStepper):
            phi, w = model.wheel_angle_speed()
        else:
            phi, w = model.state.phi, model.state.w
        return {"wheel.phi": phi, "wheel.w": w}

    def _model_state(self, model):
        last = model.last
        return {
            "wheel": list(model.state.as_tuple()),
            "pinion": list(model.pinion),
            "last": [last.tau_wheel_mean, last.tau_pinion_mean, last.W_peak, last.delta_peak,
                     last.onsets_drive, last.onsets_coast],
            "fmi": {"initial_inputs": list(model.fmi_initial_inputs),
                    "first_step": model.fmi_first_step},
        }

    def _restore_model_state(self, model, state):
        model.state = WheelState.from_tuple(state["wheel"])
        model.pinion = tuple(state["pinion"])
        tw, tp, wp, dp, nd, nc = state["last"]
        model.last = StepResult(tw, tp, wp, dp, int(nd), int(nc))
        fmi = state["fmi"]
        model.fmi_initial_inputs = tuple(fmi["initial_inputs"])
        model.fmi_first_step = bool(fmi["first_step"])
