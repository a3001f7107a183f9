"""Driveline: the simple driveline around the gear mesh as an FMI 2.0 co-simulation slave --
input-shaft kinematics from engine orders or a measured speed table, and the output shaft to
the reflected vehicle inertia.  Thin: physics in drive_rattle, FMI glue in drive_rattle_fmi."""

from pathlib import Path

from drive_rattle.driveline import (
    DrivelineModel,
    DrivelineSnapshot,
    read_speed_table,
    resolve_speed_table,
)
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
    SNAPSHOT = DrivelineSnapshot

    def _build(self, params, inputs):
        model = DrivelineModel(params, self._start_time, inputs["wheel.phi"], inputs["wheel.w"],
                               table=self._speed_table(params))
        return self._started(model, inputs)

    def _restored_model(self, params, start_time, snapshot):
        return DrivelineModel.from_snapshot(params, start_time, snapshot)

    def _speed_table(self, params):
        """The speed table the parameters name, read once per file name (initialization mode
        builds the model on every output read); None for engine orders."""
        if not params.speed_table:
            return None
        cached = getattr(self, "_table_cache", None)
        if cached is None or cached[0] != params.speed_table:
            resources = Path(self.resources) if self.resources else None
            table = read_speed_table(resolve_speed_table(params.speed_table, resources))
            self._table_cache = cached = (params.speed_table, table)
        return cached[1]

    # _step: DrivelineInputReading (drive_rattle_fmi.boundary)

    def _outputs(self, model):
        return model.outputs()

    _quick_outputs = _outputs  # all cheap, and all read by the mesh every step
