"""GearMeshRattle: the gear-mesh impact and flank-friction model (Theodossiades et al. 2008) as
an FMI 2.0 co-simulation slave.  Thin: the physics is drive_rattle, the FMI glue
drive_rattle_fmi; this module only maps the two."""

from pathlib import Path

from pythonfmu.enums import Fmi2Status

from drive_rattle.interface import MESH_INPUTS, MESH_OUTPUTS
from drive_rattle.kernel import LIBRARY_NAME, CompiledWheelStepper, load_kernel
from drive_rattle.stepper import WheelSnapshot, WheelStepper
from drive_rattle_fmi.boundary import MeshInputReading, MeshUnitParameters
from drive_rattle_fmi.slave import RattleSlave


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
    SNAPSHOT = WheelSnapshot

    def _stepper(self, params) -> tuple[type, dict]:
        """The wheel stepper class and its options: the compiled kernel if the parameters ask
        for it and it loads, else the pure-Python core (reported as a warning)."""
        if params.compiled:
            # This FMU's own kernel (the drive_rattle package in sys.modules may come from
            # another FMU of the process, whose folder the host may have deleted).
            lib = load_kernel(Path(self.resources or ".") / "drive_rattle" / LIBRARY_NAME)
            lib = lib or load_kernel()
            if lib is not None:
                return CompiledWheelStepper, {"library": lib}
            self._report(Fmi2Status.warning, "the compiled kernel is not available here: "
                                             "running the pure-Python core (same results, slower)")
        return WheelStepper, {}

    def _build(self, params, inputs):
        cls, options = self._stepper(params)
        model = cls(params, inputs["pinion.phi"], inputs["pinion.w"], inputs["wheel.tau_load"],
                    **options)
        return self._started(model, inputs)

    def _restored_model(self, params, start_time, snapshot):
        cls, options = self._stepper(params)
        return cls.from_snapshot(params, snapshot, **options)

    # _step: MeshInputReading (drive_rattle_fmi.boundary)

    def _outputs(self, model):
        return model.outputs()

    def _quick_outputs(self, model):
        phi, w = model.wheel_angle_speed()
        return {"wheel.phi": phi, "wheel.w": w}
