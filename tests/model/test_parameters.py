"""Parameter declarations and their validation by the model library: the defaults are the
reference scenario, every parameter is fully declared, and an invalid set is refused with a
message naming the parameter, its value and what is allowed."""

import math
import re

import pytest

from drive_rattle import DrivelineParameters, MeshParameters, ModelError
from drive_rattle.library import DRIVELINE, MESH
from drive_rattle.parameters import DEG, specs
from drive_rattle.units import check_parameters


def test_defaults_are_the_reference_scenario():
    p = MeshParameters()
    assert (p.z_pinion, p.z_wheel) == (20, 39)
    assert p.m_n == 2.25e-3
    assert math.isclose(p.alpha_n, 20 * DEG) and math.isclose(p.beta, 27.75 * DEG)
    assert (p.b, p.backlash, p.J_wheel) == (25e-3, 0.10e-3, 1.3e-3)
    assert (p.eta, p.sigma) == (0.05, 0.4e-6)
    d = DrivelineParameters()
    assert d.w_mean == pytest.approx(830 * 2 * math.pi / 60)
    assert [(k, a) for k, a, _ in d.order_terms()] == [(2.0, 300.0), (4.0, 200.0), (6.0, 150.0)]


def test_the_defaults_are_crowned_smooth_point_contacts():
    p = MeshParameters()
    assert (p.contact_geometry, p.roughness) == (0, 0)


@pytest.mark.parametrize("cls", [MeshParameters, DrivelineParameters])
def test_every_parameter_is_fully_declared(cls):
    names = set()
    for attr, spec in specs(cls):
        assert spec.name not in names, spec.name
        names.add(spec.name)
        assert spec.description and spec.unit is not None, attr
        assert "." in spec.name, "public names are dotted by subsystem"
    check_parameters(cls.KIND, {})  # the defaults are within their own limits


def value_in(message: str, name: str) -> float:
    """The value the message gives for ``name`` ("... 'name' = <value> ...")."""
    found = re.search(re.escape(name) + r"'? = (\S+?)[;,]? ", message)
    assert found, message
    return float(found.group(1))


@pytest.mark.parametrize(
    "name, value, allowed",
    [
        ("wheel.J", 0.0, "[1e-07, 1000] kg.m2"),
        ("wheel.J", -1.0, "[1e-07, 1000] kg.m2"),
        ("gear.m_n", 0.0, "[0.0001, 0.1] m"),
        ("gear.b", -0.01, "[0.001, 1] m"),
        ("gear.backlash", -1e-5, "[0, 0.005] m"),
        ("gear.beta", 46 * DEG, "[0, 0.785398] rad"),
        ("gear.beta", -0.01, "[0, 0.785398] rad"),
        ("gear.z_pinion", 4, "[5, 400]"),
        ("material.nu_pinion", 0.51, "[0, 0.5]"),
        ("material.E_pinion", 0.0, "[1e+08, 1e+13] Pa"),
        ("surface.sigma", 0.0, "[1e-09, 0.001] m"),
        ("surface.gamma", -1.0, "[1e-07, 1] m"),
        ("lubricant.eta", 0.0, "[1e-05, 1000] Pa.s"),
        ("contact.restitution", 0.0, "[0.01, 1]"),
        ("friction.form", 3, "one of 0"),
        ("gear.m_n", math.nan, "[0.0001, 0.1] m"),
        ("solver.h_max", math.inf, "[1e-08, 0.01] s"),
    ],
)
def test_a_value_out_of_range_names_parameter_value_and_range(name, value, allowed):
    with pytest.raises(ModelError) as err:
        MeshParameters.from_public({name: value})
    message = str(err.value)
    assert message.startswith("checkParameters: ")
    assert f"'{name}'" in message and f"allowed: {allowed}" in message
    got = value_in(message, name)
    assert got == value or (math.isnan(value) and math.isnan(got))


@pytest.mark.parametrize("name, value, allowed", [
    ("engine.w_mean", 0.5, "[1, 2000] rad/s"),
    ("engine.order[1]", 0.0, "[0.1, 100]"),
    ("shaft.k", 0.0, "[0.001, 1e+09] N.m/rad"),
    ("vehicle.J", 1e7, "[1e-06, 1e+06] kg.m2"),
])
def test_driveline_values_out_of_range_are_named_too(name, value, allowed):
    with pytest.raises(ModelError) as err:
        DrivelineParameters.from_public({name: value})
    message = str(err.value)
    assert f"'{name}'" in message and f"allowed: {allowed}" in message
    assert value_in(message, name) == value


