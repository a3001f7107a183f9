"""The catalog of units: a parameter found by its qualified name, ``<Unit>.<name>=<value>``
read by the parameter's declared type, a misspelt name answered with the nearest ones."""

import pytest

from drive_rattle.catalog import (
    UNITS,
    check_settings,
    parameter_names,
    parameter_spec,
    parse_setting,
    parse_settings,
)
from drive_rattle.parameters import specs


def test_every_parameter_of_every_unit_is_found_by_its_qualified_name():
    names = parameter_names()
    assert len(names) == len(set(names)) == sum(len(list(specs(u.parameters)))
                                                for u in UNITS.values())
    for qualified in names:
        assert parameter_spec(qualified).name == qualified.split(".", 1)[1]


@pytest.mark.parametrize("text, value", [
    ("GearMeshRattle.gear.backlash=1.2e-4", 1.2e-4),
    ("GearMeshRattle.contact.dissipation=none", 0),
    ("Driveline.vehicle.model=constant_load", 1),
    ("Driveline.pinion.a_over_step=false", False),
    ("Driveline.engine.speed_table=", ""),
])
def test_a_setting_is_read_by_the_declared_type(text, value):
    assert parse_setting(text) == (text.split("=", 1)[0], value)


@pytest.mark.parametrize("text, message", [
    ("GearMeshRattle.gear.backlas=1e-4",
     "unknown parameter 'GearMeshRattle.gear.backlas' (did you mean "
     "GearMeshRattle.gear.backlash"),
    ("gear.backlash=1e-4", "(did you mean GearMeshRattle.gear.backlash?)"),
    ("solver.h_max=1e-5",
     "(did you mean GearMeshRattle.solver.h_max or Driveline.solver.h_max?)"),
    ("Gearbox.gear.backlash=1e-4", "allowed: <Unit>.<name> with Unit one of"),
    ("GearMeshRattle.mesh.W=1", "'GearMeshRattle.mesh.W' is an output of GearMeshRattle, "
     "not a parameter"),
    ("GearMeshRattle.engine.w_mean=80", "(did you mean Driveline.engine.w_mean?)"),
    ("=0x10", "setting '=0x10' is not NAME=VALUE"),
    ("GearMeshRattle.gear.backlash", "is not NAME=VALUE"),
])
def test_a_setting_of_no_parameter_is_refused_with_the_nearest_names(text, message):
    with pytest.raises(ValueError) as err:
        parse_setting(text)
    assert message in str(err.value)


def test_settings_are_one_per_parameter_and_checked_by_the_library():
    with pytest.raises(ValueError, match=r"'Driveline\.shaft\.k' is set twice"):
        parse_settings(["Driveline.shaft.k=1", "Driveline.shaft.k=2"])
    check_settings(parse_settings(["Driveline.shaft.k=1", "GearMeshRattle.gear.b=0.02"]))
    with pytest.raises(ValueError, match=r"'shaft\.k' = -1 is out of range"):
        check_settings({"Driveline.shaft.k": -1.0})
