"""What only FMI 2.0 has, on its faces (the native one and pythonfmu's): the status inquiries
(fmi2Get*Status) -- the last successful time is asked of every face as "the time reached" in
test_glue.py."""

from __future__ import annotations

import ctypes

import pytest

from .calls import last, started
from .conftest import FACES
from .raw_fmi import DO_STEP_STATUS, ERROR, LAST_SUCCESSFUL_TIME, OK, TERMINATED

pytestmark = pytest.mark.parametrize(
    "face", [name for name, face in FACES.items() if face.standard == "2.0"], indirect=True)


def test_status_inquiries(face, mesh):
    """fmi2Terminated reads false; fmi2DoStepStatus is refused (no step is ever pending:
    canRunAsynchronuously = false); a NULL value pointer is refused."""
    inst = started(mesh)
    assert inst.step(0.0, 1e-4) == OK
    value = ctypes.c_int(7)
    assert mesh.lib.fmi2GetBooleanStatus(inst.c, TERMINATED, ctypes.byref(value)) == OK
    assert value.value == 0
    assert mesh.lib.fmi2GetStatus(inst.c, DO_STEP_STATUS, ctypes.byref(value)) == ERROR
    assert last(inst)[2].startswith("fmi2GetStatus: status kind 0 (fmi2DoStepStatus) is not "
                                    "answered here")
    assert mesh.lib.fmi2GetRealStatus(inst.c, LAST_SUCCESSFUL_TIME, None) == ERROR
    inst.free()
