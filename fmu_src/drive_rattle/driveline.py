"""The simple driveline around the mesh: the input shaft's prescribed kinematics (engine
orders or a measured speed table) and the output shaft as a torsional spring-damper to a
reflected vehicle inertia with drag.  Plain SI floats; knows nothing of FMI."""

from __future__ import annotations

import bisect
import csv
import math
from dataclasses import dataclass
from pathlib import Path

from .parameters import ParameterSet, declare
from .stepper import check_step_size

RPM = 2.0 * math.pi / 60.0
#: Number of engine-order slots of the input-shaft kinematics.
N_ORDERS = 4


def _order(k: int, default: float):
    return declare(f"engine.order[{k}]", default, "1",
                   f"engine order number of fluctuation slot {k} (cycles per revolution)",
                   minimum=0.1, maximum=100.0)


def _amplitude(k: int, default: float):
    return declare(f"engine.amplitude[{k}]", default, "rad/s2",
                   f"angular-acceleration amplitude of engine-order slot {k} (0 = off)",
                   minimum=0.0, maximum=1e6)


def _phase(k: int):
    return declare(f"engine.phase[{k}]", 0.0, "rad",
                   f"phase of the acceleration cosine of engine-order slot {k}",
                   minimum=-2.0 * math.pi, maximum=2.0 * math.pi, display_unit="deg")


@dataclass(frozen=True)
class DrivelineParameters(ParameterSet):
    """Parameters of the driveline (defaults: MODEL_NOTES section 3, creep rattle)."""

    # --- input shaft kinematics ---------------------------------------------------------
    w_mean: float = declare(
        "engine.w_mean", 830.0 * RPM, "rad/s", "mean input-shaft (engine) speed",
        minimum=1.0, maximum=2000.0, display_unit="rpm")
    # Engine orders: up to N_ORDERS slots; a slot with zero amplitude is off.
    order_1: float = _order(1, 2.0)
    amplitude_1: float = _amplitude(1, 300.0)
    phase_1: float = _phase(1)
    order_2: float = _order(2, 4.0)
    amplitude_2: float = _amplitude(2, 200.0)
    phase_2: float = _phase(2)
    order_3: float = _order(3, 6.0)
    amplitude_3: float = _amplitude(3, 150.0)
    phase_3: float = _phase(3)
    order_4: float = _order(4, 8.0)
    amplitude_4: float = _amplitude(4, 0.0)
    phase_4: float = _phase(4)
    phi_start: float = declare(
        "pinion.phi_start", 0.0, "rad", "input-shaft angle at the start time",
        display_unit="deg")
    a_over_step: bool = declare(
        "pinion.a_over_step", True, "",
        "output as pinion.a the mean acceleration over the coming step, (w(t+h) - w(t))/h with "
        "h the last communication step, so that the mesh's Taylor polynomial of the pinion "
        "keeps the pinion speed continuous from step to step; false = the instantaneous "
        "acceleration (its speed error at the step end, jerk*h^2/2, then jumps at every "
        "communication point)")
    speed_table: str = declare(
        "engine.speed_table", "", "",
        "CSV file of measured input-shaft speed (columns: time [s], speed [rad/s]; header "
        "optional); relative paths resolve against the FMU resources; empty = engine orders")
    # --- output shaft and vehicle --------------------------------------------------------
    k_shaft: float = declare(
        "shaft.k", 2.0, "N.m/rad",
        "torsional stiffness of the output shaft (default: a soft coupling, so that the wheel "
        "sees nearly the constant drag like the paper's M_res)",
        minimum=1e-3, maximum=1e9)
    c_shaft: float = declare(
        "shaft.c", 0.005, "N.m.s/rad",
        "torsional damping of the output shaft (default light: see docs/model.md section 6)",
        minimum=0.0, maximum=1e6)
    J_vehicle: float = declare(
        "vehicle.J", 5.0, "kg.m2", "vehicle inertia reflected to the output shaft",
        minimum=1e-6, maximum=1e6)
    drag: float = declare(
        "vehicle.drag", 0.15, "N.m",
        "constant drag torque on the vehicle side (creep load; default calibrated, see "
        "docs/model.md section 6)",
        minimum=-1e5, maximum=1e5)
    drag_viscous: float = declare(
        "vehicle.drag_viscous", 0.0, "N.m.s/rad", "speed-proportional drag coefficient",
        minimum=0.0, maximum=1e5)
    h_max: float = declare(
        "solver.h_max", 1e-4, "s", "largest integration substep of the output shaft",
        minimum=1e-8, maximum=1.0)
    h_comm_max: float = declare(
        "solver.h_comm_max", 1.0, "s",
        "largest communication step accepted: a guard against absurd steps (a step costs "
        "h/solver.h_max substeps), not an accuracy limit; the wheel is extrapolated linearly "
        "over a step, accuracy against the step in docs/tools.md",
        minimum=1e-7, maximum=1.0)

    def order_terms(self) -> list[tuple[float, float, float]]:
        """``(order, amplitude [rad/s^2], phase [rad])`` of the active engine orders."""
        return [
            (getattr(self, f"order_{k}"), getattr(self, f"amplitude_{k}"),
             getattr(self, f"phase_{k}"))
            for k in range(1, N_ORDERS + 1)
            if getattr(self, f"amplitude_{k}") != 0.0
        ]


