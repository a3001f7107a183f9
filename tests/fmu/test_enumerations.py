"""Integer codes as FMI 2.0 enumerations: every integer parameter with ``choices`` in the specs
is declared ``<Enumeration declaredType=...>`` with a ``<SimpleType>`` whose items are the
codes, named by short identifiers, described by the specs' text; both flavours accept them by
number through ``fmi2SetInteger`` (as FMI 2.0 sets an enumeration), in fmpy's ``simulate_fmu``
as ``start_values``."""

import re

import pytest
from fmpy import read_model_description, simulate_fmu

from drive_rattle import MESH, MeshParameters, MeshUnit, input_starts
from drive_rattle.catalog import UNITS
from drive_rattle.parameters import ParameterSpec, specs
from drive_rattle_build.model_description import enumeration
from drive_rattle_cosim.harness import steps_between, time_grid


def coded(model):
    return [spec for _, spec in specs(UNITS[model].parameters) if spec.choices]


@pytest.mark.parametrize("model", ["GearMeshRattle", "Driveline"])
def test_every_integer_code_is_an_enumeration(flavour_fmus, model):
    md = read_model_description(str(flavour_fmus[model]))
    variables = {v.name: v for v in md.modelVariables}
    types = {t.name: t for t in md.typeDefinitions}
    for spec in coded(model):
        v = variables[spec.name]
        assert v.type == "Enumeration" and v.declaredType.name in types, spec.name
        items = v.declaredType.items
        assert [int(i.value) for i in items] == sorted(spec.choices)
        assert [i.description for i in items] == [spec.choices[k] for k in sorted(spec.choices)]
        names = [i.name for i in items]
        assert len(set(names)) == len(names)
        assert all(re.fullmatch(r"[a-z][a-z0-9_]*", n) for n in names), names
        assert int(v.start) == spec.default
    # nothing else became one: the counts and tooth numbers stay Integers
    others = {v.name for v in md.modelVariables if v.type == "Enumeration"}
    assert others == {s.name for s in coded(model)}
    assert model != "GearMeshRattle" or variables["gear.z_pinion"].type == "Integer"


def test_the_names_come_from_the_specs():
    """The item names are the specs' ``choice_names`` (one source for both FMI versions)."""
    by_name = {s.name: s for model in UNITS for s in coded(model)}
    for spec in by_name.values():
        e = enumeration(spec)
        assert [(i.name, i.value) for i in e.items] == sorted(
            ((spec.choice_names[k], k) for k in spec.choices), key=lambda x: x[1])
    assert [i.name for i in enumeration(by_name["contact.hertz_law"]).items] == [
        "exact_elliptical", "equivalent_sphere"]
    assert enumeration(by_name["contact.hertz_law"]).type_name == "ContactHertzLaw"


def test_a_spec_without_a_name_for_every_code_is_refused():
    with pytest.raises(ValueError, match="choice_names"):
        ParameterSpec("load.model", 0, "1", "driveline load", minimum=0, maximum=1,
                      choices={0: "constant torque", 1: "viscous"}, choice_names={0: "constant"})
    with pytest.raises(ValueError, match="choice_names"):
        ParameterSpec("load.model", 0, "1", "driveline load", minimum=0, maximum=1,
                      choices={0: "constant torque", 1: "viscous"},
                      choice_names={0: "Constant torque", 1: "viscous"})


def test_fmpy_sets_an_enumeration_by_number(flavour_fmus):
    """``simulate_fmu(start_values={"contact.dissipation": 0})``: the run is the library's
    with that code, bit for bit (fmpy sets an Enumeration with fmi2SetInteger)."""
    stop, step = 0.01, 1e-4
    rows = simulate_fmu(str(flavour_fmus["GearMeshRattle"]), stop_time=stop, output_interval=step,
                        start_values={"contact.dissipation": 0, "friction.form": 2},
                        output=["wheel.w", "mesh.W"])
    starts = input_starts(MESH)
    unit = MeshUnit(MeshParameters(dissipation=0, friction_form=2), starts["pinion.phi"],
                    starts["pinion.w"], starts["wheel.tau_load"], starts["pinion.a"])
    assert unit.get(["contact.dissipation"])["contact.dissipation"] == 0
    phi, w = starts["pinion.phi"], starts["pinion.w"]
    times = list(rows["time"])  # fmpy's points, and its steps between them
    assert times == pytest.approx(time_grid(0.0, step, stop, "fmpy")[0], rel=1e-12)
    sizes = steps_between(times)
    wheel = [unit.outputs()["wheel.w"]]
    for h in sizes:
        unit.step(h, phi, w, 0.0, starts["wheel.tau_load"])  # held: runs on at its speed
        phi += w * h
        wheel.append(unit.outputs()["wheel.w"])
    assert list(rows["wheel.w"]) == wheel
