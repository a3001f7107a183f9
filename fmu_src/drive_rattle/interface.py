"""The two units of the system, their inputs and outputs and how they are connected: one
declaration per signal (public name, unit, description, FMI type), the units' names, the one
list of the connections between them, and the inputs' start values.

The model library's C tables, the FMU slaves' registration, the modelDescription and the
documentation tables are generated from them; the co-simulation harness, the SSP system and the
in-process twin couple the units by ``CONNECTIONS``, and the build makes one FMU per name of
``MODELS``.  The names are public API: they change only on purpose.  The values are computed
by the model library; the inputs' start values too (``units.input_starts``: what the partner
outputs at t = 0 in the default system).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

#: The units' names: the model identifiers of the FMUs (and their slave classes' names).
MESH, DRIVELINE = "GearMeshRattle", "Driveline"
#: Every unit of the system, in build order.
MODELS = (MESH, DRIVELINE)
#: The units' default experiment: the communication step every master should use (accuracy
#: against the step: docs/tools.md), and the horizon of a run of one unit alone.
DEFAULT_EXPERIMENT = {"startTime": 0.0, "stopTime": 2.0, "stepSize": 1e-4}
#: Pair slots of the mesh's outputs pair[k].W: tooth pairs are numbered in mesh order and a
#: pair's slot is its number modulo this (a geometry needing more slots is refused).
MAX_PAIR_SLOTS = 8


@dataclass(frozen=True)
class SignalSpec:
    """Declaration of one input or output (an input's range is checked by the model library
    at every step: beyond it doStep refuses)."""

    name: str
    unit: str  # SI unit ("1" dimensionless)
    description: str
    fmi_type: str = "Real"  # FMI type: Real or Integer
    display_unit: str | None = None
    minimum: float | None = None  # accepted range of inputs
    maximum: float | None = None

    def allowed(self) -> str:
        """The accepted range of an input, as the messages say it."""
        return f"[{self.minimum:g}, {self.maximum:g}] {self.unit}"


#: Input ranges (and those of the start angles and speeds and of a speed table's speeds).
#: Angles are bounded so that the relative approach of the flanks keeps its precision (at
#: 1e6 rad of pinion rotation the roll coordinate's ulp is 4e-12 m against penetrations of
#: 1e-7 m); speeds, accelerations and torques far beyond any transmission.
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


class FlangeMember(NamedTuple):
    """One variable of a shaft's flange: its member name (``phi``, ``w``, ``a``, ``tau``, as
    the Modelica Standard Library's rotational signal adaptors for FMUs name angle, speed,
    acceleration and torque), the unit's variable, and how a connection treats it (FMI 3.0's
    ``variableKind``): ``signal`` (equal on both sides), or for the torque, which sums to zero
    at a connection, ``inflow`` (positive: the torque on the unit through the flange, in its
    forward direction) or ``outflow`` (positive: the opposite)."""

    member: str
    variable: str
    kind: str = "signal"


class Flange(NamedTuple):
    """A shaft's flange of a unit: where a driveline tool would connect it (an FMI 3.0
    terminal, docs/fmi3.md)."""

    unit: str
    name: str
    description: str
    members: tuple[FlangeMember, ...]


def _flange(unit: str, name: str, description: str, *members: tuple[str, ...]) -> Flange:
    """A flange of ``unit`` whose members are the unit's inputs or outputs; ImportError if one
    is not."""
    signals = {s.name for s in {MESH: MESH_INPUTS + MESH_OUTPUTS,
                                DRIVELINE: DRIVELINE_INPUTS + DRIVELINE_OUTPUTS}[unit]}
    flange = Flange(unit, name, description, tuple(FlangeMember(*m) for m in members))
    missing = [m.variable for m in flange.members if m.variable not in signals]
    if missing:
        raise ImportError(f"flange {unit}.{name}: {missing} are not signals of {unit}")
    return flange


#: The shafts' flanges of each unit, one per shaft the unit meets.  Torques: the mesh's
#: pinion.tau_mesh is the torque the mesh puts on the pinion, so the torque on the mesh through
#: that flange is -pinion.tau_mesh (outflow); wheel.tau_load resists the wheel, so it is the
#: torque on the mesh through the wheel's flange with the sign reversed (outflow) and, by
#: reaction, the torque on the Driveline's output shaft (inflow).  The Driveline drives the
#: input shaft by its kinematics alone, so its pinion flange has no torque; the mesh has no
#: wheel acceleration.  Matched by member name, the flanges of the two units give CONNECTIONS.
FLANGES = (
    _flange(MESH, "pinion", "the pinion's flange on the input shaft: the pinion's motion in, "
            "the mesh torque on the pinion out",
            ("phi", "pinion.phi"), ("w", "pinion.w"), ("a", "pinion.a"),
            ("tau", "pinion.tau_mesh", "outflow")),
    _flange(MESH, "wheel", "the wheel's flange on the output shaft: the wheel's motion out, "
            "the output shaft's resisting torque in",
            ("phi", "wheel.phi"), ("w", "wheel.w"), ("tau", "wheel.tau_load", "outflow")),
    _flange(DRIVELINE, "pinion", "the input shaft's flange at the pinion: its motion out",
            ("phi", "pinion.phi"), ("w", "pinion.w"), ("a", "pinion.a")),
    _flange(DRIVELINE, "wheel", "the output shaft's flange at the wheel: the wheel's motion "
            "in, the output shaft's torque on the wheel out",
            ("phi", "wheel.phi"), ("w", "wheel.w"), ("tau", "wheel.tau_load", "inflow")),
)


def inputs_of(unit: str, outputs: dict[str, dict[str, float]]) -> dict[str, float]:
    """The inputs of ``unit`` from the outputs of every unit (``{unit: {output: value}}``)
    along ``CONNECTIONS``."""
    return {c.input: outputs[c.source][c.output] for c in CONNECTIONS if c.target == unit}
