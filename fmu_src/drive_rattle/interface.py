"""The two units of the system, their inputs and outputs and how they are connected: one
declaration per signal (public name, unit, description, FMI type), the units' names, the one
list of the connections between them, and the inputs' start values.

The FMU slaves register exactly these signals, the modelDescription and the documentation
tables are generated from them, the co-simulation harness, the SSP system and the in-process
twin couple the units by ``CONNECTIONS``, and the build makes one FMU per name of ``MODELS``.
The names are public API: they change only on purpose.  The output values themselves are
computed by the unit models (``WheelStepper.outputs``, ``DrivelineModel.outputs``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import NamedTuple

from .driveline import DrivelineModel, DrivelineParameters
from .geometry import MAX_PAIR_SLOTS
from .parameters import MeshParameters
from .stepper import WheelStepper

#: The units' names: the model identifiers of the FMUs (and their slave classes' names).
MESH, DRIVELINE = "GearMeshRattle", "Driveline"
#: Every unit of the system, in build order.
MODELS = (MESH, DRIVELINE)


@dataclass(frozen=True)
class SignalSpec:
    """Declaration of one input or output."""

    name: str
    unit: str  # SI unit ("1" dimensionless)
    description: str
    fmi_type: str = "Real"  # FMI type: Real or Integer
    display_unit: str | None = None
    start: float = 0.0  # start value of inputs (see coupled_start_inputs)
    minimum: float | None = None  # accepted range of inputs (beyond it doStep refuses)
    maximum: float | None = None

    def check(self, value: float) -> None:
        """Raise ValueError naming the input unless ``value`` is finite and in range."""
        if not math.isfinite(value):
            raise ValueError(
                f"input '{self.name}' = {value!r} is not finite; allowed: finite numbers")
        if (self.minimum is not None and value < self.minimum) or (
                self.maximum is not None and value > self.maximum):
            raise ValueError(
                f"input '{self.name}' = {value!r} is out of range; allowed: "
                f"[{self.minimum:g}, {self.maximum:g}] {self.unit}")


#: Input ranges.  Angles are bounded so that the relative approach of the flanks keeps its
#: precision (at 1e6 rad of pinion rotation the roll coordinate's ulp is 4e-12 m against
#: penetrations of 1e-7 m); speeds, accelerations and torques far beyond any transmission.
ANGLE_RANGE = {"minimum": -1e6, "maximum": 1e6}
SPEED_RANGE = {"minimum": -1e4, "maximum": 1e4}


MESH_INPUTS = (
    SignalSpec("pinion.phi", "rad", "pinion (input-shaft gear) angle, forward positive",
               display_unit="deg", **ANGLE_RANGE),
    SignalSpec("pinion.w", "rad/s", "pinion speed", display_unit="rpm", **SPEED_RANGE),
    SignalSpec("pinion.a", "rad/s2", "pinion angular acceleration (Taylor term inside a step)",
               minimum=-1e7, maximum=1e7),
    SignalSpec("wheel.tau_load", "N.m",
               "resisting torque on the wheel (M_res of eq. 10), positive against forward "
               "rotation", minimum=-1e5, maximum=1e5),
)

MESH_OUTPUTS = (
    SignalSpec("wheel.tau_mesh", "N.m",
               "mesh torque on the wheel averaged over the last step, positive driving it "
               "forward"),
    SignalSpec("pinion.tau_mesh", "N.m",
               "mesh torque on the pinion averaged over the last step (negative while the "
               "pinion drives)"),
    SignalSpec("wheel.phi", "rad", "wheel angle, forward positive", display_unit="deg"),
    SignalSpec("wheel.w", "rad/s", "wheel speed", display_unit="rpm"),
    SignalSpec("mesh.W", "N", "total normal force of the pairs in contact now"),
    SignalSpec("mesh.W_peak", "N", "peak total normal force within the last step"),
    SignalSpec("mesh.F", "N",
               "net flank friction force now, positive when it drives the wheel forward"),
    SignalSpec("mesh.delta", "m", "normal penetration of the flank in contact now, 0 when apart",
               display_unit="um"),
    SignalSpec("mesh.delta_peak", "m", "peak normal penetration within the last step",
               display_unit="um"),
    SignalSpec("mesh.v_impact", "m/s", "normal approach speed at the last contact onset",
               display_unit="mm/s"),
    SignalSpec("mesh.h", "m",
               "film thickness (eq. 11) at the most loaded pair; when apart, the clearance "
               "of the nearer flank plus its eq. 7 delta_max", display_unit="um"),
    SignalSpec("mesh.lambda", "1", "film parameter h/sigma (at mesh.h)"),
    SignalSpec("mesh.psi", "1", "proportion of dry contact psi (at mesh.h)"),
    SignalSpec("mesh.n_contact", "1", "number of tooth pairs in contact now", fmi_type="Integer"),
    SignalSpec("mesh.impacts_drive", "1", "cumulative contact onsets on the drive flank",
               fmi_type="Integer"),
    SignalSpec("mesh.impacts_coast", "1", "cumulative contact onsets on the coast flank",
               fmi_type="Integer"),
    SignalSpec("mesh.transmission_error", "m",
               "dynamic transmission error: the signed rigid-body approach of the flanks along "
               "the tooth normal, cos(beta_b) (r_bp pinion.phi - r_bw wheel.phi), positive when "
               "the pinion leads, 0 at the centre of the backlash", display_unit="um"),
    SignalSpec("mesh.force_tangential", "N",
               "tangential component (pitch circle, wheel's forward direction) of the mesh's "
               "normal force on the wheel now: sum W_i cos(beta_b) cos(alpha_t), signed by "
               "the flank"),
    SignalSpec("mesh.force_radial", "N",
               "radial component of the mesh's normal force on the wheel now, positive pushing "
               "the gears apart: sum W_i cos(beta_b) sin(alpha_t)"),
    SignalSpec("mesh.force_axial", "N",
               "axial component of the mesh's normal force on the wheel now: sum W_i "
               "sin(beta_b), positive in the direction a drive-flank load pushes the wheel"),
    SignalSpec("mesh.impact_energy", "J",
               "kinetic energy of the last contact onset on the tooth normal, "
               "1/2 m_n mesh.v_impact^2 (m_n = wheel.J / (r_bw cos beta_b)^2)"),
    SignalSpec("mesh.rattle_index", "W",
               "rattle index: impact kinetic energy per second, exponentially averaged with "
               "the time constant rattle.time_constant"),
    *(SignalSpec(f"pair[{k}].W", "N",
                 f"normal force of pair slot {k} (tooth pairs numbered in mesh order, slot = "
                 f"number mod {MAX_PAIR_SLOTS}; either flank)")
      for k in range(MAX_PAIR_SLOTS)),
)

DRIVELINE_INPUTS = (
    SignalSpec("wheel.phi", "rad", "wheel angle (from the mesh unit)", display_unit="deg",
               **ANGLE_RANGE),
    SignalSpec("wheel.w", "rad/s", "wheel speed (from the mesh unit)", display_unit="rpm",
               **SPEED_RANGE),
)

DRIVELINE_OUTPUTS = (
    SignalSpec("pinion.phi", "rad", "input-shaft (pinion) angle", display_unit="deg"),
    SignalSpec("pinion.w", "rad/s", "input-shaft (pinion) speed", display_unit="rpm"),
    SignalSpec("pinion.a", "rad/s2", "input-shaft (pinion) angular acceleration"),
    SignalSpec("wheel.tau_load", "N.m",
               "output-shaft torque resisting the wheel, positive against forward rotation"),
    SignalSpec("vehicle.w", "rad/s", "speed of the reflected vehicle inertia",
               display_unit="rpm"),
)


class Connection(NamedTuple):
    """One coupling signal: ``source``'s output feeds ``target``'s input."""

    source: str  # unit
    output: str
    target: str  # unit
    input: str


def _fed_by(target: str, inputs, source: str, outputs) -> tuple[Connection, ...]:
    """Each input of ``target`` fed by the output of the same name of ``source``."""
    names = {s.name for s in outputs}
    missing = [s.name for s in inputs if s.name not in names]
    if missing:
        raise ImportError(f"{target} inputs {missing} have no output of that name in {source}")
    return tuple(Connection(source, s.name, target, s.name) for s in inputs)


#: The coupling of the system: every input of a unit is fed by its partner's output of the
#: same name (Driveline -> mesh: pinion kinematics and load torque; mesh -> Driveline: the
#: wheel's angle and speed).  The one definition, used by the harness, the SSP system, the
#: other masters, the regression kit and the in-process twin.
CONNECTIONS = (_fed_by(MESH, MESH_INPUTS, DRIVELINE, DRIVELINE_OUTPUTS)
               + _fed_by(DRIVELINE, DRIVELINE_INPUTS, MESH, MESH_OUTPUTS))


def inputs_of(unit: str, outputs: dict[str, dict[str, float]]) -> dict[str, float]:
    """The inputs of ``unit`` from the outputs of every unit (``{unit: {output: value}}``)
    along ``CONNECTIONS``."""
    return {c.input: outputs[c.source][c.output] for c in CONNECTIONS if c.target == unit}


# ---------------------------------------------------------------------- input start values
#: Rounds of the start-value exchange before it must have reached its fixed point.
START_EXCHANGE_ROUNDS = 8


def coupled_start_inputs(mesh_params: MeshParameters | None = None,
                         driveline_params: DrivelineParameters | None = None,
                         start_time: float = 0.0) -> tuple[dict[str, float], dict[str, float]]:
    """``(mesh inputs, driveline inputs)`` at ``start_time`` [s] of the coupled system: what
    each unit's partner outputs there once both are initialized (SI units).

    The initialization the co-simulation harness performs, run to its fixed point: the
    Driveline's input-shaft kinematics and load torque (which do not depend on the wheel
    beyond rounding), the mesh's wheel state for them (static flank equilibrium with
    ``init.in_contact``), the Driveline built behind that wheel, until nothing changes.  At
    the fixed point a unit initialized with its inputs at these values outputs exactly its
    partner's values, so masters that exchange nothing during initialization start the pair
    consistent.  These are the inputs' start values of the FMUs for the default parameters."""
    mp = mesh_params or MeshParameters()
    dp = driveline_params or DrivelineParameters()
    wheel = {"wheel.phi": 0.0, "wheel.w": 0.0}
    for _ in range(START_EXCHANGE_ROUNDS):
        drive = DrivelineModel(dp, start_time, wheel["wheel.phi"], wheel["wheel.w"]).outputs()
        mesh_inputs = inputs_of(MESH, {DRIVELINE: drive})
        phi, w = WheelStepper(mp, mesh_inputs["pinion.phi"], mesh_inputs["pinion.w"],
                              mesh_inputs["wheel.tau_load"]).wheel_angle_speed()
        new_wheel = inputs_of(DRIVELINE, {MESH: {"wheel.phi": phi, "wheel.w": w}})
        if new_wheel == wheel:
            return mesh_inputs, wheel
        wheel = new_wheel
    raise ValueError(
        f"the start values of the coupled inputs do not settle within "
        f"{START_EXCHANGE_ROUNDS} exchanges (last wheel state {wheel}); check the parameters")


def _with_starts(signals: tuple[SignalSpec, ...], starts: dict[str, float]):
    return tuple(replace(s, start=starts[s.name]) for s in signals)


# Every input starts at what its partner outputs at t = 0 in the default scenario (computed
# from the core's defaults, never copied: they follow any change of the physics defaults).
_MESH_STARTS, _DRIVELINE_STARTS = coupled_start_inputs()
MESH_INPUTS = _with_starts(MESH_INPUTS, _MESH_STARTS)
DRIVELINE_INPUTS = _with_starts(DRIVELINE_INPUTS, _DRIVELINE_STARTS)
