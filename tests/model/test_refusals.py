"""refusals.c, the physics' refusals worded once for every face: a step the stepper cannot
resolve is refused with its reason, and the unit is left as it was."""

import pytest

from drive_rattle import ModelError

from .helpers import H, approach_unit


def test_too_stiff_a_contact_is_refused_with_the_unit_unchanged():
    # The lightest legal wheel at the largest damping and 2 m/s: the contact's time scale is
    # far below a nanosecond; the step is refused, not silently wrong.
    unit = approach_unit(2.0, dissipation=2, damping=1000.0, J_wheel=1e-7)
    before, outputs = unit.save(), unit.outputs()
    with pytest.raises(ModelError, match="too stiff to resolve"):
        unit.call("rm_do_step", unit.time, H)
    assert unit.save() == before and unit.outputs() == outputs
