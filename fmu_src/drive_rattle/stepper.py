"""Advances the wheel across one communication step (paper eq. 10) with located contact events.

Inside a step the pinion follows the Taylor polynomial of its step-start inputs,

    phi_p(t) = phi_p0 + w_p0 t + a_p t^2 / 2,

and the load torque is held.  The wheel alternates between two modes:

* **free flight** (no flank in contact): the wheel's acceleration is constant, so the normal
  approach is a quadratic in time; the next contact onset is its exact root (no substeps);
* **contact** on one flank: classical RK4 on substeps of a fixed grid ``t_j = j H / n``
  (``n = ceil(H / h_max)``), split wherever a pair enters or leaves the zone of action or its
  contact point changes its law of motion (kinematic, exact), subdivided where the contact's
  own time scales (sqrt(m/k) of its stiffness, m/c of its damping) are shorter than the grid,
  and ended at the release or at a friction reversal (a pair's sliding speed changing sign at
  the pitch point), both located by Brent's method on the RK4 step from the substep start (so
  the events are consistent with the integrator).  Between reversals each pair's friction
  keeps its direction, so the right-hand side is smooth on every substep.

A flank exactly touching (zero penetration) and moving into contact -- or at rest and being
accelerated into it -- is a contact onset (exact touch).

Every time inside the step is a grid point ``j H / n`` or a located event offset from one;
no time is accumulated across substeps or steps.  A rejected step (non-finite input,
non-positive step, a contact too stiff to resolve) raises ValueError before anything is
changed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from typing import ClassVar, NamedTuple

from . import lubrication, roots
from .geometry import COAST, DRIVE, MAX_PAIR_SLOTS
from .mesh import MeshLoads, MeshModel
from .parameters import MeshParameters
from .snapshots import check_fields

#: Largest flank penetration [m] accepted in a start state given by wheel.phi_start: ten
#: times the penetrations of loaded operation; more means a wheel angle that does not match the
#: pinion's (the teeth would start deep inside each other).
MAX_INITIAL_PENETRATION = 10e-6

#: The static flank equilibrium of the start (init.in_contact): the first penetration [m]
#: tried as the upper end of the bracket (doubled until it brackets), the largest penetration
#: [m] searched, and the tolerance [m] of Brent's method on it.
EQUILIBRIUM_FIRST_BRACKET = 1e-9
EQUILIBRIUM_MAX_PENETRATION = 1e-2
EQUILIBRIUM_XTOL = 1e-18

#: Largest penetration [m], as a fraction of the normal module, that a step may reach: far
#: beyond it the Hertz contact of the flanks' surfaces is no longer a model of anything (the
#: default pair reaches about 1e-3 of the module in rattle).
MAX_PENETRATION_MODULES = 0.05

#: Samples used to find a positive penetration inside a substep that starts at a contact
#: onset (penetration ~0) and ends separated: a grazing contact shorter than one substep.
GRAZING_SAMPLES = 8

#: Largest product of a contact substep and the contact's fastest rate, sqrt(k/m) + c/m.
#: RK4 is stable to about 2.8 on both the imaginary and the negative real axis; 0.25 keeps a
#: single impact's restitution within 1e-4 of the closed form from 1 mm/s to 0.5 m/s at any
#: legal damping (tests/core/test_impact.py), and leaves the default grid (10 us) untouched at
#: the default pair's rattle speeds below ~20 mm/s.
CONTACT_RATE_SAFETY = 0.25

#: Largest number of contact substeps in one communication step; beyond it the contact is
#: stiffer than the stepper resolves at a sensible cost and the step is refused.
MAX_CONTACT_SUBSTEPS = 200_000

#: xtol [s] and rtol of Brent's method for the release, the friction reversals and the pair
#: engagements.
EVENT_XTOL = 1e-15
EVENT_RTOL = roots.BRENT_RTOL

#: Relative slack of the substep grid: a step that is a whole multiple of solver.h_max to
#: rounding, h/h_max = n (1 + a few ulps), gets n grid substeps, not n + 1.
GRID_SLACK = 1e-12

#: A crowned pair's engagement located in the first this fraction of a substep does not end
#: the substep: RK4's error from a kink that close to its start is negligible (it scales with
#: the kink's offset to the power 2.5), and splitting there would let a pair hovering at its
#: offset end substep after substep a few femtoseconds long.
ENGAGEMENT_MIN_FRACTION = 1e-3


def _domain(kind: str, **options):
    """A dataclass field whose metadata holds the domain of its saved value
    (``snapshots.DOMAINS``)."""
    return field(metadata={"domain": kind}, **options)


def domains(cls) -> tuple[str, ...]:
    """The domains of the saved fields of ``cls``, in field order."""
    return tuple(f.metadata["domain"] for f in fields(cls) if "domain" in f.metadata)


@dataclass(frozen=True)
class WheelState:
    """Complete state of the wheel and the contact bookkeeping (SI units); a value: change a
    stepper's state with ``restore`` (``dataclasses.replace`` makes a changed copy)."""

    phi: float = _domain("f")  # wheel angle [rad]
    w: float = _domain("f")  # wheel speed [rad/s]
    flank: int = _domain("flank", default=0)  # flank in contact: +1 drive, -1 coast, 0 none
    v_impact_drive: float = _domain("f", default=0.0)  # normal approach speed at the last
    # drive-flank onset [m/s]
    v_impact_coast: float = _domain("f", default=0.0)  # same, coast flank [m/s]
    v_impact_last: float = _domain("f", default=0.0)  # normal approach speed at the last
    # onset on either flank [m/s]
    impacts_drive: int = _domain("n", default=0)  # cumulative contact onsets, drive flank
    impacts_coast: int = _domain("n", default=0)  # cumulative contact onsets, coast flank
    rattle_index: float = _domain("f+", default=0.0)  # exponentially averaged impact kinetic
    # energy per second [W]

    def as_tuple(self) -> tuple:
        return tuple(getattr(self, f.name) for f in fields(self))

    @classmethod
    def from_tuple(cls, values) -> WheelState:
        """From values in field order (integer fields converted with int, the others with
        float)."""
        return cls(*(int(v) if f.type == "int" else float(v)
                     for f, v in zip(fields(cls), values, strict=True)))


