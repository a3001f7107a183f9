"""The native FMUs are the model library under an FMI face: bit for bit the in-process twin
(``drive_rattle_cosim.system.simulate`` and the library's units, which run the same C), the
library's records as their FMU states, the library's statuses and messages verbatim.  Every
float is compared as its hexadecimal text, never with a tolerance: rattle is chaotic, and one
ulp of difference would grow into another impact sequence.

* the coupled system under the fmpy harness against ``system.simulate``, with other contact
  laws, friction forms, dissipation, a free start and a measured speed table;
* the serialized FMU state's payload against the unit's ``rm_save`` record at points of the
  regression inputs, and a restored instance continuing as the original did;
* the committed regression references, packed in the FMU and in the repository.
"""

from __future__ import annotations

import math
import subprocess
import sys

import pytest

from drive_rattle.interface import DRIVELINE, MESH, MODELS
from drive_rattle.parameters import DrivelineParameters, MeshParameters
from drive_rattle.units import Unit
from drive_rattle_cosim.harness import CoSimulation
from drive_rattle_cosim.regression import REFERENCE_ROOT, check
from drive_rattle_cosim.system import SIGNALS, simulate

from ..adversarial.raw_fmi import HEADER, OK, Model, unpack
from .twin import KINDS, bits, input_rows, interface

#: (mesh parameters, driveline parameters) by public name
VARIANTS = {
    "defaults": ({}, {}),
    "the regression scenario: strong order 2": ({}, {"engine.amplitude[1]": 2000.0}),
    "sphere law, apparent-area friction on sliding speed": (
        {"contact.hertz_law": 1, "friction.form": 1, "friction.shear_speed": 1},
        {"engine.amplitude[1]": 2000.0}),
    "spur gears, damping factor, printed friction": (
        {"gear.beta": 0.0, "contact.dissipation": 2, "contact.damping": 300.0,
         "friction.form": 2}, {}),
    "free start, no friction, stiff shaft": (
        {"init.in_contact": False, "wheel.w_start": 40.0, "friction.enabled": False},
        {"shaft.k": 50.0, "pinion.a_over_step": False}),
}
STOP = 0.05  # s: 500 communication steps


def harness_and_twin(native_fmus, mesh: dict, driveline: dict, stop: float):
    """The coupled native pair under the harness and the twin: (result, record)."""
    params = {**{f"{MESH}.{k}": v for k, v in mesh.items()},
              **{f"{DRIVELINE}.{k}": v for k, v in driveline.items()}}
    with CoSimulation(native_fmus[MESH], native_fmus[DRIVELINE], params) as sim:
        result = sim.run(stop)
    record = simulate(MeshParameters.from_public(mesh), DrivelineParameters.from_public(driveline),
                      stop_time=stop)
    return result, record


def assert_same(result, record) -> None:
    assert [t.hex() for t in result.time] == [t.hex() for t in record.time]
    compared = 0
    for qualified, column in result.columns.items():
        name = qualified.partition(".")[2]
        if qualified.startswith(f"{MESH}.") and name not in SIGNALS:
            continue  # the twin records the mesh's outputs and the driveline's
        if name in SIGNALS:
            assert bits([column]) == bits([record.signals[name]]), qualified
            compared += 1
    assert compared >= 30


@pytest.mark.parametrize("variant", list(VARIANTS))
def test_coupled_system_is_the_twin(native_fmus, variant):
    mesh, driveline = VARIANTS[variant]
    result, record = harness_and_twin(native_fmus, mesh, driveline, STOP)
    assert_same(result, record)
    assert result[f"{MESH}.mesh.impacts_drive"][-1] > 0
    assert math.isfinite(result[f"{MESH}.mesh.W_peak"][-1])


def test_coupled_with_a_speed_table_is_the_twin(native_fmus, tmp_path):
    table = tmp_path / "speed run-up.csv"
    rows = [(k * 0.01, 80.0 + 15.0 * math.sin(40.0 * k * 0.01)) for k in range(11)]
    table.write_text("time [s],speed [rad/s]\n" + "".join(f"{t!r},{w!r}\n" for t, w in rows),
                     encoding="utf-8")
    result, record = harness_and_twin(native_fmus, {}, {"engine.speed_table": str(table)}, 0.08)
    assert_same(result, record)


# ------------------------------------------------------------------ FMU states
@pytest.fixture(scope="module")
def unpacked(native_fmus, tmp_path_factory):
    return {name: Model(unpack(fmu, tmp_path_factory.mktemp(f"eq_{name}")))
            for name, fmu in native_fmus.items()}


@pytest.mark.parametrize("model", MODELS)
def test_fmu_states_are_the_library_records(unpacked, native_fmus, model):
    """At points of the regression inputs the serialized state is the envelope (this FMU's
    GUID) around the unit's own record, the twin's rm_save at the same point byte for byte;
    deserialized into a fresh instance it continues as the original did."""
    m = unpacked[model]
    _, guid, names, _ = interface(native_fmus[model])
    rows = input_rows(model)
    inst = m.instantiate(b"original")
    twin = Unit(KINDS[model], initialize=False)
    assert inst.setup(rows[0][0]) == OK and inst.enter() == OK
    twin.call("rm_setup", rows[0][0])
    twin.call("rm_enter_initialization")
    inst.set_named(dict(zip(names, rows[0][1:], strict=True)))
    twin.set(dict(zip(names, rows[0][1:], strict=True)))
    assert inst.exit() == OK
    twin.call("rm_exit_initialization")
    saved = None
    for k in range(len(rows) - 1):
        inputs = dict(zip(names, rows[k][1:], strict=True))
        assert inst.set_named(inputs) == OK
        twin.set(inputs)
        t, h = rows[k][0], rows[k + 1][0] - rows[k][0]
        assert inst.step(t, h) == OK, inst.log[-2:]
        twin.call("rm_do_step", t, h)
        if k % 100 == 0 or k == 250:
            blob = inst.serialized()
            assert blob[32:32 + len(guid)] == guid.encode()
            assert blob[HEADER:] == twin.save(), k
            if k == 250:
                saved, expected_after = blob, []
        if saved is not None and k >= 250:
            expected_after.append(inst.snapshot())
    other = m.instantiate(b"restored")
    status, state = other.deserialize(saved)
    assert status == OK and other.set_state(state) == OK, other.log
    assert other.snapshot() == expected_after[0]
    for k in range(251, len(rows) - 1):
        other.set_named(dict(zip(names, rows[k][1:], strict=True)))
        assert other.step(rows[k][0], rows[k + 1][0] - rows[k][0]) == OK
        assert other.snapshot() == expected_after[k - 250], k
    assert not inst.log and not other.log
    for i in (inst, other):
        i.free()
    twin.close()


# ------------------------------------------------------------------ regression references
@pytest.mark.parametrize("model", MODELS)
def test_regression_references_pass(native_fmus, model):
    for source in (None, REFERENCE_ROOT):  # packed in the FMU, and the committed folder
        checks = check(native_fmus[model], source)
        assert checks and all(c.passed for c in checks), [c for c in checks if not c.passed]


def test_regression_cli(native_fmus):
    run = subprocess.run([sys.executable, "-m", "drive_rattle_cosim.regression", "check",
                          *(str(native_fmus[m]) for m in MODELS)],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout + run.stderr
    assert run.stdout.count(": pass") == 2
