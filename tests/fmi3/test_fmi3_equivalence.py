"""The FMI 3.0 FMUs are the model library under its FMI 3.0 face: in fmpy they give the FMI 2.0
native face's numbers bit for bit -- each FMU alone on the committed regression inputs, the
pair coupled in the harness in the paper scenario (and with other contact laws, friction
readings and dissipation, set through the Enumerations); their FMU states are the library's
records (tests/faces/test_states.py).
Every float is compared as its hexadecimal text, never with a tolerance: rattle is chaotic, and
one ulp of difference would grow into another impact sequence."""

from __future__ import annotations

import pytest

from drive_rattle.interface import DRIVELINE, MESH, MODELS
from drive_rattle_cosim.harness import CoSimulation

from ..faces.hosts import run_fmpy
from ..native.twin import bits, input_rows, interface, twin_run

#: (mesh parameters, driveline parameters) by public name; the integer codes go through
#: fmi3SetInt64 (Enumerations) in FMI 3.0 and fmi2SetInteger in FMI 2.0
VARIANTS = {
    "paper scenario (defaults)": ({}, {}),
    "regression scenario: strong order 2": ({}, {"engine.amplitude[1]": 2000.0}),
    "sphere law, apparent-area friction on sliding speed": (
        {"contact.hertz_law": 1, "friction.form": 1, "friction.shear_speed": 1},
        {"engine.amplitude[1]": 2000.0}),
    "spur gears, damping factor, printed friction, free start": (
        {"gear.beta": 0.0, "contact.dissipation": 2, "contact.damping": 300.0,
         "friction.form": 2, "init.in_contact": False, "wheel.w_start": 40.0}, {}),
}
STOP = 0.05  # s: 500 communication steps
#: the paper scenario over a longer horizon (5000 steps)
STOPS = {"paper scenario (defaults)": 0.5}


@pytest.mark.parametrize("model", MODELS)
def test_alone_in_fmpy_is_the_fmi2_face(fmi3_fmus, native_fmus, model):
    """On the committed regression inputs (500 steps of 0.1 ms), every output at every point
    equals the FMI 2.0 native FMU's under the same calls in fmpy (the harness's unit drives
    both), and the library's own unit driven by them."""
    rows = input_rows(model)
    table = run_fmpy(fmi3_fmus[model], rows)
    assert len(table) == len(rows) == 501
    assert bits(table) == bits(run_fmpy(native_fmus[model], rows))
    names = interface(native_fmus[model])[2]
    assert bits(table) == bits(twin_run(model, rows, names))


@pytest.mark.parametrize("variant", list(VARIANTS))
def test_coupled_pair_is_the_fmi2_face(fmi3_fmus, native_fmus, variant):
    """The FMI 3.0 pair and the FMI 2.0 native pair under the harness (one loop, an adapter
    per standard): every output of both units at every point, bit for bit."""
    mesh, driveline = VARIANTS[variant]
    params = {**{f"{MESH}.{k}": v for k, v in mesh.items()},
              **{f"{DRIVELINE}.{k}": v for k, v in driveline.items()}}
    stop = STOPS.get(variant, STOP)
    with CoSimulation(fmi3_fmus[MESH], fmi3_fmus[DRIVELINE], params) as pair:
        assert all(u.fmi_version == "3.0" for u in pair.units.values())
        mine = pair.run(stop)
        assert not [m for u in pair.units.values() for m in u.messages]
    with CoSimulation(native_fmus[MESH], native_fmus[DRIVELINE], params) as sim:
        reference = sim.run(stop)
    assert [t.hex() for t in mine.time] == [t.hex() for t in reference.time]
    assert len(mine.time) == round(stop / 1e-4) + 1
    assert set(mine.columns) == set(reference.columns) and len(mine.columns) >= 35
    for name, column in reference.columns.items():
        assert bits([mine[name]]) == bits([column]), name
    assert mine[f"{MESH}.mesh.impacts_drive"][-1] > 0


# ------------------------------------------------------------------ FMU states