class EngineOrderKinematics:
    """Input-shaft motion from engine orders (MODEL_NOTES section 3):

        a(t)   = sum_k A_k cos(W_k t + p_k),            W_k = order_k * w_mean
        w(t)   = w_mean + sum_k A_k / W_k sin(W_k t + p_k)
        phi(t) = phi_0 + w_mean t - sum_k A_k / W_k^2 (cos(W_k t + p_k) - cos p_k)

    so the mean speed is exactly ``w_mean`` and the three signals are mutually consistent.
    """

    def __init__(self, p: DrivelineParameters, t_start: float = 0.0):
        self.w_mean = p.w_mean
        self.phi_0 = p.phi_start
        self.t_start = t_start
        self.terms = [(A, k * p.w_mean, ph) for k, A, ph in p.order_terms()]

    def __call__(self, t: float) -> tuple[float, float, float]:
        """``(phi [rad], w [rad/s], a [rad/s^2])`` at time t [s]."""
        tau = t - self.t_start
        phi = self.phi_0 + self.w_mean * tau
        w, a = self.w_mean, 0.0
        for A, W, ph in self.terms:
            arg = W * tau + ph
            phi -= A / (W * W) * (math.cos(arg) - math.cos(ph))
            w += A / W * math.sin(arg)
            a += A * math.cos(arg)
        return phi, w, a


class SpeedTableKinematics:
    """Input-shaft motion from a measured speed table: speed is linear between samples, the
    angle its exact integral, the acceleration its slope.  Held constant beyond the table."""

    def __init__(self, path: Path, phi_0: float = 0.0):
        times, speeds = read_speed_table(path)
        self.times, self.speeds = times, speeds
        self.phi_0 = phi_0
        # Angle at each sample: trapezoidal integral (exact for piecewise-linear speed).
        self.angles = [phi_0]
        for i in range(1, len(times)):
            dt = times[i] - times[i - 1]
            self.angles.append(self.angles[-1] + 0.5 * dt * (speeds[i] + speeds[i - 1]))

    def __call__(self, t: float) -> tuple[float, float, float]:
        ts, ws = self.times, self.speeds
        if t <= ts[0]:
            return self.phi_0 + ws[0] * (t - ts[0]), ws[0], 0.0
        if t >= ts[-1]:
            return self.angles[-1] + ws[-1] * (t - ts[-1]), ws[-1], 0.0
        i = bisect.bisect_right(ts, t) - 1
        dt = t - ts[i]
        a = (ws[i + 1] - ws[i]) / (ts[i + 1] - ts[i])
        return self.angles[i] + ws[i] * dt + 0.5 * a * dt * dt, ws[i] + a * dt, a


def read_speed_table(path: Path) -> tuple[list[float], list[float]]:
    """Read ``time [s], speed [rad/s]`` rows from a CSV file (a non-numeric first row is a
    header).  Raises ValueError naming the file and the row for malformed content."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as err:
        raise ValueError(
            f"parameter 'engine.speed_table' = {str(path)!r} cannot be read: {err.strerror}; "
            "allowed: a readable CSV file of time [s], speed [rad/s], or empty for the engine "
            "orders") from None
    times: list[float] = []
    speeds: list[float] = []
    for n, row in enumerate(csv.reader(text.splitlines()), start=1):
        if not row or not "".join(row).strip():
            continue
        try:
            t, w = float(row[0]), float(row[1])
        except (ValueError, IndexError):
            if n == 1:
                continue  # header
            raise ValueError(
                f"speed table {str(path)!r} row {n} = {row!r}: expected two numbers "
                "(time [s], speed [rad/s])") from None
        if not (math.isfinite(t) and math.isfinite(w)):
            raise ValueError(f"speed table {str(path)!r} row {n} has a non-finite value")
        if times and t <= times[-1]:
            raise ValueError(
                f"speed table {str(path)!r} row {n}: time {t!r} s does not increase")
        times.append(t)
        speeds.append(w)
    if len(times) < 2:
        raise ValueError(f"speed table {str(path)!r} needs at least two rows")
    return times, speeds


@dataclass
class ShaftState:
    """State of the output shaft's vehicle side (SI units)."""

    phi: float  # vehicle-side angle [rad]
    w: float  # vehicle-side speed [rad/s]


