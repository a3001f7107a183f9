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
  input unset or constant): the inputs that carry the partner's motion (an angle and its
  speed) do not change between two steps.  Read literally, a held angle with a non-zero speed moves
  the partner back to the same angle at every communication point, which no shaft does.  With
  ``inputs.continue_when_held`` the unit runs the partner on at constant speed from where the
  last step left it instead (docs/tools.md).

"Held" means: no ``fmi2SetReal`` on any of these inputs since the last step (since
instantiation, at the first step), or all of them set to exactly the values of the last step.
A partner that moves changes its angle at every step, so a coupled run is never held.

The units' parameter classes and the stepping logic live here, not in the slave modules:
pythonfmu executes the slave module anew at every ``fmi2Instantiate`` and what it defines stays
alive (a dataclass defined there was measured to keep about 30 kiB per instantiation;
tests/adversarial/test_endurance.py), while this module is imported once per process.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from pythonfmu.enums import Fmi2Status

from drive_rattle.driveline import DrivelineParameters
from drive_rattle.parameters import MeshParameters, declare
from drive_rattle.snapshots import check_fields

SETTLE_FIRST_STEP = "init.settle_first_step"
CONTINUE_WHEN_HELD = "inputs.continue_when_held"


def settle_first_step_parameter(what: str):
    """Dataclass field of the Boolean parameter ``init.settle_first_step`` (default true);
    ``what`` says what settling means for the unit."""
    return declare(SETTLE_FIRST_STEP, True, "", what)


def continue_when_held_parameter(what: str):
    """Dataclass field of the Boolean parameter ``inputs.continue_when_held`` (default true)."""
    return declare(CONTINUE_WHEN_HELD, True, "", what)


@dataclass(frozen=True)
class MeshUnitParameters(MeshParameters):
    """The physics parameters, and how the unit reads its inputs (drive_rattle_fmi.boundary)."""

    settle_first_step: bool = settle_first_step_parameter(
        "when the pinion inputs or wheel.tau_load of the first doStep differ from those at the "
        "end of initialization (a master that exchanges no values during initialization), "
        "first settle the wheel in the static flank equilibrium for them, as init.in_contact "
        "does at initialization (only with init.in_contact); false = step from the "
        "initialized wheel state")
    continue_when_held: bool = continue_when_held_parameter(
        "when the master holds pinion.phi, pinion.w, pinion.a (set none of them since the "
        "last step, or set the last step's values again; e.g. fmpy simulate of this FMU "
        "alone), the pinion runs on at constant "
        "speed from where the last step left it (at the first step: from pinion.phi at "
        "pinion.w; pinion.a unused); false = take held values literally (the pinion jumps "
        "back to the held angle at every step)")


@dataclass(frozen=True)
class DrivelineUnitParameters(DrivelineParameters):
    """The driveline's parameters, and how the unit reads its inputs
    (drive_rattle_fmi.boundary)."""

    settle_first_step: bool = settle_first_step_parameter(
        "when wheel.phi or wheel.w of the first doStep differ from those at the end of "
        "initialization (a master that exchanges no values during initialization), first "
        "start the output shaft anew in steady state behind them, as at initialization; "
        "false = step from the initialized shaft")
    continue_when_held: bool = continue_when_held_parameter(
        "when the master holds wheel.phi and wheel.w (set neither since the last step, or "
        "set the last step's values again; e.g. fmpy simulate of this FMU alone), the wheel "
        "runs on at constant speed "
        "from where the last step left it (at the first step: from wheel.phi at wheel.w); "
        "false = take held values literally (the wheel jumps back to the held angle at every "
        "step)")


class HeldInputTracking:
    """Mixin for a RattleSlave subclass (put it first among the bases): tells whether the
    master holds ``MOTION_INPUTS``: set none of them since the last successful step (since
    instantiation, before the first step), or set them to exactly the values of the last
    step.  The model carries those values (``fmi_last_motion``, None before the first step)."""

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

    def _motion_values(self) -> tuple:
        return tuple(self._values[name] for name in self.MOTION_INPUTS)

    def _motion_held(self) -> bool:
        """True when the master holds the motion inputs (see the class)."""
        last = getattr(self._model, "fmi_last_motion", None)
        return not self._motion_set or (last is not None and self._motion_values() == last)

    def _motion_step_done(self) -> None:
        """Call after a successful step."""
        self._model.fmi_last_motion = self._motion_values()
        self._motion_set = False


