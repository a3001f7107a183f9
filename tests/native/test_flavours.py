"""The two flavours are one model: the pythonfmu FMUs and the native FMUs, both on the model
library, give every output on the regression inputs bit for bit alike, and save the same
state (the library's record) after the same calls.  Their answers to bad calls are compared
case by case in tests/adversarial/test_fmi_bad_input.py."""

from __future__ import annotations

import ctypes

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from fmpy.util import read_csv

from drive_rattle.interface import MODELS
from drive_rattle_cosim.regression import REFERENCE_ROOT, read_opt, simulate_on_inputs

#: Bytes of the serialized state's envelope before the record (rattle_fmi_common.h): it holds
#: the FMU's GUID, which differs between the flavours.
ENVELOPE = 96


def _inputs(model: str) -> tuple[np.ndarray, dict]:
    folder = REFERENCE_ROOT / model
    return read_csv(str(folder / f"{model}_in.csv")), read_opt(folder / f"{model}_ref.opt")


@pytest.mark.parametrize("model", MODELS)
def test_outputs_on_the_regression_inputs_are_identical(fmus, native_fmus, model):
    inputs, opt = _inputs(model)
    python = simulate_on_inputs(fmus[model], inputs, opt)
    native = simulate_on_inputs(native_fmus[model], inputs, opt)
    assert python.dtype.names == native.dtype.names and len(python) == len(native) > 100
    for name in python.dtype.names:
        # bit for bit: the float64 patterns, not a tolerance (rattle amplifies one ulp)
        assert python[name].astype(float).tobytes() == native[name].astype(float).tobytes(), name


def _record_after_steps(fmu, steps: int, h: float, tmp_path) -> bytes:
    md = read_model_description(str(fmu))
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu), str(tmp_path)),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="flavours")
    slave.instantiate()
    try:
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        for k in range(steps):
            slave.doStep(currentCommunicationPoint=k * h, communicationStepSize=h)
        state = slave.getFMUstate()
        blob = bytes(slave.serializeFMUstate(state))
        slave.freeFMUstate(state)
    finally:
        slave.terminate()
        slave.freeInstance()
    return blob


@pytest.mark.parametrize("model", MODELS)
def test_states_hold_the_same_record(fmus, native_fmus, model, tmp_path):
    python = _record_after_steps(fmus[model], 200, 1e-4, tmp_path / "python")
    native = _record_after_steps(native_fmus[model], 200, 1e-4, tmp_path / "native")
    assert python[:8] == native[:8] == b"RTLSTSER"
    assert python[ENVELOPE:] == native[ENVELOPE:]
    assert python[32:ENVELOPE] != native[32:ENVELOPE]  # the GUIDs: each flavour its own
    assert ctypes.c_uint64.from_buffer_copy(python[16:24]).value == len(python) - ENVELOPE
