"""Every face is the model library under an FMI face, bit for bit: alone in fmpy on the
committed regression inputs (the harness's unit, and fmpy's simulate_fmu) and coupled under the
harness (with other contact laws, friction forms, dissipation, free starts, a stiff shaft, a
measured speed table),
every output at every point equals the library's (its unit driven by the same calls;
``drive_rattle_cosim.system.simulate``, the in-process coupled system) and the native FMI 2.0
face's.  Every float is compared as its hexadecimal text, never with a tolerance: rattle is
chaotic, and one ulp of difference would grow into another impact sequence."""

from __future__ import annotations

import functools
import math

import pytest

from drive_rattle.interface import DRIVELINE, MESH, MODELS
from drive_rattle.parameters import DrivelineParameters, MeshParameters
from drive_rattle_cosim.harness import CoSimulation
from drive_rattle_cosim.regression import REFERENCE_ROOT, read_opt, simulate_on_inputs
from drive_rattle_cosim.system import SIGNALS, simulate

from .hosts import run_fmpy
from .twin import bits, input_rows, interface, twin_run


@pytest.mark.parametrize("model", MODELS)
def test_alone_in_fmpy_is_the_library(face, face_fmus, native_fmus, model):
    """On the committed regression inputs (500 steps of 0.1 ms) every output at every point is
    the library's unit's under the same calls (the harness's unit drives the FMU), and fmpy's
    simulate_fmu gives the native FMI 2.0 face's table bit for bit."""
    rows = input_rows(model)
    table = run_fmpy(face_fmus[model], rows)
    assert len(table) == len(rows) == 501
    assert bits(table) == bits(twin_run(model, rows, interface(face_fmus[model])[2]))
    from fmpy.util import read_csv

    folder = REFERENCE_ROOT / model
    inputs, opt = read_csv(str(folder / f"{model}_in.csv")), read_opt(folder / f"{model}_ref.opt")
    mine = simulate_on_inputs(face_fmus[model], inputs, opt)
    native = simulate_on_inputs(native_fmus[model], inputs, opt)
    assert mine.dtype.names == native.dtype.names and len(mine) == len(native) > 100
    for name in mine.dtype.names:
        # bit for bit: the float64 patterns, not a tolerance
        assert mine[name].astype(float).tobytes() == native[name].astype(float).tobytes(), name


#: (mesh parameters, driveline parameters) by public name; the integer codes go through
#: fmi2SetInteger in FMI 2.0 and fmi3SetInt64 (Enumerations) in FMI 3.0
VARIANTS = {
    "paper scenario (defaults)": ({}, {}),
    "regression scenario: strong order 2": ({}, {"engine.amplitude[1]": 2000.0}),
    "sphere law, apparent-area friction on sliding speed": (
        {"contact.hertz_law": 1, "friction.form": 1, "friction.shear_speed": 1},
        {"engine.amplitude[1]": 2000.0}),
    "spur gears, damping factor, printed friction": (
        {"gear.beta": 0.0, "contact.dissipation": 2, "contact.damping": 300.0,
         "friction.form": 2}, {}),
    "spur gears, damping factor, printed friction, free start": (
        {"gear.beta": 0.0, "contact.dissipation": 2, "contact.damping": 300.0,
         "friction.form": 2, "init.in_contact": False, "wheel.w_start": 40.0}, {}),
    "free start, no friction, stiff shaft": (
        {"init.in_contact": False, "wheel.w_start": 40.0, "friction.enabled": False},
        {"shaft.k": 50.0, "pinion.a_over_step": False}),
}
STOP = 0.05  # s: 500 communication steps
#: the paper scenario over a longer horizon (5000 steps)
STOPS = {"paper scenario (defaults)": 0.5}


def coupled(fmus, mesh: dict, driveline: dict, stop: float):
    """The pair of ``fmus`` coupled under the harness with these parameters: the result, and
    every message the units logged."""
    params = {**{f"{MESH}.{k}": v for k, v in mesh.items()},
              **{f"{DRIVELINE}.{k}": v for k, v in driveline.items()}}
    with CoSimulation(fmus[MESH], fmus[DRIVELINE], params) as pair:
        result = pair.run(stop)
        return result, [m for u in pair.units.values() for m in u.messages]


def library(mesh: dict, driveline: dict, stop: float):
    """The in-process coupled system (the same C as every face)."""
    return simulate(MeshParameters.from_public(mesh), DrivelineParameters.from_public(driveline),
                    stop_time=stop)


@functools.cache
def library_variant(variant: str):
    return library(*VARIANTS[variant], STOPS.get(variant, STOP))


def assert_is_the_library(result, record) -> None:
    """Every signal the library records, at every point, bit for bit."""
    assert [t.hex() for t in result.time] == [t.hex() for t in record.time]
    compared = 0
    for qualified, column in result.columns.items():
        name = qualified.partition(".")[2]
        if qualified.startswith(f"{MESH}.") and name not in SIGNALS:
            continue  # the library records the mesh's outputs and the driveline's
        if name in SIGNALS:
            assert bits([column]) == bits([record.signals[name]]), qualified
            compared += 1
    assert compared >= 30


@pytest.mark.parametrize("variant", list(VARIANTS))
def test_coupled_pair_is_the_library(face, face_fmus, native_fmus, variant):
    stop = STOPS.get(variant, STOP)
    result, messages = coupled(face_fmus, *VARIANTS[variant], stop)
    assert not messages, messages
    assert_is_the_library(result, library_variant(variant))
    assert len(result.time) == round(stop / 1e-4) + 1
    if face.name != "native":  # every column, also those the library does not record
        reference, _ = coupled(native_fmus, *VARIANTS[variant], stop)
        assert set(result.columns) == set(reference.columns) and len(result.columns) >= 35
        for name, column in reference.columns.items():
            assert bits([result[name]]) == bits([column]), name
    assert result[f"{MESH}.mesh.impacts_drive"][-1] > 0
    assert math.isfinite(result[f"{MESH}.mesh.W_peak"][-1])


def test_coupled_with_a_speed_table_is_the_library(face, face_fmus, tmp_path):
    """The engine's speed from a measured table (a file named by a String parameter)."""
    table = tmp_path / "speed run-up.csv"
    rows = [(k * 0.01, 80.0 + 15.0 * math.sin(40.0 * k * 0.01)) for k in range(11)]
    table.write_text("time [s],speed [rad/s]\n" + "".join(f"{t!r},{w!r}\n" for t, w in rows),
                     encoding="utf-8")
    driveline = {"engine.speed_table": str(table)}
    result, _ = coupled(face_fmus, {}, driveline, 0.08)
    assert_is_the_library(result, library({}, driveline, 0.08))