#: The entry of a model snapshot (``RattleSlave._model_state``) that holds how the unit reads
#: its inputs; the others are the unit model's own snapshot (``to_json``).
BOUNDARY_KEY = "fmi"


class _InputReading(HeldInputTracking):
    """The first step's settling and the held inputs, for a unit whose ``_build`` ends with
    ``return self._started(model, inputs)``, and the model snapshot of its FMU states: the unit
    model's own (``SNAPSHOT.to_json`` of ``model.snapshot()``) with ``_boundary_state``."""

    #: Inputs whose values at the end of initialization the first step compares with.
    START_INPUTS: tuple[str, ...] = ()
    #: check_fields layout of a subclass' own entries in ``_boundary_state``.
    _EXTRA_BOUNDARY_LAYOUT: ClassVar[dict] = {}
    #: The snapshot type of the unit model (``to_json`` / ``from_json``).
    SNAPSHOT: ClassVar[type] = None

    def _model_state(self, model) -> dict:
        return {**model.snapshot().to_json(), BOUNDARY_KEY: self._boundary_state(model)}

    def _model_from_snapshot(self, params, start_time: float, data):
        if not isinstance(data, dict) or BOUNDARY_KEY not in data:
            got = sorted(data) if isinstance(data, dict) else type(data).__name__
            raise ValueError(f"model snapshot has entries {got}, expected the model's and "
                             f"{BOUNDARY_KEY!r}")
        own = {key: value for key, value in data.items() if key != BOUNDARY_KEY}
        model = self._restored_model(params, start_time, self.SNAPSHOT.from_json(own))
        self._restore_boundary(model, data[BOUNDARY_KEY])
        return model

    def _restored_model(self, params, start_time: float, snapshot):
        """The unit model in the saved ``snapshot`` (``from_snapshot``: nothing solved)."""
        raise NotImplementedError

    def _started(self, model, inputs: dict):
        model.fmi_initial_inputs = tuple(inputs[name] for name in self.START_INPUTS)
        model.fmi_first_step = True
        model.fmi_last_motion = None
        return model

    @staticmethod
    def _boundary_state(model) -> dict:
        last = model.fmi_last_motion
        return {"initial_inputs": list(model.fmi_initial_inputs),
                "first_step": model.fmi_first_step,
                "last_motion": None if last is None else list(last)}

    @classmethod
    def _restore_boundary(cls, model, state) -> None:
        """Load a ``_boundary_state`` snapshot into ``model`` (ValueError if malformed)."""
        layout = {"initial_inputs": ("f",) * len(cls.START_INPUTS), "first_step": ("any",),
                  "last_motion": ("any",), **cls._EXTRA_BOUNDARY_LAYOUT}
        s = check_fields(state, layout)
        if not isinstance(s["first_step"], bool):
            raise ValueError(f"model snapshot first_step = {s['first_step']!r}: expected a "
                             "boolean")
        last = s["last_motion"]
        if last is not None:
            check_fields({"last_motion": last}, {"last_motion": ("f",) * len(cls.MOTION_INPUTS)})
        model.fmi_initial_inputs = tuple(s["initial_inputs"])
        model.fmi_first_step = s["first_step"]
        model.fmi_last_motion = None if last is None else tuple(last)

    def _first_step_differs(self, model, values: tuple) -> bool:
        return model.fmi_first_step and model.params.settle_first_step and (
            values != model.fmi_initial_inputs)

    def _settled_warning(self, model, values: tuple, what: str) -> None:
        units = {spec.name: spec.unit for spec in self.INPUTS}
        given = ", ".join(f"{n} = {v!r} {units[n]}"
                          for n, v in zip(self.START_INPUTS, values, strict=True))
        self._report(Fmi2Status.warning, (
            f"doStep at the first step: the inputs ({given}) differ from those at the end of "
            f"initialization {model.fmi_initial_inputs!r}: {what} "
            "(init.settle_first_step; a master that exchanges no values during "
            "initialization)"))


