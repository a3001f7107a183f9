"""Parameter declarations: defaults are the reference scenario; invalid sets raise clear errors."""

import math

import pytest

from drive_rattle.parameters import DEG, MeshParameters, specs


def test_defaults_are_the_reference_scenario():
    p = MeshParameters()
    assert (p.z_pinion, p.z_wheel) == (20, 39)
    assert p.m_n == 2.25e-3
    assert math.isclose(p.alpha_n, 20 * DEG) and math.isclose(p.beta, 27.75 * DEG)
    assert (p.b, p.backlash, p.J_wheel) == (25e-3, 0.10e-3, 1.3e-3)
    assert (p.eta, p.sigma) == (0.05, 0.4e-6)


def test_every_parameter_is_fully_declared():
    names = set()
    for attr, spec in specs(MeshParameters):
        assert spec.name not in names, spec.name
        names.add(spec.name)
        assert spec.description and spec.unit is not None, attr
        assert "." in spec.name, "public names are dotted by subsystem"
        spec.check(spec.default)  # the default is within its own limits


@pytest.mark.parametrize(
    "name, value, fragment",
    [
        ("wheel.J", 0.0, "[1e-07, 1000] kg.m2"),
        ("wheel.J", -1.0, "wheel.J"),
        ("gear.m_n", 0.0, "gear.m_n"),
        ("gear.b", -0.01, "gear.b"),
        ("gear.backlash", -1e-5, "[0, 0.005] m"),
        ("gear.beta", 46 * DEG, "gear.beta"),
        ("gear.beta", -0.01, "gear.beta"),
        ("material.nu_pinion", 0.5, "(0, 0.5)"),
        ("material.nu_wheel", 0.0, "material.nu_wheel"),
        ("material.E_pinion", 0.0, "material.E_pinion"),
        ("surface.sigma", 0.0, "surface.sigma"),
        ("surface.gamma", -1.0, "surface.gamma"),
        ("lubricant.eta", 0.0, "lubricant.eta"),
        ("gear.z_pinion", 20.5, "must be an integer"),
        ("friction.form", 3, "one of 0"),
        ("gear.m_n", float("nan"), "must be finite"),
    ],
)
def test_invalid_value_names_parameter_value_and_range(name, value, fragment):
    with pytest.raises(ValueError) as err:
        MeshParameters.from_public({name: value})
    msg = str(err.value)
    assert name in msg and repr(value) in msg and "allowed" in msg
    assert fragment in msg


def test_undercutting_pinion_is_rejected_with_minimum():
    with pytest.raises(ValueError) as err:
        MeshParameters.from_public({"gear.z_pinion": 10, "gear.beta": 0.0})
    msg = str(err.value)
    assert "gear.z_pinion" in msg and "= 10" in msg and "undercut" in msg and ">= 18" in msg


def test_contact_ratio_below_one_is_rejected():
    # Stub teeth on a spur pair: the path of contact is shorter than the base pitch.
    with pytest.raises(ValueError) as err:
        MeshParameters.from_public({"gear.h_a": 0.5, "gear.beta": 0.0})
    assert "eps_alpha = 0.88" in str(err.value) and "gear.h_a = 0.5" in str(err.value)
    assert "allowed: eps_alpha >= 1" in str(err.value)


def test_face_width_needing_too_many_pair_slots_is_rejected():
    with pytest.raises(ValueError) as err:
        MeshParameters.from_public({"gear.b": 0.2})
    assert "gear.b" in str(err.value) and "pair slots" in str(err.value)


def test_unknown_public_name_is_rejected():
    with pytest.raises(ValueError, match="unknown parameter"):
        MeshParameters.from_public({"gear.teeth": 20})


def test_public_round_trip():
    p = MeshParameters()
    assert MeshParameters.from_public(p.to_public()) == p