class OutputShaft:
    """Torsional spring-damper from the wheel to the reflected vehicle inertia with drag:

        tau_load = k (phi_w - phi_v) + c (w_w - w_v)      (torque resisting the wheel)
        J_v dw_v/dt = tau_load - drag - drag_viscous w_v

    Within a step the wheel moves at its step-start speed; RK4 on substeps <= h_max.
    """

    def __init__(self, p: DrivelineParameters, phi_w: float, w_w: float):
        self.p = p
        # Start in steady state: vehicle at the wheel speed, shaft wound up by the drag.
        steady = p.drag + p.drag_viscous * w_w
        self.state = ShaftState(phi_w - steady / p.k_shaft, w_w)
        self.tau_load = self.torque(phi_w, w_w, self.state)

    def torque(self, phi_w: float, w_w: float, s: ShaftState) -> float:
        """Shaft torque on the wheel [N.m], positive resisting forward rotation."""
        return self.p.k_shaft * (phi_w - s.phi) + self.p.c_shaft * (w_w - s.w)

    def step(self, h: float, phi_w: float, w_w: float) -> float:
        """Advance by h [s] with the wheel's step-start angle and speed; returns tau_load at
        the end of the step.  State is committed only on success."""
        p = self.p
        n = max(1, math.ceil(h / p.h_max * (1.0 - 1e-12)))
        dt = h / n
        phi, w = self.state.phi, self.state.w

        def acc(t: float, phi_v: float, w_v: float) -> float:
            tau = p.k_shaft * (phi_w + w_w * t - phi_v) + p.c_shaft * (w_w - w_v)
            return (tau - p.drag - p.drag_viscous * w_v) / p.J_vehicle

        for j in range(n):
            t = h * j / n
            a1 = acc(t, phi, w)
            a2 = acc(t + 0.5 * dt, phi + 0.5 * dt * w, w + 0.5 * dt * a1)
            a3 = acc(t + 0.5 * dt, phi + 0.5 * dt * (w + 0.5 * dt * a1), w + 0.5 * dt * a2)
            a4 = acc(t + dt, phi + dt * (w + 0.5 * dt * a2), w + dt * a3)
            phi += dt * (w + dt / 6.0 * (a1 + a2 + a3))
            w += dt / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4)
        if not (math.isfinite(phi) and math.isfinite(w)):
            raise ValueError("output shaft diverged: reduce solver.h_max")
        self.state = ShaftState(phi, w)
        self.tau_load = self.torque(phi_w + w_w * h, w_w, self.state)
        return self.tau_load


def input_kinematics(p: DrivelineParameters, t_start: float = 0.0,
                     resources: Path | None = None):
    """The input-shaft kinematics the parameters select: a speed table or engine orders.

    A relative speed-table path is looked up in ``resources`` (the FMU's resources folder)
    first, then in the working directory."""
    if p.speed_table:
        path = Path(p.speed_table)
        if not path.is_absolute() and resources is not None and (Path(resources) / path).exists():
            path = Path(resources) / path
        return SpeedTableKinematics(path, p.phi_start)
    return EngineOrderKinematics(p, t_start)


class Driveline:
    """The driveline unit: input-shaft kinematics and output shaft, at communication points.

    ``phi_w``, ``w_w`` are the wheel's angle and speed at the start time; the shaft starts in
    steady state behind them."""

    def __init__(self, p: DrivelineParameters, t_start: float, phi_w: float, w_w: float,
                 resources: Path | None = None):
        self.params = p
        self.kinematics = input_kinematics(p, t_start, resources)
        self.shaft = OutputShaft(p, phi_w, w_w)
        self.time = t_start
        self.last_step = 0.0  # the last communication step [s]; 0 before the first

    def step(self, t: float, h: float, phi_w: float, w_w: float) -> None:
        """Advance from the communication point t by h with the wheel's angle and speed at t."""
        check_step_size(h, self.params.h_comm_max)
        self.shaft.step(h, phi_w, w_w)
        self.time = t + h
        self.last_step = h

    def outputs(self) -> dict[str, float]:
        """Values of the driveline outputs now (SI units, public names).

        With ``pinion.a_over_step``, ``pinion.a`` is the mean acceleration over the coming
        step (taken as long as the last one): the mesh then moves the pinion at exactly its
        speed at the next communication point, and the pinion speed it sees is continuous.
        A quadratic with the instantaneous acceleration misses the end speed by jerk*h^2/2,
        2e-5 m/s on the tooth normal at a 1e-4 s step in the paper scenario; that jump at
        every communication point pumps energy into the contacts (docs/model.md, section 6)."""
        phi, w, a = self.kinematics(self.time)
        h = self.last_step
        if self.params.a_over_step and h > 0.0:
            a = (self.kinematics(self.time + h)[1] - w) / h
        return {"pinion.phi": phi, "pinion.w": w, "pinion.a": a,
                "wheel.tau_load": self.shaft.tau_load, "vehicle.w": self.shaft.state.w}
