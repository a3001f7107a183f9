"""GearMeshRattle: the gear-mesh impact and flank-friction model (Theodossiades et al. 2008) as
an FMI 2.0 co-simulation slave.  Thin: the physics is drive_rattle, the FMI glue
drive_rattle_fmi; this module only maps the two."""

from pathlib import Path

from drive_rattle.interface import MESH_INPUTS, MESH_OUTPUTS, mesh_outputs
from drive_rattle.kernel import LIBRARY_NAME, CompiledWheelStepper, load_kernel
from drive_rattle.stepper import StepResult, WheelState, WheelStepper
from drive_rattle_fmi.boundary import MeshInputReading, MeshUnitParameters
from drive_rattle_fmi.slave import WARNING, RattleSlave, check_snapshot_fields

#: The model snapshot of an FMU state (check_snapshot_fields layout): WheelState.as_tuple(),
#: the pinion's angle and speed, the last step's aggregates, and how the unit reads its inputs
#: (drive_rattle_fmi.boundary, checked there).
SNAPSHOT_LAYOUT = {
    "wheel": ("f", "f", "flank", "f", "f", "f", "n", "n", "f+"),
    "pinion": ("f", "f"),
    "last": ("f", "f", "f+", "f+", "n", "n"),
    "fmi": ("any",),
}


class GearMeshRattle(MeshInputReading, RattleSlave):
    """Helical gear mesh with backlash: Hertzian impacts of every tooth pair on both flanks and
    mixed boundary/viscous flank friction; pinion kinematics in, wheel motion and torques out."""

    description = (
        "Transmission drive rattle: gear-mesh impact (Hertz, every tooth pair, both flanks) and "
        "flank friction of a helical pair with backlash; kinematic pinion, wheel integrated "
        "inside (Theodossiades, Rahnejat, De la Cruz, Kelly, ENOC 2008)")
    PARAMETERS = MeshUnitParameters
    INPUTS = MESH_INPUTS
    OUTPUTS = MESH_OUTPUTS

    def _kernel(self, params):
        """The compiled kernel library if the parameters ask for it and it loads, else None
        (reported as a warning)."""
        if not params.compiled:
            return None
        # This FMU's own kernel (the drive_rattle package in sys.modules may come from
        # another FMU of the process, whose folder the host may have deleted).
        lib = load_kernel(Path(self.resources or ".") / "drive_rattle" / LIBRARY_NAME)
        lib = lib or load_kernel()
        if lib is None:
            self._report(WARNING, "the compiled kernel is not available here: running the "
                                  "pure-Python core (same results, slower)")
        return lib

    def _build(self, params, inputs):
        args = (params, inputs["pinion.phi"], inputs["pinion.w"], inputs["wheel.tau_load"])
        lib = self._kernel(params)
        if lib is not None:
            return self._started(CompiledWheelStepper(*args, library=lib), inputs)
        return self._started(WheelStepper(*args), inputs)

    # _step: MeshInputReading (drive_rattle_fmi.boundary)

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
            "fmi": self._boundary_state(model),
        }

    def _model_from_snapshot(self, params, start_time, snapshot):
        s = check_snapshot_fields(snapshot, SNAPSHOT_LAYOUT)
        args = (params, WheelState.from_tuple(s["wheel"]), tuple(s["pinion"]),
                StepResult(*s["last"]))
        lib = self._kernel(params)
        if lib is not None:
            model = CompiledWheelStepper.from_snapshot(*args, library=lib)
        else:
            model = WheelStepper.from_snapshot(*args)
        self._restore_boundary(model, s["fmi"])
        return model