def test_the_library_checks_what_the_specs_declare():
    # Each Real parameter with limits: just beyond each limit refused, the limit itself
    # accepted (unless exclusive) -- the generated tables and the specs agree.
    for cls in (MeshParameters, DrivelineParameters):
        for _, spec in specs(cls):
            if spec.fmi_type != "Real":
                continue
            for limit, outward, exclusive in ((spec.minimum, -1, spec.min_exclusive),
                                              (spec.maximum, 1, spec.max_exclusive)):
                if limit is None:
                    continue
                beyond = limit + outward * max(abs(limit), 1e-300) * 1e-9
                with pytest.raises(ModelError, match=re.escape(f"'{spec.name}'")):
                    check_parameters(cls.KIND, {spec.name: beyond})
                if not exclusive:
                    try:
                        check_parameters(cls.KIND, {spec.name: limit})
                    except ModelError as err:  # only a combination check may refuse a limit
                        assert f"'{spec.name}' = " not in str(err) or "out of range" not in \
                            str(err), str(err)


def test_wrong_types_and_unknown_names_are_refused_by_the_specs():
    with pytest.raises(ValueError, match=r"'gear\.z_pinion' = 20\.5 must be an integer"):
        MeshParameters.from_public({"gear.z_pinion": 20.5})
    with pytest.raises(ValueError, match="unknown parameter"):
        MeshParameters.from_public({"gear.teeth": 20})


@pytest.mark.parametrize("cls", [MeshParameters, DrivelineParameters])
def test_public_round_trip(cls):
    p = cls()
    assert cls.from_public(p.to_public()) == p


@pytest.mark.parametrize("kind", [MESH, DRIVELINE])
def test_check_parameters_refuses_an_unknown_name(kind):
    with pytest.raises(ModelError, match="unknown variable"):
        check_parameters(kind, {"no.such": 1.0})


def spec_of(cls, name):
    return next(spec for _, spec in specs(cls) if spec.name == name)


@pytest.mark.parametrize("cls, name, text, value", [
    (MeshParameters, "gear.backlash", "1.2e-4", 1.2e-4),
    (MeshParameters, "gear.backlash", " 0 ", 0.0),
    (MeshParameters, "gear.z_pinion", "20", 20),
    (MeshParameters, "gear.z_pinion", "2e1", 20),
    (MeshParameters, "friction.enabled", "false", False),
    (MeshParameters, "friction.enabled", "TRUE", True),
    (MeshParameters, "friction.enabled", "1", True),
    (MeshParameters, "contact.dissipation", "2", 2),
    # every item name of every enumeration gives its code
    *((MeshParameters, spec.name, item, code) for _, spec in specs(MeshParameters)
      if spec.choice_names for code, item in spec.choice_names.items()),
    *((DrivelineParameters, spec.name, item, code) for _, spec in specs(DrivelineParameters)
      if spec.choice_names for code, item in spec.choice_names.items()),
    (DrivelineParameters, "engine.speed_table", "", ""),
    (DrivelineParameters, "engine.speed_table", " a b.csv", " a b.csv"),
])
def test_a_text_is_read_by_the_declared_type(cls, name, text, value):
    parsed = spec_of(cls, name).parse(text)
    assert parsed == value and type(parsed) is type(value)


@pytest.mark.parametrize("name, text, message", [
    ("gear.backlash", "", "'gear.backlash' = '' is not a number; allowed: [0, 0.005] m"),
    ("gear.backlash", "0x10", "= '0x10' is not a number"),
    ("gear.z_pinion", "20.5", "= '20.5' is not a whole number; allowed: [5, 400]"),
    ("gear.z_pinion", "nan", "= 'nan' is not a whole number"),
    ("friction.enabled", "maybe", "= 'maybe' is not a truth value; allowed: true or false"),
    ("contact.dissipation", "None",
     "= 'None' is neither a code nor an item name of the enumeration (did you mean 'none'?); "
     "allowed: 0 or 'none', 1 or 'hunt_crossley_restitution'"),
    ("contact.dissipation", "2.5", "neither a code nor an item name"),
])
def test_a_text_that_is_not_of_the_declared_type_is_refused(name, text, message):
    with pytest.raises(ValueError) as err:
        spec_of(MeshParameters, name).parse(text)
    assert message in str(err.value)