class MeshInputReading(_InputReading):
    """GearMeshRattle's step: held pinion inputs run on, a first step on other inputs than
    initialization's settles the wheel first, and a step refused beyond the default
    experiment's step names the step to use."""

    MOTION_INPUTS = ("pinion.phi", "pinion.w", "pinion.a")
    START_INPUTS = ("pinion.phi", "pinion.w", "wheel.tau_load")

    def _step(self, t, h, inputs):
        model = self._model
        p = model.params
        phi_p, w_p, a_p = inputs["pinion.phi"], inputs["pinion.w"], inputs["pinion.a"]
        tau_load = inputs["wheel.tau_load"]
        if p.continue_when_held and self._motion_held():
            (phi_p, w_p), a_p = model.pinion, 0.0
        settled = None
        if p.init_in_contact and self._first_step_differs(model, (phi_p, w_p, tau_load)):
            start = model.start_snapshot(phi_p, w_p, tau_load)  # ValueError: no equilibrium
            settled = model.snapshot()
            model.restore(start)
        try:
            model.step(h, phi_p, w_p, a_p, tau_load)
        except Exception as err:
            if settled is not None:  # a rejected step leaves the unit as it was
                model.restore(settled)
            advised = self.DEFAULT_EXPERIMENT["stepSize"]
            if isinstance(err, ValueError) and h > advised and "h_comm_max" not in str(err):
                raise ValueError(
                    f"{err}. The communication step {h!r} s is {h / advised:.3g} times the "
                    f"default experiment's: use {advised!r} s (docs/tools.md: accuracy "
                    "against the step)") from None
            raise
        model.fmi_first_step = False
        self._motion_step_done()
        if settled is not None:
            self._settled_warning(model, (phi_p, w_p, tau_load),
                                  "the wheel was settled in the flank equilibrium for them first")


class DrivelineInputReading(_InputReading):
    """The Driveline's step: a held wheel runs on, a first step on another wheel than
    initialization's starts the output shaft anew behind it."""

    MOTION_INPUTS = ("wheel.phi", "wheel.w")
    START_INPUTS = ("wheel.phi", "wheel.w")

    def _started(self, model, inputs: dict):
        # where the wheel runs on from when the inputs are held
        model.fmi_wheel_end = (inputs["wheel.phi"], inputs["wheel.w"])
        return super()._started(model, inputs)

    @staticmethod
    def _boundary_state(model) -> dict:
        return {**_InputReading._boundary_state(model), "wheel_end": list(model.fmi_wheel_end)}

    _EXTRA_BOUNDARY_LAYOUT: ClassVar[dict] = {"wheel_end": ("f", "f")}

    @classmethod
    def _restore_boundary(cls, model, state) -> None:
        super()._restore_boundary(model, state)
        model.fmi_wheel_end = tuple(state["wheel_end"])

    def _step(self, t, h, inputs):
        model = self._model
        p = model.params
        phi_w, w_w = inputs["wheel.phi"], inputs["wheel.w"]
        if p.continue_when_held and self._motion_held():
            phi_w, w_w = model.fmi_wheel_end
        settled = None
        if self._first_step_differs(model, (phi_w, w_w)):
            start = model.start_snapshot(phi_w, w_w)
            settled = model.snapshot()
            model.restore(start)
        try:
            model.step(h, phi_w, w_w, t=t)
        except Exception:
            if settled is not None:  # a rejected step leaves the unit as it was
                model.restore(settled)
            raise
        # The output shaft moves the wheel at its step-start speed within a step.
        model.fmi_wheel_end = (phi_w + w_w * h, w_w)
        model.fmi_first_step = False
        self._motion_step_done()
        if settled is not None:
            self._settled_warning(model, (phi_w, w_w),
                                  "the output shaft was started anew in steady state behind them")