class PinionState(NamedTuple):
    """The pinion's angle [rad] and speed [rad/s] at the end of the last step (the step-start
    inputs at construction)."""

    phi: float
    w: float


@dataclass
class ContactEvent:
    """A located contact event of a step."""

    time: float  # time from the start of the step [s]
    kind: str  # "onset", "release", "reversal" (a pair's friction turns) or "pair" (a crowned
    # pair starts or stops carrying load)
    flank: int  # +1 drive, -1 coast
    speed: float  # normal approach speed d(delta)/dt at the event [m/s]


@dataclass
class StepResult:
    """Per-step aggregates (SI units), the located events and cost counters of a step."""

    tau_wheel_mean: float = _domain("f")  # mesh torque on the wheel averaged over the step
    # [N.m]
    tau_pinion_mean: float = _domain("f")  # mesh torque on the pinion averaged over the step
    # [N.m]
    W_peak: float = _domain("f+")  # peak total normal force within the step [N]
    delta_peak: float = _domain("f+")  # peak penetration within the step [m]
    onsets_drive: int = _domain("n")  # contact onsets in this step, drive flank
    onsets_coast: int = _domain("n")  # contact onsets in this step, coast flank
    events: list[ContactEvent] = field(default_factory=list)
    rhs_evaluations: int = 0  # cost counter
    contact_substeps: int = 0  # cost counter

    @classmethod
    def none(cls) -> StepResult:
        """The aggregates before the first step (all zero)."""
        return cls(0.0, 0.0, 0.0, 0.0, 0, 0)

    def aggregates(self) -> tuple:
        """The saved aggregates, in field order (what a snapshot keeps of a step)."""
        return tuple(getattr(self, f.name) for f in fields(self) if "domain" in f.metadata)


#: The saved aggregates of a StepResult, in order.
AGGREGATES = tuple(f.name for f in fields(StepResult) if "domain" in f.metadata)


@dataclass(frozen=True)
class WheelSnapshot:
    """Everything a wheel stepper needs to continue exactly where it was: the wheel's state,
    the pinion at the end of the last step and that step's aggregates (its events and cost
    counters are not kept)."""

    state: WheelState
    pinion: PinionState
    result: StepResult

    #: check_fields layout of ``to_json``.
    LAYOUT: ClassVar[dict] = {"wheel": domains(WheelState), "pinion": ("f", "f"),
                              "last": domains(StepResult)}

    def to_json(self) -> dict:
        """A JSON-able dict (floats round-trip exactly through repr-based JSON)."""
        return {"wheel": list(self.state.as_tuple()), "pinion": list(self.pinion),
                "last": list(self.result.aggregates())}

    @classmethod
    def from_json(cls, data) -> WheelSnapshot:
        """The snapshot of a ``to_json`` dict; ValueError naming the first entry out of its
        domain (the dict may come from a forged or corrupted FMU state)."""
        s = check_fields(data, cls.LAYOUT)
        return cls(WheelState(*s["wheel"]), PinionState(*s["pinion"]), StepResult(*s["last"]))


