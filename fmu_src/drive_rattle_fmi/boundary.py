"""How a unit reads inputs that a master holds, or did not exchange during initialization.

Two situations that FMI 2.0 allows and that a co-simulation of this pair must survive:

* **No exchange during initialization** (fmpy's SSP runner, fmu-manipulation-toolbox's
  container, gemseo-fmu, cofmupy): a unit ends initialization on its inputs' start values and
  sees its partner's first outputs only with the first ``fmi2DoStep``.  The start values are
  the default system's (``drive_rattle.interface.coupled_start_inputs``); where the first
  step's inputs differ from the values the unit was initialized with, the parameter
  ``init.settle_first_step`` lets the unit settle its start state against them, as it would
  have done during initialization.
* **Held inputs** (``fmpy simulate X.fmu`` of one unit alone, or any master that leaves an
  input unset): the master sets none of the inputs that carry the partner's motion (an angle
  and its speed) between two steps.  Read literally, a held angle with a non-zero speed moves
  the partner back to the same angle at every communication point, which no shaft does.  With
  ``inputs.continue_when_held`` the unit runs the partner on at constant speed from where the
  last step left it instead (docs/tools.md).

"Set" means an ``fmi2SetReal`` call on the variable, whatever the value: masters that do
drive the inputs call it before every step.
"""

from __future__ import annotations

from drive_rattle.parameters import declare

SETTLE_FIRST_STEP = "init.settle_first_step"
CONTINUE_WHEN_HELD = "inputs.continue_when_held"


def settle_first_step_parameter(what: str):
    """Dataclass field of the Boolean parameter ``init.settle_first_step`` (default true);
    ``what`` says what settling means for the unit."""
    return declare(SETTLE_FIRST_STEP, True, "", what)


def continue_when_held_parameter(what: str):
    """Dataclass field of the Boolean parameter ``inputs.continue_when_held`` (default true)."""
    return declare(CONTINUE_WHEN_HELD, True, "", what)


class HeldInputTracking:
    """Mixin for a RattleSlave subclass (put it first among the bases): remembers whether the
    master set any of ``MOTION_INPUTS`` since the last successful step (since instantiation,
    before the first step)."""

    #: Names of the inputs that carry the partner's motion.
    MOTION_INPUTS: tuple[str, ...] = ()

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._motion_vrs = frozenset(
            v.value_reference for v in self.vars.values() if v.name in self.MOTION_INPUTS)
        self._motion_set = False

    def set_real(self, vrs, values):
        super().set_real(vrs, values)
        if not self._motion_set and not self._motion_vrs.isdisjoint(vrs):
            self._motion_set = True

    def _motion_held(self) -> bool:
        """True when the master set none of the motion inputs since the last step."""
        return not self._motion_set

    def _motion_step_done(self) -> None:
        """Call after a successful step: the next one must be set anew."""
        self._motion_set = False
