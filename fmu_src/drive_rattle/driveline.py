"""The simple driveline around the mesh: the input shaft's prescribed kinematics (engine
orders or a measured speed table) and the output shaft as a torsional spring-damper to a
reflected vehicle inertia with drag.  Plain SI floats; knows nothing of FMI."""

from __future__ import annotations

import bisect
import csv
import math
import os
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

from .parameters import ParameterSet, declare
from .snapshots import check_fields
from .stepper import GRID_SLACK, check_step_size

RPM = 2.0 * math.pi / 60.0
#: Number of engine-order slots of the input-shaft kinematics.
N_ORDERS = 4
#: Largest speed-table file accepted [bytes]: 4 MiB, some 100 000 rows of "time,speed" -- far
#: more than a measured run-up needs; the table is kept in memory and in every FMU state.
MAX_SPEED_TABLE_BYTES = 4 * 1024 * 1024
#: Longest speed-table path accepted [bytes of its file-system encoding] (Linux PATH_MAX).
MAX_PATH_BYTES = 4096
#: Largest substep of the output shaft's RK4, relative to the time scale of its fastest mode
#: (1 / spectral radius of the linear spring-damper): below it RK4 is accurate to ~1e-9 per
#: substep; above it the shaft is integrated exactly (OutputShaft.step).
RK4_MAX_STEP_SCALE = 0.1


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
        "shaft.k", 0.2, "N.m/rad",
        "torsional stiffness of the output shaft (default: a very soft coupling, so that the "
        "wheel sees the nearly constant drag of the paper's M_res; see docs/model.md section 6)",
        minimum=1e-3, maximum=1e9)
    c_shaft: float = declare(
        "shaft.c", 0.005, "N.m.s/rad",
        "torsional damping of the output shaft (default light: see docs/model.md section 6)",
        minimum=0.0, maximum=1e6)
    J_vehicle: float = declare(
        "vehicle.J", 5.0, "kg.m2", "vehicle inertia reflected to the output shaft",
        minimum=1e-6, maximum=1e6)
    drag: float = declare(
        "vehicle.drag", 0.0833, "N.m",
        "constant drag torque on the vehicle side (creep load; default 0.5 M*, half the load "
        "the default engine orders can separate the default wheel from, M* = wheel.J "
        "z_p/z_w 250 rad/s^2 = 0.1667 N.m; see docs/model.md section 6)",
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
        self._setup(times, speeds, phi_0)

    @classmethod
    def from_table(cls, times, speeds, phi_0: float = 0.0,
                   source: str = "the speed table") -> SpeedTableKinematics:
        """The kinematics of a table already read (checked as :func:`read_speed_table`
        checks a file; ValueError naming ``source`` otherwise)."""
        times, speeds = check_speed_table(times, speeds, source)
        kin = cls.__new__(cls)
        kin._setup(times, speeds, phi_0)
        return kin

    def _setup(self, times: list[float], speeds: list[float], phi_0: float) -> None:
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


def _shorten(text: str, limit: int = 80) -> str:
    return text if len(text) <= limit else f"{text[:limit]}... ({len(text)} characters)"


def read_bounded_file(path: Path, limit: int, parameter: str) -> bytes:
    """The bytes of the regular file ``path``, at most ``limit`` of them, read once.

    Refused with a ValueError naming ``parameter``: a path longer than MAX_PATH_BYTES, a file
    that cannot be opened, anything but a regular file (a FIFO would block the reader
    forever, /dev/zero would fill the memory) and a file larger than ``limit``.  The file is
    opened non-blocking and checked on the open descriptor, so it cannot be swapped for a
    FIFO between the check and the read."""
    shown = _shorten(str(path))
    allowed = (f"allowed: a readable regular file of at most {limit} bytes, path at most "
               f"{MAX_PATH_BYTES} bytes")
    if "\0" in str(path):
        raise ValueError(f"parameter '{parameter}' = {shown!r} contains a NUL character; "
                         f"{allowed}")
    if len(os.fsencode(path)) > MAX_PATH_BYTES:
        raise ValueError(f"parameter '{parameter}' = {shown!r} is too long a path; {allowed}")
    try:
        info = os.stat(path)
        if not stat.S_ISREG(info.st_mode):
            raise ValueError(f"parameter '{parameter}' = {shown!r} is not a regular file "
                             f"({_file_kind(info.st_mode)}); {allowed}")
        flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
        fd = os.open(path, flags | getattr(os, "O_CLOEXEC", 0) | getattr(os, "O_BINARY", 0))
    except OSError as err:
        raise ValueError(f"parameter '{parameter}' = {shown!r} cannot be read: "
                         f"{err.strerror}; {allowed}") from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise ValueError(f"parameter '{parameter}' = {shown!r} is not a regular file "
                             f"({_file_kind(info.st_mode)}); {allowed}")
        if info.st_size > limit:
            raise ValueError(f"parameter '{parameter}' = {shown!r} has {info.st_size} bytes; "
                             f"{allowed}")
        chunks, total = [], 0
        while total <= limit:
            chunk = os.read(fd, min(1 << 20, limit + 1 - total))
            if not chunk:
                break
            chunks.append(chunk)
            total += len(chunk)
    except OSError as err:
        raise ValueError(f"parameter '{parameter}' = {shown!r} cannot be read: "
                         f"{err.strerror}; {allowed}") from None
    finally:
        os.close(fd)
    if total > limit:  # it grew while being read
        raise ValueError(f"parameter '{parameter}' = {shown!r} has more than {limit} bytes; "
                         f"{allowed}")
    return b"".join(chunks)


def _file_kind(mode: int) -> str:
    for test, kind in ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return kind
    return "not a regular file"


def read_speed_table(path: Path) -> tuple[list[float], list[float]]:
    """Read ``time [s], speed [rad/s]`` rows from a CSV file (a non-numeric first row is a
    header).  Raises ValueError naming the file and the row for malformed content, and naming
    the parameter for a file that cannot serve (see :func:`read_bounded_file`)."""
    path = Path(path)
    raw = read_bounded_file(path, MAX_SPEED_TABLE_BYTES, "engine.speed_table")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as err:
        raise ValueError(f"speed table {_shorten(str(path))!r} is not UTF-8 text "
                         f"(byte {err.start}); allowed: a CSV file of time [s], speed [rad/s]"
                         ) from None
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
    return check_speed_table(times, speeds, f"speed table {str(path)!r}")


def check_speed_table(times, speeds, source: str) -> tuple[list[float], list[float]]:
    """``(times, speeds)`` as lists of floats if they form a valid speed table: at least two
    rows, finite numbers, strictly increasing times; ValueError naming ``source`` otherwise."""
    if not (isinstance(times, (list, tuple)) and isinstance(speeds, (list, tuple))
            and len(times) == len(speeds)):
        raise ValueError(f"{source}: times and speeds must be two lists of equal length")
    if len(times) < 2:
        raise ValueError(f"{source} needs at least two rows")
    out_t, out_w = [], []
    for n, (t, w) in enumerate(zip(times, speeds, strict=True), start=1):
        if not all(isinstance(x, float) and math.isfinite(x) for x in (t, w)):
            raise ValueError(f"{source} row {n} = {(t, w)!r}: expected two finite floats")
        if out_t and t <= out_t[-1]:
            raise ValueError(f"{source} row {n}: time {t!r} s does not increase")
        out_t.append(t)
        out_w.append(w)
    return out_t, out_w


@dataclass
class ShaftState:
    """State of the output shaft's vehicle side (SI units)."""

    phi: float  # vehicle-side angle [rad]
    w: float  # vehicle-side speed [rad/s]


class OutputShaft:
    """Torsional spring-damper from the wheel to the reflected vehicle inertia with drag:

        tau_load = k (phi_w - phi_v) + c (w_w - w_v)      (torque resisting the wheel)
        J_v dw_v/dt = tau_load - drag - drag_viscous w_v

    Within a step the wheel moves at its step-start speed; RK4 on substeps <= h_max.  Where
    that substep is not small against the shaft's own time scales (stiff or heavily damped
    shafts on a light vehicle, e.g. shaft.c = 1e6 N.m.s/rad with vehicle.J = 1e-6 kg.m2, whose
    damping time J/c is 1e-12 s) the same linear equation is solved exactly instead, so that
    every legal parameter set integrates stably.
    """

    def __init__(self, p: DrivelineParameters, phi_w: float, w_w: float):
        self.p = p
        # Start in steady state: vehicle at the wheel speed, shaft wound up by the drag.
        steady = p.drag + p.drag_viscous * w_w
        self.state = ShaftState(phi_w - steady / p.k_shaft, w_w)
        self.tau_load = self.torque(phi_w, w_w, self.state)

    @classmethod
    def from_snapshot(cls, p: DrivelineParameters, state: ShaftState,
                      tau_load: float) -> OutputShaft:
        """The shaft in a saved state (no steady-state start)."""
        shaft = cls.__new__(cls)
        shaft.p = p
        shaft.state = ShaftState(state.phi, state.w)
        shaft.tau_load = tau_load
        return shaft

    def torque(self, phi_w: float, w_w: float, s: ShaftState) -> float:
        """Shaft torque on the wheel [N.m], positive resisting forward rotation."""
        return self.p.k_shaft * (phi_w - s.phi) + self.p.c_shaft * (w_w - s.w)

    def spectral_radius_bound(self) -> float:
        """An upper bound [1/s] of the magnitude of the shaft's eigenvalues (at most twice
        the largest): (c + drag_viscous)/J + sqrt(k/J)."""
        p = self.p
        return (p.c_shaft + p.drag_viscous) / p.J_vehicle + math.sqrt(p.k_shaft / p.J_vehicle)

    def step(self, h: float, phi_w: float, w_w: float) -> float:
        """Advance by h [s] with the wheel's step-start angle and speed; returns tau_load at
        the end of the step.  State is committed only on success."""
        p = self.p
        n = max(1, math.ceil(h / p.h_max * (1.0 - GRID_SLACK)))
        dt = h / n
        if dt * self.spectral_radius_bound() > RK4_MAX_STEP_SCALE:
            phi, w = self._exact(h, phi_w, w_w)
        else:
            phi, w = self._rk4(h, n, phi_w, w_w)
        if not (math.isfinite(phi) and math.isfinite(w)):
            raise ValueError("output shaft diverged: reduce solver.h_max")
        self.state = ShaftState(phi, w)
        self.tau_load = self.torque(phi_w + w_w * h, w_w, self.state)
        return self.tau_load

    def _rk4(self, h: float, n: int, phi_w: float, w_w: float) -> tuple[float, float]:
        p = self.p
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
        return phi, w

    def _exact(self, h: float, phi_w: float, w_w: float) -> tuple[float, float]:
        """The exact solution over h of the linear equation above.

        With the wheel at phi_w + w_w t, x_p(t) = phi_w + w_w t - (drag + drag_viscous w_w)/k,
        w_p = w_w solves it (the steadily wound shaft); the deviation e = (phi_v - x_p,
        w_v - w_w) obeys e' = A e with A = [[0, 1], [-k/J, -(c + drag_viscous)/J]], so
        e(h) = exp(A h) e(0).  exp(A h) is evaluated from the eigenvalues of A without
        overflow: both have non-positive real parts."""
        p = self.p
        g = (p.c_shaft + p.drag_viscous) / p.J_vehicle  # -trace(A) >= 0
        d = p.k_shaft / p.J_vehicle  # det(A) > 0
        offset = (p.drag + p.drag_viscous * w_w) / p.k_shaft
        e0 = self.state.phi - (phi_w - offset)
        f0 = self.state.w - w_w
        s = -0.5 * g
        q2 = 0.25 * g * g - d
        x2 = abs(q2) * h * h
        if x2 < 1e-6:  # near critical damping: series of cosh(qh), sinh(qh)/q in q^2 h^2
            es = math.exp(s * h)
            ch = 1.0 + 0.5 * q2 * h * h * (1.0 + q2 * h * h / 12.0)
            sh = h * (1.0 + q2 * h * h / 6.0 * (1.0 + q2 * h * h / 20.0))
            m11, m12 = es * (ch - s * sh), es * sh
            m21, m22 = -d * es * sh, es * (ch + (-g - s) * sh)
        elif q2 < 0.0:  # underdamped: exp(sh) (cos(wd h) I + sin(wd h)/wd (A - sI))
            wd = math.sqrt(-q2)
            es = math.exp(s * h)
            c, sn = es * math.cos(wd * h), es * math.sin(wd * h) / wd
            m11, m12 = c - s * sn, sn
            m21, m22 = -d * sn, c + (-g - s) * sn
        else:  # overdamped: real eigenvalues l2 < l1 < 0, l1 from l1 l2 = det (no cancellation)
            l2 = s - math.sqrt(q2)
            l1 = d / l2
            e1, e2 = math.exp(l1 * h), math.exp(l2 * h)
            span = l1 - l2
            m11, m12 = (l1 * e2 - l2 * e1) / span, (e1 - e2) / span
            m21, m22 = -d * (e1 - e2) / span, (l1 * e1 - l2 * e2) / span
        e1h = m11 * e0 + m12 * f0
        f1h = m21 * e0 + m22 * f0
        return phi_w + w_w * h - offset + e1h, w_w + f1h


def _exists(path: Path) -> bool:
    """Path.exists without raising (too long a name is an error there, not False)."""
    try:
        os.stat(path)
    except (OSError, ValueError):
        return False
    return True


def resolve_speed_table(name: str, resources: Path | None = None) -> Path:
    """The file a speed-table parameter names: a relative path is looked up in ``resources``
    (the FMU's resources folder) first, then in the working directory."""
    path = Path(name)
    if not path.is_absolute() and resources is not None and _exists(Path(resources) / path):
        path = Path(resources) / path
    return path


def input_kinematics(p: DrivelineParameters, t_start: float = 0.0,
                     resources: Path | None = None, table=None):
    """The input-shaft kinematics the parameters select: a speed table or engine orders.

    ``table`` = ``(times, speeds)`` is the speed table already read (nothing is read then);
    otherwise the file is read (see :func:`resolve_speed_table`)."""
    if p.speed_table:
        if table is None:
            return SpeedTableKinematics(resolve_speed_table(p.speed_table, resources),
                                        p.phi_start)
        return SpeedTableKinematics.from_table(*table, p.phi_start)
    return EngineOrderKinematics(p, t_start)


@dataclass(frozen=True)
class DrivelineSnapshot:
    """Everything the driveline needs to continue exactly where it was: the output shaft's
    vehicle-side state and torque, the time, the last communication step and the speed table
    read at the start (``(times, speeds)``, or None for engine orders)."""

    shaft: ShaftState
    tau_load: float
    time: float
    last_step: float
    table: tuple | None

    #: check_fields layout of ``to_json``.
    LAYOUT: ClassVar[dict] = {"shaft": ("f", "f", "f"), "time": ("=f",),
                              "last_step": ("=f+",), "table": ("any",)}

    def to_json(self) -> dict:
        """A JSON-able dict (floats round-trip exactly through repr-based JSON)."""
        table = None if self.table is None else [list(self.table[0]), list(self.table[1])]
        return {"shaft": [self.shaft.phi, self.shaft.w, self.tau_load], "time": self.time,
                "last_step": self.last_step, "table": table}

    @classmethod
    def from_json(cls, data) -> DrivelineSnapshot:
        """The snapshot of a ``to_json`` dict; ValueError naming the first invalid entry (the
        dict may come from a forged or corrupted FMU state; the table is checked when it is
        used, ``DrivelineModel.restore``)."""
        s = check_fields(data, cls.LAYOUT)
        table = s["table"]
        if table is not None and not (isinstance(table, list) and len(table) == 2):
            raise ValueError(f"model snapshot 'table' = {str(table)[:60]!r}: expected "
                             "[times, speeds] or null")
        phi, w, tau = s["shaft"]
        return cls(ShaftState(phi, w), tau, s["time"], s["last_step"],
                   None if table is None else (table[0], table[1]))


class DrivelineModel:
    """The driveline unit: input-shaft kinematics and output shaft, at communication points.

    ``phi_w``, ``w_w`` are the wheel's angle and speed at the start time; the shaft starts in
    steady state behind them.  ``table`` is the speed table already read (``(times, speeds)``,
    see :func:`read_speed_table`); without it the file the parameters name is read here, once.
    Like the wheel steppers it is advanced by ``step`` and saved and set whole with
    ``snapshot`` / ``restore`` (``from_snapshot``), which never start anything anew.
    """

    def __init__(self, p: DrivelineParameters, t_start: float, phi_w: float, w_w: float,
                 resources: Path | None = None, table=None):
        self.params = p
        self.t_start = t_start
        if p.speed_table and table is None:
            table = read_speed_table(resolve_speed_table(p.speed_table, resources))
        self._use_table(table if p.speed_table else None)
        self.shaft = OutputShaft(p, phi_w, w_w)
        self.time = t_start
        self.last_step = 0.0  # the last communication step [s]; 0 before the first

    def _use_table(self, table) -> None:
        """The input-shaft kinematics from ``table`` (``(times, speeds)``) or engine orders."""
        # Tuples: kept in every FMU state, which deep-copies lists item by item.
        self.table = None if table is None else (tuple(table[0]), tuple(table[1]))
        self.kinematics = input_kinematics(self.params, self.t_start, None, self.table)

    @classmethod
    def from_snapshot(cls, p: DrivelineParameters, t_start: float,
                      snapshot: DrivelineSnapshot) -> DrivelineModel:
        """The driveline in a saved state: the shaft as saved (no steady-state start) and the
        speed table as saved with it -- no file is read."""
        drive = cls.__new__(cls)
        drive.params = p
        drive.t_start = t_start
        drive.table = drive.kinematics = None
        drive.restore(snapshot)
        return drive

    def snapshot(self) -> DrivelineSnapshot:
        """The complete current state (a value: later steps do not change it)."""
        s = self.shaft
        return DrivelineSnapshot(ShaftState(s.state.phi, s.state.w), s.tau_load, self.time,
                                 self.last_step, self.table)

    def restore(self, snapshot: DrivelineSnapshot) -> None:
        """Set the complete state saved by :meth:`snapshot` (nothing is started anew, no file
        read).  ValueError, nothing changed, if the parameters name a speed table and the
        snapshot has none, or its table is invalid."""
        table = None
        if self.params.speed_table:
            if snapshot.table is None:
                raise ValueError("the saved driveline state lacks the speed table that "
                                 "parameter 'engine.speed_table' names")
            times, speeds = check_speed_table(*snapshot.table, "the saved speed table")
            table = (tuple(times), tuple(speeds))
        if self.kinematics is None or table != self.table:
            self._use_table(table)
        self.shaft = OutputShaft.from_snapshot(self.params, snapshot.shaft, snapshot.tau_load)
        self.time = snapshot.time
        self.last_step = snapshot.last_step

    def start_snapshot(self, phi_w: float, w_w: float) -> DrivelineSnapshot:
        """The current state with the output shaft started anew in steady state behind the
        wheel at ``phi_w`` [rad], ``w_w`` [rad/s], as the constructor starts it."""
        shaft = OutputShaft(self.params, phi_w, w_w)
        return DrivelineSnapshot(shaft.state, shaft.tau_load, self.time, self.last_step,
                                 self.table)

    def step(self, h: float, phi_w: float, w_w: float, *, t: float) -> None:
        """Advance by ``h`` [s] with the wheel's angle [rad] and speed [rad/s] at the step
        start ``t`` [s] (the communication point the step starts from: the input-shaft
        kinematics are functions of time, and the time is taken, never accumulated)."""
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