class WheelStepperBase:
    """The contract of a wheel stepper: the wheel's equation of motion with the mesh model
    (paper eq. 10), advanced one communication step at a time.

    Two implementations compute the same numbers bit for bit (docs/kernel.md): the
    pure-Python reference :class:`WheelStepper` and ``kernel.CompiledWheelStepper``.  Callers
    use only this contract and never ask which one they hold:

    * ``Stepper(params, phi_p, w_p, tau_load)``: the start state for the initial inputs (the
      static flank equilibrium with ``init.in_contact``, else ``wheel.phi_start`` checked
      against the pinion); ``from_state(params, state, pinion)``: a given wheel state, nothing
      solved; ``from_snapshot(params, snapshot)``: a saved stepper, nothing solved or checked;
    * ``step(h, phi_p, w_p, a_p, tau_load)`` advances by ``h`` and returns the
      :class:`StepResult`; a refused step raises ValueError and changes nothing;
    * ``outputs()``: the values of ``interface.MESH_OUTPUTS`` now; ``wheel_angle_speed()``: the
      two a partner reads every step, cheaply;
    * ``snapshot()`` / ``restore(snapshot)``: save and set the complete state (restoring never
      solves start conditions); ``start_snapshot(phi_p, w_p, tau_load)``: the state the
      constructor starts from, for inputs given later;
    * ``state``, ``pinion``, ``last_result``: the current values (read-only).

    Subclasses implement ``_setup`` (their resources), ``_load`` / ``snapshot`` and the
    stepping and output methods.
    """

    def __init__(self, params: MeshParameters, phi_p: float = 0.0, w_p: float = 0.0,
                 tau_load: float = 0.0, **options):
        self._setup(params, **options)
        self._load(self.start_snapshot(phi_p, w_p, tau_load))

    @classmethod
    def from_snapshot(cls, params: MeshParameters, snapshot: WheelSnapshot, **options):
        """A stepper in a saved state (a restored FMU state), taken as it is: unlike the
        constructor it solves no start equilibrium and checks no start condition (the state
        was valid when it was saved, and its pinion has moved on since the start).
        ``options`` go to the implementation's set-up (e.g. the kernel ``library``)."""
        stepper = cls.__new__(cls)
        stepper._setup(params, **options)
        stepper._load(snapshot)
        return stepper

    @classmethod
    def from_state(cls, params: MeshParameters, state: WheelState,
                   pinion: tuple[float, float] = (0.0, 0.0), **options):
        """A stepper whose wheel is in ``state`` against the pinion at ``pinion`` (angle
        [rad], speed [rad/s]), before any step: nothing is solved or checked."""
        return cls.from_snapshot(params, WheelSnapshot(state, PinionState(*pinion),
                                                       StepResult.none()), **options)

    def restore(self, snapshot: WheelSnapshot) -> None:
        """Set the complete state saved by :meth:`snapshot` (no start condition is solved)."""
        self._load(snapshot)

    def _setup(self, params: MeshParameters) -> None:
        """The parameters and the mesh model (subclasses add their resources)."""
        self.params = params
        self.mesh = MeshModel(params)
        self.geometry = self.mesh.geometry

    # ------------------------------------------------------------------ to implement
    def _load(self, snapshot: WheelSnapshot) -> None:
        raise NotImplementedError

    def snapshot(self) -> WheelSnapshot:
        """The complete current state (values: later steps do not change it)."""
        raise NotImplementedError

    @property
    def state(self) -> WheelState:
        raise NotImplementedError

    @property
    def pinion(self) -> PinionState:
        """The pinion's angle and speed at the end of the last step."""
        raise NotImplementedError

    @property
    def last_result(self) -> StepResult:
        """The result of the last step (all zero before the first)."""
        raise NotImplementedError

    def step(self, h: float, phi_p: float, w_p: float, a_p: float = 0.0,
             tau_load: float = 0.0) -> StepResult:
        raise NotImplementedError

    def outputs(self) -> dict[str, float]:
        raise NotImplementedError

    def wheel_angle_speed(self) -> tuple[float, float]:
        """``(state.phi, state.w)``: the wheel's angle [rad] and speed [rad/s] now."""
        raise NotImplementedError

    # ------------------------------------------------------------------ start conditions
    def start_snapshot(self, phi_p: float, w_p: float, tau_load: float) -> WheelSnapshot:
        """The state the constructor starts from for the initial inputs ``phi_p`` [rad],
        ``w_p`` [rad/s] and ``tau_load`` [N.m]: with ``init.in_contact`` the wheel rests in the
        static flank equilibrium for them; otherwise it starts at ``wheel.phi_start``,
        ``wheel.w_start`` (ValueError if that puts the flanks into each other)."""
        _check_finite(phi_p=phi_p, w_p=w_p, tau_load=tau_load)
        params = self.params
        if params.init_in_contact:
            state = self.equilibrium_state(phi_p, w_p, tau_load)
        else:
            free = WheelState(params.phi_start, params.w_start)
            flank = self.contact_flank(phi_p, w_p, 0.0, tau_load, free)
            state = WheelState(params.phi_start, params.w_start, flank)
            pen = self.mesh.penetration
            depth = max(pen(DRIVE, phi_p, params.phi_start), pen(COAST, phi_p, params.phi_start))
            if depth > MAX_INITIAL_PENETRATION:
                g, ratio = self.geometry, self.geometry.ratio
                half = g.half_backlash / self.mesh.arm_wheel
                raise ValueError(
                    f"parameter 'wheel.phi_start' = {params.phi_start!r} rad puts the flanks "
                    f"{depth * 1e3:.4g} mm into each other at pinion.phi = {phi_p!r} rad; "
                    f"allowed: within the backlash, |wheel.phi_start - {ratio:.6g} pinion.phi| "
                    f"<= {half:.4g} rad (plus {MAX_INITIAL_PENETRATION * 1e6:g} um), or "
                    "init.in_contact = true")
        return WheelSnapshot(state, PinionState(phi_p, w_p), StepResult.none())

    def equilibrium_state(self, phi_p: float, w_p: float, tau_load: float) -> WheelState:
        """Wheel at the rigid speed ratio, resting on the flank that carries ``tau_load``
        with the penetration at which the mesh torque balances it."""
        mesh = self.mesh
        w_w = w_p * self.geometry.ratio
        if tau_load == 0.0:
            return WheelState(self._wheel_angle(DRIVE, phi_p, 0.0), w_w, 0)
        flank = DRIVE if tau_load > 0.0 else COAST

        def residual(delta: float) -> float:
            phi_w = self._wheel_angle(flank, phi_p, delta)
            return mesh.torques(flank, phi_p, w_p, phi_w, w_w, 0.0)[0] - tau_load

        hi = EQUILIBRIUM_FIRST_BRACKET
        r_hi = residual(hi)
        while (r_hi > 0.0) != (flank == DRIVE) or r_hi == 0.0:
            hi *= 2.0
            if hi > EQUILIBRIUM_MAX_PENETRATION:
                raise ValueError(
                    f"no static flank equilibrium for wheel.tau_load = {tau_load!r} N.m: the "
                    f"mesh torque does not reach it within {EQUILIBRIUM_MAX_PENETRATION * 1e3:g}"
                    " mm penetration (friction dominates the normal force?); set "
                    "init.in_contact = false")
            r_hi = residual(hi)
        r_0 = residual(0.0)
        if (r_0 >= 0.0) == (flank == DRIVE):
            # A load so small that the rounding-level penetration of the touching state
            # (~1e-18 m) already carries it: the flanks just touch.
            delta = 0.0
        else:
            delta = roots.brent(residual, 0.0, hi, fa=r_0, fb=r_hi, xtol=EQUILIBRIUM_XTOL,
                                rtol=roots.BRENT_RTOL)
        return WheelState(self._wheel_angle(flank, phi_p, delta), w_w, flank)

    def _wheel_angle(self, flank: int, phi_p: float, delta: float) -> float:
        """Wheel angle at which ``flank`` has penetration ``delta`` against pinion ``phi_p``."""
        m = self.mesh
        x = flank * (self.geometry.half_backlash + delta)
        return (m.arm_pinion * phi_p - x) / m.arm_wheel

    def contact_flank(self, phi_p: float, w_p: float, a_p: float, tau_load: float,
                      state: WheelState) -> int:
        """Flank in contact for the wheel ``state`` against the pinion (``phi_p``, ``w_p``,
        ``a_p``) under the load ``tau_load``: the flank that penetrates (the current one
        first), or one exactly touching that the motion drives into contact -- approaching,
        or at rest and accelerated towards it (exact touch)."""
        mesh = self.mesh
        accel_w = -tau_load / self.params.J_wheel  # free wheel; no force at zero penetration
        for flank in (state.flank, DRIVE, COAST):
            if flank == 0:
                continue
            pen = mesh.penetration(flank, phi_p, state.phi)
            if pen > 0.0:
                return flank
            if pen == 0.0:
                rate = mesh.approach_rate(flank, w_p, state.w)
                if rate > 0.0:
                    return flank
                if rate == 0.0 and mesh.approach_rate(flank, a_p, accel_w) > 0.0:
                    return flank
        return 0


