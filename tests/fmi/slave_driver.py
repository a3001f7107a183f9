"""Drive the slave classes directly, as an FMI master would, without building an FMU."""

from __future__ import annotations

import sys
from pathlib import Path

SRC = Path(__file__).resolve().parents[2] / "fmu_src" / "slaves"
if str(SRC) not in sys.path:
    sys.path.insert(0, str(SRC))

from Driveline import Driveline  # noqa: E402
from GearMeshRattle import GearMeshRattle  # noqa: E402

SLAVES = {"GearMeshRattle": GearMeshRattle, "Driveline": Driveline}


class Driven:
    """A slave instance with name-based access and the status channel read back (the model
    library built in place: ``drive-rattle-build --library``)."""

    def __init__(self, cls, name="inst", resources=None):
        self.slave = cls(instance_name=name, resources=resources)
        self.vr = {v.name: v.value_reference for v in self.slave.vars.values()}
        self.fmi_type = dict(self.slave._fmi_types)

    def status(self) -> tuple[int, str]:
        """(status code, message) reported since the last call; resets the channel like the
        status shim does."""
        code = self.slave._fmi_status.value
        msg = self.slave._fmi_message if code else ""
        self.slave._fmi_status.value = 0
        return code, msg

    def set(self, **values):
        for key, value in values.items():
            name = key.replace("__", ".")
            setter = getattr(self.slave, f"set_{self.fmi_type[name].lower()}")
            setter([self.vr[name]], [value])

    def set_named(self, values: dict):
        for name, value in values.items():
            getattr(self.slave, f"set_{self.fmi_type[name].lower()}")([self.vr[name]], [value])

    def get(self, name):
        return getattr(self.slave, f"get_{self.fmi_type[name].lower()}")([self.vr[name]])[0]

    def state(self) -> bytes:
        """The FMU state (the model library's record) as bytes."""
        return self.slave._fmu_state_to_bytes(self.slave._get_fmu_state())

    def phase(self) -> str:
        from drive_rattle.library import PHASES

        return PHASES[self.slave._lib.rm_phase(self.slave._unit)]

    def initialize(self, start_time=0.0, **inputs):
        self.slave.setup_experiment(start_time)
        self.slave.enter_initialization_mode()
        self.set_named(inputs)
        self.slave.exit_initialization_mode()
        return self.status()

    def step(self, t, h):
        self.slave.do_step(t, h)
        return self.status()
