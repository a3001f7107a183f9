"""Drive slave classes directly, as an FMI master would, without building an FMU."""

from __future__ import annotations

import sys
from pathlib import Path

SRC = Path(__file__).resolve().parents[2] / "fmu_src"
if str(SRC) not in sys.path:
    sys.path.insert(0, str(SRC))

from Driveline import Driveline  # noqa: E402
from GearMeshRattle import GearMeshRattle  # noqa: E402

SLAVES = {"GearMeshRattle": GearMeshRattle, "Driveline": Driveline}
_RESOURCES: list[str] = []


def kernel_resources() -> str:
    """A resources folder holding drive_rattle/_rattle_kernel.so, compiled once per session,
    so that the slaves run the compiled kernel as they do inside a built FMU."""
    if not _RESOURCES:
        import atexit
        import shutil
        import tempfile

        from drive_rattle.kernel import LIBRARY_NAME
        from drive_rattle_build.kernel import compile_kernel

        folder = Path(tempfile.mkdtemp(prefix="slave_resources_"))
        atexit.register(shutil.rmtree, folder, ignore_errors=True)
        (folder / "drive_rattle").mkdir()
        compile_kernel(folder / "drive_rattle" / LIBRARY_NAME)
        _RESOURCES.append(str(folder))
    return _RESOURCES[0]


class Driven:
    """A slave instance with name-based access and the status channel read back."""

    def __init__(self, cls, name="inst", resources=None):
        self.slave = cls(instance_name=name, resources=resources or kernel_resources())
        self.vr = {v.name: v.value_reference for v in self.slave.vars.values()}
        self.fmi_type = dict(self.slave._fmi_types)

    def status(self) -> tuple[int, str]:
        """(status code, message) reported since the last call; resets the channel like the
        native shim does."""
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

    def initialize(self, start_time=0.0, **inputs):
        self.slave.setup_experiment(start_time)
        self.slave.enter_initialization_mode()
        self.set_named(inputs)
        self.slave.exit_initialization_mode()
        return self.status()

    def step(self, t, h):
        self.slave.do_step(t, h)
        return self.status()