class WheelStepper(WheelStepperBase):
    """The pure-Python wheel stepper: the reference implementation of the contract
    (:class:`WheelStepperBase`), and the only one that reports the located events
    (``StepResult.events``)."""

    def _load(self, snapshot: WheelSnapshot) -> None:
        self._state = snapshot.state
        self._pinion = PinionState(float(snapshot.pinion[0]), float(snapshot.pinion[1]))
        self._last = StepResult(*snapshot.result.aggregates())

    def snapshot(self) -> WheelSnapshot:
        return WheelSnapshot(self._state, self._pinion, StepResult(*self._last.aggregates()))

    @property
    def state(self) -> WheelState:
        return self._state

    @property
    def pinion(self) -> PinionState:
        return self._pinion

    @property
    def last_result(self) -> StepResult:
        return self._last

    def wheel_angle_speed(self) -> tuple[float, float]:
        return self._state.phi, self._state.w

    # ------------------------------------------------------------------ stepping
    def step(self, h: float, phi_p: float, w_p: float, a_p: float = 0.0,
             tau_load: float = 0.0) -> StepResult:
        """Advance the wheel by ``h`` [s] under the pinion kinematics ``phi_p`` [rad],
        ``w_p`` [rad/s], ``a_p`` [rad/s^2] at the step start and the held load torque
        ``tau_load`` [N.m].  Commits the new state only when the whole step succeeded."""
        _check_finite(phi_p=phi_p, w_p=w_p, a_p=a_p, tau_load=tau_load)
        check_step_size(h, self.params.h_comm_max)
        run = _StepRun(self, h, phi_p, w_p, a_p, tau_load)
        state, result = run.execute()
        if not (math.isfinite(state.phi) and math.isfinite(state.w)
                and math.isfinite(result.tau_pinion_mean) and math.isfinite(result.W_peak)):
            raise diverged_error(state.phi, state.w)
        phi_p_end = phi_p + h * (w_p + 0.5 * a_p * h)
        pen = self.mesh.penetration
        depth = max(max(result.delta_peak, pen(DRIVE, phi_p_end, state.phi)),
                    pen(COAST, phi_p_end, state.phi))
        limit = MAX_PENETRATION_MODULES * self.params.m_n
        if depth > limit:
            raise penetration_error(depth, limit)
        self._state = state
        self._pinion = PinionState(phi_p + w_p * h + 0.5 * a_p * h * h, w_p + a_p * h)
        self._last = result
        return result

    # ------------------------------------------------------------------ outputs
    def loads_now(self) -> MeshLoads:
        """Mesh loads at the end of the last step (or at the start), with per-pair detail.

        When no flank is in contact, the loads of the flank nearer to contact (zero forces,
        negative ``delta`` = its clearance)."""
        st = self._state
        phi_p, w_p = self._pinion
        flank = st.flank
        if flank == 0:
            pen = self.mesh.penetration
            flank = DRIVE if pen(DRIVE, phi_p, st.phi) >= pen(COAST, phi_p, st.phi) else COAST
        v_imp = st.v_impact_drive if flank == DRIVE else st.v_impact_coast
        return self.mesh.loads(flank, phi_p, w_p, st.phi, st.w, v_imp)

    def outputs(self) -> dict[str, float]:
        """Values of ``interface.MESH_OUTPUTS`` for the current state (SI units), in their
        declared order."""
        st, last = self._state, self._last
        mesh, g = self.mesh, self.geometry
        loads = self.loads_now()
        loaded = [p for p in loads.pairs if p.W > 0.0]
        if loaded:
            top = loaded[0]  # the most loaded pair (the first of equals)
            for pair in loaded:
                if pair.W > top.W:
                    top = pair
            h, lam, psi = top.h, top.film_parameter, top.dry_fraction
        else:
            v_imp = st.v_impact_drive if loads.flank > 0 else st.v_impact_coast
            d_max = mesh.energy_balance_delta_max(loads.flank, self._pinion.phi, v_imp)
            h = lubrication.film_thickness(-loads.delta, d_max)
            lam = h / self.params.sigma
            psi = lubrication.dry_fraction(lam)
        W = loads.W
        transverse = W * g.normal_factor
        out = {
            "wheel.tau_mesh": last.tau_wheel_mean,
            "pinion.tau_mesh": last.tau_pinion_mean,
            "wheel.phi": st.phi,
            "wheel.w": st.w,
            "mesh.W": loads.W,
            "mesh.W_peak": last.W_peak,
            "mesh.F": loads.F,
            "mesh.delta": loads.delta if loaded else 0.0,
            "mesh.delta_peak": last.delta_peak,
            "mesh.v_impact": st.v_impact_last,
            "mesh.h": h,
            "mesh.lambda": lam,
            "mesh.psi": psi,
            "mesh.n_contact": len(loaded),
            "mesh.impacts_drive": st.impacts_drive,
            "mesh.impacts_coast": st.impacts_coast,
            "mesh.transmission_error": mesh.penetration(DRIVE, self._pinion.phi, st.phi)
            + g.half_backlash,
            "mesh.force_tangential": loads.flank * transverse * g.cos_alpha_t,
            "mesh.force_radial": transverse * g.sin_alpha_t,
            "mesh.force_axial": loads.flank * W * g.sin_beta_b,
            "mesh.impact_energy": 0.5 * mesh.normal_mass * st.v_impact_last * st.v_impact_last,
            "mesh.rattle_index": st.rattle_index,
        }
        for k, f in enumerate(mesh.pair_forces(loads)):
            out[f"pair[{k}].W"] = f
        return out


