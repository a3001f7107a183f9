"""Advances the wheel across one communication step (paper eq. 10) with located contact events.

Inside a step the pinion follows the Taylor polynomial of its step-start inputs,

    phi_p(t) = phi_p0 + w_p0 t + a_p t^2 / 2,

and the load torque is held.  The wheel alternates between two modes:

* **free flight** (no flank in contact): the wheel's acceleration is constant, so the normal
  approach is a quadratic in time; the next contact onset is its exact root (no substeps);
* **contact** on one flank: classical RK4 on substeps of a fixed grid ``t_j = j H / n``
  (``n = ceil(H / h_max)``), split wherever a pair enters or leaves the zone of action
  (kinematic, exact) and ended at the release, located by Brent's method on the RK4 step
  from the substep start (so the event is consistent with the integrator).

Every time inside the step is a grid point ``j H / n`` or a located event offset from one;
no time is accumulated across substeps or steps.  A rejected step (non-finite input,
non-positive step) raises ValueError before anything is changed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from . import roots
from .geometry import COAST, DRIVE
from .mesh import MeshLoads, MeshModel
from .parameters import MeshParameters

#: Largest flank penetration [m] accepted in a start state given by wheel.phi_start: ten
#: times the penetrations of loaded operation; more means a wheel angle that does not match the
#: pinion's (the teeth would start deep inside each other).
MAX_INITIAL_PENETRATION = 10e-6

#: Largest penetration [m], as a fraction of the normal module, that a step may reach: far
#: beyond it the Hertz contact of the flanks' surfaces is no longer a model of anything (the
#: default pair reaches about 1e-3 of the module in rattle).
MAX_PENETRATION_MODULES = 0.05

#: Samples used to find a positive penetration inside a substep that starts at a contact
#: onset (penetration ~0) and ends separated: a grazing contact shorter than one substep.
GRAZING_SAMPLES = 8


@dataclass
class WheelState:
    """Complete state of the wheel and the contact bookkeeping (SI units)."""

    phi: float  # wheel angle [rad]
    w: float  # wheel speed [rad/s]
    flank: int = 0  # flank in contact: +1 drive, -1 coast, 0 none
    v_impact_drive: float = 0.0  # normal approach speed at the last drive-flank onset [m/s]
    v_impact_coast: float = 0.0  # same, coast flank [m/s]
    v_impact_last: float = 0.0  # normal approach speed at the last onset on either flank [m/s]
    impacts_drive: int = 0  # cumulative contact onsets, drive flank
    impacts_coast: int = 0  # cumulative contact onsets, coast flank

    def as_tuple(self) -> tuple:
        return (self.phi, self.w, self.flank, self.v_impact_drive, self.v_impact_coast,
                self.v_impact_last, self.impacts_drive, self.impacts_coast)

    @classmethod
    def from_tuple(cls, values) -> WheelState:
        phi, w, flank, vd, vc, vl, nd, nc = values
        return cls(float(phi), float(w), int(flank), float(vd), float(vc), float(vl),
                   int(nd), int(nc))


@dataclass
class ContactEvent:
    """A located contact onset or release."""

    time: float  # time from the start of the step [s]
    kind: str  # "onset" or "release"
    flank: int  # +1 drive, -1 coast
    speed: float  # normal approach speed d(delta)/dt at the event [m/s]


@dataclass
class StepResult:
    """Per-step aggregates (SI units)."""

    tau_wheel_mean: float  # mesh torque on the wheel averaged over the step [N.m]
    tau_pinion_mean: float  # mesh torque on the pinion averaged over the step [N.m]
    W_peak: float  # peak total normal force within the step [N]
    delta_peak: float  # peak penetration within the step [m]
    onsets_drive: int  # contact onsets in this step, drive flank
    onsets_coast: int  # contact onsets in this step, coast flank
    events: list[ContactEvent] = field(default_factory=list)
    rhs_evaluations: int = 0  # cost counter


class WheelStepper:
    """The wheel's equation of motion with the mesh model, stepped one communication step at
    a time.

    ``phi_p``, ``w_p`` and ``tau_load`` at construction are the initial inputs; with
    ``init.in_contact`` the wheel starts in the static flank equilibrium for them.
    """

    def __init__(self, params: MeshParameters, phi_p: float = 0.0, w_p: float = 0.0,
                 tau_load: float = 0.0):
        _check_finite(phi_p=phi_p, w_p=w_p, tau_load=tau_load)
        self.params = params
        self.mesh = MeshModel(params)
        self.geometry = self.mesh.geometry
        if params.init_in_contact:
            self.state = self.equilibrium_state(phi_p, w_p, tau_load)
        else:
            self.state = WheelState(params.phi_start, params.w_start)
            self.state.flank = self._flank_in_contact(phi_p, params.phi_start, 0)
            depth = max(self.mesh.penetration(f, phi_p, params.phi_start) for f in (DRIVE, COAST))
            if depth > MAX_INITIAL_PENETRATION:
                g, ratio = self.geometry, self.geometry.ratio
                half = g.half_backlash / self.mesh.arm_wheel
                raise ValueError(
                    f"parameter 'wheel.phi_start' = {params.phi_start!r} rad puts the flanks "
                    f"{depth * 1e3:.4g} mm into each other at pinion.phi = {phi_p!r} rad; "
                    f"allowed: within the backlash, |wheel.phi_start - {ratio:.6g} pinion.phi| "
                    f"<= {half:.4g} rad (plus {MAX_INITIAL_PENETRATION * 1e6:g} um), or "
                    "init.in_contact = true")
        # Pinion kinematics at the end of the last step, for the "now" outputs.
        self.pinion = (phi_p, w_p)
        self.last = StepResult(0.0, 0.0, 0.0, 0.0, 0, 0)

    # ------------------------------------------------------------------ initial state
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

        hi = 1e-9
        r_hi = residual(hi)
        while (r_hi > 0.0) != (flank == DRIVE) or r_hi == 0.0:
            hi *= 2.0
            if hi > 1e-2:
                raise ValueError(
                    f"no static flank equilibrium for wheel.tau_load = {tau_load!r} N.m: the "
                    "mesh torque does not reach it within 10 mm penetration (friction "
                    "dominates the normal force?); set init.in_contact = false")
            r_hi = residual(hi)
        r_0 = residual(0.0)
        if (r_0 >= 0.0) == (flank == DRIVE):
            # A load so small that the rounding-level penetration of the touching state
            # (~1e-18 m) already carries it: the flanks just touch.
            delta = 0.0
        else:
            delta = roots.brent(residual, 0.0, hi, fa=r_0, fb=r_hi, xtol=1e-18)
        return WheelState(self._wheel_angle(flank, phi_p, delta), w_w, flank)

    def _wheel_angle(self, flank: int, phi_p: float, delta: float) -> float:
        """Wheel angle at which ``flank`` has penetration ``delta`` against pinion ``phi_p``."""
        m = self.mesh
        x = flank * (self.geometry.half_backlash + delta)
        return (m.arm_pinion * phi_p - x) / m.arm_wheel

    def _flank_in_contact(self, phi_p: float, phi_w: float, current: int) -> int:
        """Flank in contact given the angles; keeps ``current`` while it still penetrates."""
        pen = self.mesh.penetration
        if current != 0 and pen(current, phi_p, phi_w) > 0.0:
            return current
        if pen(DRIVE, phi_p, phi_w) > 0.0:
            return DRIVE
        if pen(COAST, phi_p, phi_w) > 0.0:
            return COAST
        return 0

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
            raise ValueError(
                f"the step diverged (wheel angle {state.phi!r} rad, speed {state.w!r} rad/s); "
                "the inputs or parameters are beyond what the integrator resolves "
                "(reduce solver.h_max or the communication step)")
        depth = max(result.delta_peak, *(self.mesh.penetration(
            f, phi_p + h * (w_p + 0.5 * a_p * h), state.phi) for f in (DRIVE, COAST)))
        limit = MAX_PENETRATION_MODULES * self.params.m_n
        if depth > limit:
            raise ValueError(
                f"the flanks would penetrate {depth * 1e3:.4g} mm in this step, beyond the "
                f"validity of the Hertz contact (allowed: {limit * 1e3:.4g} mm = "
                f"{MAX_PENETRATION_MODULES} gear.m_n); the inputs drive the teeth into each "
                "other far harder than any transmission (check wheel.tau_load and the pinion "
                "kinematics, or reduce the communication step)")
        self.state = state
        self.pinion = (phi_p + w_p * h + 0.5 * a_p * h * h, w_p + a_p * h)
        self.last = result
        return result

    # ------------------------------------------------------------------ outputs
    def loads_now(self) -> MeshLoads:
        """Mesh loads at the end of the last step (or at the start), with per-pair detail.

        When no flank is in contact, the loads of the flank nearer to contact (zero forces,
        negative ``delta`` = its clearance)."""
        st = self.state
        phi_p, w_p = self.pinion
        flank = st.flank
        if flank == 0:
            pen = self.mesh.penetration
            flank = DRIVE if pen(DRIVE, phi_p, st.phi) >= pen(COAST, phi_p, st.phi) else COAST
        v_imp = st.v_impact_drive if flank == DRIVE else st.v_impact_coast
        return self.mesh.loads(flank, phi_p, w_p, st.phi, st.w, v_imp)


class _StepRun:
    """One communication step: local copies of the state, committed by the caller."""

    def __init__(self, stepper: WheelStepper, h: float, phi_p: float, w_p: float, a_p: float,
                 tau_load: float):
        p = stepper.params
        self.stepper = stepper
        self.mesh = stepper.mesh
        self.geometry = stepper.geometry
        self.H = h
        self.n_sub = max(1, math.ceil(h / p.h_max * (1.0 - 1e-12)))
        self.phi_p0, self.w_p0, self.a_p = phi_p, w_p, a_p
        self.tau_load = tau_load
        self.J = p.J_wheel
        s = stepper.state
        self.state = WheelState(*s.as_tuple())
        self.result = StepResult(0.0, 0.0, 0.0, 0.0, 0, 0)
        self.int_tau_pinion = 0.0

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
        flank = self.stepper._flank_in_contact(self.phi_p0, st.phi, st.flank)
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
        dw = st.w - self.stepper.state.w
        r.tau_wheel_mean = (self.J * dw + self.tau_load * self.H) / self.H
        r.tau_pinion_mean = self.int_tau_pinion / self.H
        if st.flank != 0:
            r.delta_peak = max(r.delta_peak, mesh.penetration(st.flank, self.phi_p(self.H), st.phi))
            r.W_peak = max(r.W_peak, self._rhs(self.H, st.phi, st.w)[2])
        return st, r

    # ------------------------------------------------------------------ events
    def _event(self, t: float, kind: str, flank: int) -> ContactEvent:
        st = self.state
        speed = self.mesh.approach_rate(flank, self.w_p(t), st.w)
        ev = ContactEvent(t, kind, flank, speed)
        self.result.events.append(ev)
        return ev

    def _onset(self, t: float, flank: int) -> None:
        st = self.state
        v = max(self._event(t, "onset", flank).speed, 0.0)
        st.v_impact_last = v
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
        c = g.half_backlash
        hit_d = roots.first_crossing(x0 - c, v0, half_acc, span, rising=True)
        hit_c = roots.first_crossing(-x0 - c, -v0, -half_acc, span, rising=True)
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
            flank, self.phi_p(t), self.w_p(t), phi_w, w_w, v_imp)
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
        """One RK4 substep in contact, ended at the next grid point, pair breakpoint or
        release, whichever comes first."""
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
        h = t_end - t
        k1 = self._rhs(t, st.phi, st.w)
        self.result.W_peak = max(self.result.W_peak, k1[2])
        phi_b, w_b, q = self._rk4(t, h, st.phi, st.w, k1)
        delta_a = m.penetration(flank, self.phi_p(t), st.phi)
        delta_b = m.penetration(flank, self.phi_p(t_end), phi_b)
        released = False
        if delta_b <= 0.0:
            dt = self._release_time(t, h, delta_a, delta_b, k1)
            if dt is not None:
                released = True
                if dt < h:
                    h = dt
                    t_end = t + h
                    phi_b, w_b, q = self._rk4(t, h, st.phi, st.w, k1)
                delta_b = 0.0
        self._track_peak(t, h, flank, delta_a, st.phi, st.w, delta_b, phi_b, w_b)
        st.phi, st.w = phi_b, w_b
        self.int_tau_pinion += q
        if released or delta_b <= 0.0:
            self._event(t_end, "release", flank)
            st.flank = 0
        return t_end

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
        return roots.brent(delta_after, lo, h, fa=f_lo, fb=delta_b, xtol=1e-15)

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
            K = m.stiffness_sum(flank, self.phi_p(t + s * h))
            r.W_peak = max(r.W_peak, K * d**1.5)


def check_step_size(h: float, h_max: float) -> None:
    """Raise ValueError unless 0 < h <= h_max (the parameter solver.h_comm_max)."""
    if not (h > 0.0 and math.isfinite(h)):
        raise ValueError(f"step size h = {h!r} s is invalid; allowed: finite and > 0")
    if h > h_max:
        raise ValueError(
            f"step size h = {h!r} s exceeds solver.h_comm_max = {h_max!r} s; allowed: "
            f"(0, {h_max!r}] s")


def _check_finite(**values: float) -> None:
    for name, v in values.items():
        try:
            ok = math.isfinite(v)
        except TypeError:
            ok = False
        if not ok:
            raise ValueError(f"input {name} = {v!r} is not a finite number")