class _WorkingState:
    """The mutable copy of a :class:`WheelState` that a step advances; frozen again into a
    new WheelState when the step is committed."""

    __slots__ = tuple(f.name for f in fields(WheelState))

    def __init__(self, state: WheelState):
        for name in self.__slots__:
            setattr(self, name, getattr(state, name))

    def frozen(self) -> WheelState:
        return WheelState(*(getattr(self, name) for name in self.__slots__))


class _StepRun:
    """One communication step: local copies of the state, committed by the caller."""

    def __init__(self, stepper: WheelStepper, h: float, phi_p: float, w_p: float, a_p: float,
                 tau_load: float):
        p = stepper.params
        self.stepper = stepper
        self.mesh = stepper.mesh
        self.geometry = stepper.geometry
        self.H = h
        self.n_sub = max(1, math.ceil(h / p.h_max * (1.0 - GRID_SLACK)))
        self.phi_p0, self.w_p0, self.a_p = phi_p, w_p, a_p
        self.tau_load = tau_load
        self.J = p.J_wheel
        self.start = stepper.state
        self.state = _WorkingState(self.start)
        self.result = StepResult.none()
        self.int_tau_pinion = 0.0
        # Friction direction of each pair slot on the current substep, and the directions
        # a located reversal prescribes for the substep after it.
        self.signs = [0.0] * MAX_PAIR_SLOTS
        self.reversed: dict[int, float] = {}
        self.friction = p.friction_enabled
        # Impact energy entering the rattle index, weighted to the step end.
        self.rattle_time = p.rattle_time
        self.rattle_gain = 0.0

    # pinion kinematics at time t from the step start
    def phi_p(self, t: float) -> float:
        return self.phi_p0 + t * (self.w_p0 + 0.5 * self.a_p * t)

    def w_p(self, t: float) -> float:
        return self.w_p0 + self.a_p * t

    def grid(self, j: int) -> float:
        """Time of grid point j (exactly H at j = n)."""
        return self.H if j >= self.n_sub else self.H * j / self.n_sub

    def execute(self) -> tuple[WheelState, StepResult]:
        st = self.state
        mesh = self.mesh
        # Inputs may move the pinion discontinuously between steps: re-establish the mode.
        flank = self.stepper.contact_flank(self.phi_p0, self.w_p0, self.a_p, self.tau_load, st)
        if flank != st.flank:
            if st.flank != 0:
                self._event(0.0, "release", st.flank)
            if flank != 0:
                self._onset(0.0, flank)
            st.flank = flank
        t = 0.0
        while t < self.H:
            t = self._free_flight(t) if st.flank == 0 else self._contact_substep(t)
        r = self.result
        # Mean mesh torque from the momentum balance I_w dw = (tau_mesh - tau_load) dt.
        dw = st.w - self.start.w
        r.tau_wheel_mean = (self.J * dw + self.tau_load * self.H) / self.H
        r.tau_pinion_mean = self.int_tau_pinion / self.H
        st.rattle_index = st.rattle_index * math.exp(-self.H / self.rattle_time) + self.rattle_gain
        if st.flank != 0:
            r.delta_peak = max(r.delta_peak, mesh.penetration(st.flank, self.phi_p(self.H), st.phi))
            r.W_peak = max(r.W_peak, self._rhs(self.H, st.phi, st.w)[2])
        return st.frozen(), r

    # ------------------------------------------------------------------ events
    def _event(self, t: float, kind: str, flank: int) -> ContactEvent:
        st = self.state
        speed = self.mesh.approach_rate(flank, self.w_p(t), st.w)
        ev = ContactEvent(t, kind, flank, speed)
        self.result.events.append(ev)
        return ev

    def _onset(self, t: float, flank: int) -> None:
        st = self.state
        v = self._event(t, "onset", flank).speed
        if v < 0.0:
            v = 0.0
        st.v_impact_last = v
        # Kinetic energy of the impact on the tooth normal, into the rattle index (an
        # exponential average: each impact adds E / tau, decayed to the step end).
        energy = 0.5 * self.mesh.normal_mass * v * v
        self.rattle_gain += energy / self.rattle_time * math.exp(-(self.H - t) / self.rattle_time)
        if flank == DRIVE:
            st.v_impact_drive = v
            st.impacts_drive += 1
            self.result.onsets_drive += 1
        else:
            st.v_impact_coast = v
            st.impacts_coast += 1
            self.result.onsets_coast += 1

    # ------------------------------------------------------------------ free flight
    def _free_flight(self, t: float) -> float:
        """Exact motion under the held load until the next onset or the step end."""
        st, m, g = self.state, self.mesh, self.geometry
        a_w = -self.tau_load / self.J
        x0 = m.arm_pinion * self.phi_p(t) - m.arm_wheel * st.phi
        v0 = m.arm_pinion * self.w_p(t) - m.arm_wheel * st.w
        half_acc = 0.5 * (m.arm_pinion * self.a_p - m.arm_wheel * a_w)
        span = self.H - t
        half_backlash = g.half_backlash
        hit_d = roots.first_crossing(x0 - half_backlash, v0, half_acc, span, rising=True)
        hit_c = roots.first_crossing(-x0 - half_backlash, -v0, -half_acc, span, rising=True)
        if hit_d is None and hit_c is None:
            dt, flank = span, 0
        elif hit_c is None or (hit_d is not None and hit_d <= hit_c):
            dt, flank = hit_d, DRIVE
        else:
            dt, flank = hit_c, COAST
        t_new = self.H if flank == 0 else t + dt
        st.phi += dt * (st.w + 0.5 * a_w * dt)
        st.w += a_w * dt
        if flank != 0:
            st.flank = flank
            self._onset(t_new, flank)
        return t_new

    # ------------------------------------------------------------------ contact
    def _rhs(self, t: float, phi_w: float, w_w: float) -> tuple[float, float, float]:
        """(wheel acceleration, mesh torque on the pinion, total normal force) at time t."""
        st = self.state
        flank = st.flank
        v_imp = st.v_impact_drive if flank == DRIVE else st.v_impact_coast
        tau_w, tau_p, W = self.mesh.torques(
            flank, self.phi_p(t), self.w_p(t), phi_w, w_w, v_imp, self.signs)
        self.result.rhs_evaluations += 1
        return (tau_w - self.tau_load) / self.J, tau_p, W

    def _rk4(self, t: float, h: float, phi: float, w: float, k1) -> tuple[float, float, float]:
        """Classical RK4 over [t, t+h] from (phi, w) with first stage ``k1``.

        Returns the new (phi, w) and the integral of the pinion torque over the step."""
        a1, p1, _ = k1
        a2, p2, _ = self._rhs(t + 0.5 * h, phi + 0.5 * h * w, w + 0.5 * h * a1)
        w2 = w + 0.5 * h * a1
        a3, p3, _ = self._rhs(t + 0.5 * h, phi + 0.5 * h * w2, w + 0.5 * h * a2)
        w3 = w + 0.5 * h * a2
        a4, p4, _ = self._rhs(t + h, phi + h * w3, w + h * a3)
        w4 = w + h * a3
        phi_new = phi + h / 6.0 * (w + 2.0 * w2 + 2.0 * w3 + w4)
        w_new = w + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
        return phi_new, w_new, h / 6.0 * (p1 + 2.0 * p2 + 2.0 * p3 + p4)

    def _contact_substep(self, t: float) -> float:
        """One RK4 substep in contact, ended at the next grid point, pair breakpoint, release
        or friction reversal, whichever comes first, and no longer than the contact's own
        time scales allow."""
        st, m, g = self.state, self.mesh, self.geometry
        flank = st.flank
        j = min(int(t * self.n_sub / self.H), self.n_sub - 1)
        t_end = self.grid(j + 1)
        if t_end <= t:  # t sits on a grid point within rounding
            t_end = self.grid(j + 2)
        # Split at the next pair entry/exit so the right-hand side is smooth on the substep.
        u_a = g.flank_roll(flank, self.phi_p(t))
        bp = g.next_breakpoint(u_a, g.flank_roll(flank, self.phi_p(t_end)))
        if bp is not None:
            k = flank * g.rb_pinion
            dt = roots.first_crossing(u_a - bp, k * self.w_p(t), 0.5 * k * self.a_p, t_end - t,
                                      rising=bp > u_a)
            if dt is not None:
                t_end = t + dt
        h = self._resolved_substep(t, t_end - t)
        t_end = t + h
        self._friction_directions(t)
        delta_a = m.penetration(flank, self.phi_p(t), st.phi)
        flipped: set[int] = set()
        while True:
            k1 = self._rhs(t, st.phi, st.w)
            phi_b, w_b, q = self._rk4(t, h, st.phi, st.w, k1)
            delta_b = m.penetration(flank, self.phi_p(t_end), phi_b)
            released = False
            reversal = None
            dt_event = h
            if delta_b <= 0.0:
                dt = self._release_time(t, h, delta_a, delta_b, k1)
                if dt is not None:
                    released = True
                    dt_event = dt
            reversals = self._reversal_times(t, h, w_b, k1, flipped)
            # A reversal at the substep start to rounding (sliding speed zero at t): the pair's
            # friction takes its new direction for the whole substep; redo it.
            instant = [slot for slot, dt in reversals if t + dt <= t]
            if not instant:
                break
            for slot in instant:
                self.signs[slot] = -self.signs[slot]
                flipped.add(slot)
        self.result.W_peak = max(self.result.W_peak, k1[2])
        for slot, dt in reversals:
            if dt < dt_event:
                dt_event, reversal, released = dt, slot, False
        # A crowned pair starting or ending to carry load (its own penetration crossing zero)
        # makes the force a C1 kink; ending the substep there keeps RK4's order.  One located
        # right at the substep start needs no split (ENGAGEMENT_MIN_FRACTION).
        engaged = None
        for slot, dt in self._engagement_times(t, h, phi_b, k1):
            if dt < dt_event and dt > ENGAGEMENT_MIN_FRACTION * h:
                dt_event, engaged, reversal, released = dt, slot, None, False
        if dt_event < h:
            h = dt_event
            t_end = t + h
            phi_b, w_b, q = self._rk4(t, h, st.phi, st.w, k1)
        delta_b = 0.0 if released else m.penetration(flank, self.phi_p(t_end), phi_b)
        self._track_peak(t, h, flank, delta_a, st.phi, st.w, delta_b, phi_b, w_b)
        st.phi, st.w = phi_b, w_b
        self.int_tau_pinion += q
        if reversal is not None:
            self.reversed[reversal] = -self.signs[reversal]
            self._event(t_end, "reversal", flank)
        if engaged is not None:
            self._event(t_end, "pair", flank)
        if released or delta_b <= 0.0:
            self._event(t_end, "release", flank)
            st.flank = 0
        return t_end

    def _resolved_substep(self, t: float, span: float) -> float:
        """Length of the next contact substep: ``span`` divided into equal parts no longer
        than CONTACT_RATE_SAFETY over the contact's fastest rate sqrt(k/m) + c/m, estimated
        at the penetration the substep can reach, delta + max(ddelta/dt, 0) span."""
        st, m = self.state, self.mesh
        flank = st.flank
        delta = m.penetration(flank, self.phi_p(t), st.phi)
        rate = m.approach_rate(flank, self.w_p(t), st.w)
        reach = delta + rate * span if rate > 0.0 else delta
        k, c = m.contact_rates(flank, self.phi_p(t), self.w_p(t), reach, rate)
        mass = m.normal_mass
        fastest = math.sqrt(k / mass) + c / mass
        r = self.result
        r.contact_substeps += 1
        if fastest * span <= CONTACT_RATE_SAFETY:
            return span
        parts = math.ceil(fastest * span / CONTACT_RATE_SAFETY)
        if r.contact_substeps + parts > MAX_CONTACT_SUBSTEPS:
            raise stiffness_error(fastest, k, c, mass)
        return span / parts

    def _friction_directions(self, t: float) -> None:
        """Fix each pair's friction direction for the substep from ``t``: the sign of its
        sliding speed, or the one a reversal located at ``t`` prescribes (its sliding speed is
        zero to rounding there)."""
        st, m = self.state, self.mesh
        signs = self.signs
        for k in range(MAX_PAIR_SLOTS):
            signs[k] = 0.0
        w_p = self.w_p(t)
        for slot, s, _g, _dg in self.geometry.pairs(st.flank, self.phi_p(t)):
            forced = self.reversed.get(slot)
            if forced is not None:
                signs[slot] = forced
                continue
            v_s = m.sliding_speed(s, w_p, st.w)
            signs[slot] = 1.0 if v_s > 0.0 else (-1.0 if v_s < 0.0 else 0.0)
        self.reversed.clear()

    def _reversal_times(self, t: float, h: float, w_b: float, k1, flipped):
        """``(slot, dt)`` for each pair (not in ``flipped``) whose sliding speed ends the
        substep with the sign opposite to its friction direction: the located offset of the
        reversal in [0, h].  None without friction (the directions do not matter)."""
        st, m = self.state, self.mesh
        flank = st.flank
        out = []
        if not self.friction:
            return out
        for slot, s, _g, _dg in self.geometry.pairs(flank, self.phi_p(t + h)):
            sign = self.signs[slot]
            if slot in flipped or sign == 0.0 or sign * m.sliding_speed(
                    s, self.w_p(t + h), w_b) >= 0.0:
                continue

            def speed(dt: float, w: float, slot=slot) -> float:
                for other, s_k, _g_k, _dg_k in self.geometry.pairs(flank, self.phi_p(t + dt)):
                    if other == slot:
                        return m.sliding_speed(s_k, self.w_p(t + dt), w)
                return 0.0

            def slide(dt: float, speed=speed) -> float:
                return speed(dt, self._rk4(t, dt, st.phi, st.w, k1)[1])

            f_a = speed(0.0, st.w)
            f_b = speed(h, w_b)
            if f_a == 0.0 or (f_a > 0.0) == (f_b > 0.0):
                continue  # no sign change on the substep's own RK4 path
            out.append((slot, roots.brent(slide, 0.0, h, fa=f_a, fb=f_b, xtol=EVENT_XTOL,
                                                  rtol=EVENT_RTOL)))
        return out

    def _engagement_times(self, t: float, h: float, phi_b: float, k1):
        """``(slot, dt)`` for each pair with a crown offset whose own penetration
        delta - g changes sign over the substep: the located offset of the change in [0, h]."""
        st, m, g = self.state, self.mesh, self.geometry
        flank = st.flank
        out = []

        def own_penetration(dt: float, phi_w: float, slot: int) -> float | None:
            phi_p = self.phi_p(t + dt)
            for other, _s, offset, _dg in g.pairs(flank, phi_p):
                if other == slot:
                    return m.penetration(flank, phi_p, phi_w) - offset
            return None

        for slot, _s, offset, _dg in g.pairs(flank, self.phi_p(t)):
            if offset == 0.0:
                continue
            f_a = own_penetration(0.0, st.phi, slot)
            f_b = own_penetration(h, phi_b, slot)
            if f_a is None or f_b is None or (f_a > 0.0) == (f_b > 0.0):
                continue

            def crossing(dt: float, slot=slot) -> float:
                return own_penetration(dt, self._rk4(t, dt, st.phi, st.w, k1)[0], slot)

            out.append((slot, roots.brent(crossing, 0.0, h, fa=f_a, fb=f_b, xtol=EVENT_XTOL,
                                                  rtol=EVENT_RTOL)))
        return out

    def _release_time(self, t: float, h: float, delta_a: float, delta_b: float, k1):
        """Offset in (0, h] of the release (penetration crossing zero downwards) in the
        substep from ``t``, or None for a grazing contact that never penetrated."""
        st, m = self.state, self.mesh
        flank = st.flank

        def delta_after(dt: float) -> float:
            phi_b, _, _ = self._rk4(t, dt, st.phi, st.w, k1)
            return m.penetration(flank, self.phi_p(t + dt), phi_b)

        lo, f_lo = 0.0, delta_a
        if f_lo <= 0.0:  # substep starts at the onset: find where it penetrated
            for i in range(1, GRAZING_SAMPLES):
                s = h * i / GRAZING_SAMPLES
                f_s = delta_after(s)
                if f_s > 0.0:
                    lo, f_lo = s, f_s
                    break
            else:
                return None
        return roots.brent(delta_after, lo, h, fa=f_lo, fb=delta_b, xtol=EVENT_XTOL,
                           rtol=EVENT_RTOL)

    def _track_peak(self, t, h, flank, d_a, phi_a, w_a, d_b, phi_b, w_b) -> None:
        """Peak penetration and force inside the substep from the cubic Hermite interpolant
        of the penetration (values and rates at both ends)."""
        m, r = self.mesh, self.result
        r.delta_peak = max(r.delta_peak, d_a, d_b)
        dd_a = m.approach_rate(flank, self.w_p(t), w_a) * h
        dd_b = m.approach_rate(flank, self.w_p(t + h), w_b) * h
        if not (dd_a > 0.0 > dd_b):
            return
        # Hermite cubic on s in [0, 1]: derivative is a quadratic; its root where it falls.
        A = 6.0 * (d_a - d_b) + 3.0 * (dd_a + dd_b)
        B = -6.0 * (d_a - d_b) - 4.0 * dd_a - 2.0 * dd_b
        s = roots.first_crossing(dd_a, B, A, 1.0, rising=False)
        if s is None:
            return
        s2, s3 = s * s, s * s * s
        d = ((2 * s3 - 3 * s2 + 1) * d_a + (s3 - 2 * s2 + s) * dd_a
             + (-2 * s3 + 3 * s2) * d_b + (s3 - s2) * dd_b)
        if d > r.delta_peak:
            r.delta_peak = d
            r.W_peak = max(r.W_peak, m.static_force(flank, self.phi_p(t + s * h), d))


def check_step_size(h: float, h_max: float) -> None:
    """Raise ValueError unless 0 < h <= h_max (the parameter solver.h_comm_max)."""
    if not (h > 0.0 and math.isfinite(h)):
        raise ValueError(f"step size h = {h!r} s is invalid; allowed: finite and > 0")
    if h > h_max:
        raise ValueError(
            f"step size h = {h!r} s exceeds solver.h_comm_max = {h_max!r} s; allowed: "
            f"(0, {h_max!r}] s")


# The refusals' messages, in one place: the compiled kernel (kernel.py) reports the same
# refusals with these functions from the numbers the C code returns.
def diverged_error(phi: float, w: float) -> ValueError:
    """The refusal of a step whose wheel angle ``phi`` or speed ``w`` is not finite."""
    return ValueError(
        f"the step diverged (wheel angle {phi!r} rad, speed {w!r} rad/s); "
        "the inputs or parameters are beyond what the integrator resolves "
        "(reduce solver.h_max or the communication step)")


def penetration_error(depth: float, limit: float) -> ValueError:
    """The refusal of a step whose penetration ``depth`` [m] exceeds ``limit`` [m]."""
    return ValueError(
        f"the flanks would penetrate {depth * 1e3:.4g} mm in this step, beyond the "
        f"validity of the Hertz contact (allowed: {limit * 1e3:.4g} mm = "
        f"{MAX_PENETRATION_MODULES} gear.m_n); the inputs drive the teeth into each "
        "other far harder than any transmission (check wheel.tau_load and the pinion "
        "kinematics, or reduce the communication step)")


def stiffness_error(fastest: float, k: float, c: float, mass: float) -> ValueError:
    """The refusal of a step whose contact (fastest rate ``fastest`` [1/s] from stiffness
    ``k`` [N/m] and damping ``c`` [N.s/m] on ``mass`` [kg]) needs more than
    MAX_CONTACT_SUBSTEPS substeps."""
    return ValueError(
        f"the contact is too stiff to resolve: its fastest time scale "
        f"{1.0 / fastest:.3g} s (stiffness {k:.4g} N/m, damping {c:.4g} N.s/m on the "
        f"wheel's normal mass {mass:.4g} kg) needs more than {MAX_CONTACT_SUBSTEPS} "
        "substeps in this step; reduce the communication step, the impact speed "
        "(inputs) or contact.damping, or raise wheel.J")


def _check_finite(**values: float) -> None:
    for name, v in values.items():
        try:
            ok = math.isfinite(v)
        except TypeError:
            ok = False
        if not ok:
            raise ValueError(f"input {name} = {v!r} is not a finite number")
