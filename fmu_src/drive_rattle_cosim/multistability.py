"""Multistability of the rattle measured, not denied: a grid of operating points (load x
backlash), each run from several starts until its statistics are stationary, the start
transient detected and dropped, and every point reported as single-valued or multistable with
the statistics of each attractor.

Impacting gear pairs have coexisting periodic orbits and chaotic transients at some loads and
backlashes (MODEL_NOTES section 5; docs/analysis.md section 7).  Which one a run shows depends
on how it started, so one run per point does not describe the point.  This study runs each
point from the starts of :data:`STARTS` --

* ``smooth``: the static flank equilibrium for the load (``init.in_contact``);
* ``kick -1``, ``kick +1``, ``kick +5``: that equilibrium with the wheel's speed changed by
  -1, +1, +5 rad/s;
* ``free``: the wheel at the centre of the backlash at the rigid speed, no flank in contact;
* ``phase 1/3``, ``phase 2/3``: the smooth start with the engine orders shifted by a third and
  two thirds of the forcing period (the run starts at another point of the forcing cycle);
* with ``--phases N`` (:func:`phase_starts`), the smooth start at N evenly spaced points of
  the forcing cycle besides: a state whose basin is small can lie between the seven --

on the paper's model by default (``vehicle.model`` = 1: the pinion kinematic from the engine
orders, the wheel under the constant load M_res; loads relative to the separation load M*,
:func:`separation_load`), on one of two engines (``--engine``):

* ``library`` (the default): the model library's compiled coupled loop (:class:`LibraryEngine`);
* ``fmu``: the FMUs of ``--fmu-dir`` (FMI 2.0 or 3.0) coupled by the fmpy harness
  (:class:`FmuEngine`): every parameter of the start set before initialization, the harness's
  initialization and nanosecond grid.  These are the library's calls, so a start runs the same
  trajectory bit for bit on both engines and reaches the same state (tested); only the onsets
  differ in how they are known (the FMUs output counters, not located times), which can move
  an onset into the next window where its step straddles a window's end.

Each run is cut into windows of a whole, even number of forcing periods (about ``window``
seconds; the forcing repeats with the greatest common period of the orders and the mesh, 36 ms
at 830 rpm, and an even number holds whole period-doubled orbits).  Per window: onsets per
second on each flank, the 10/50/90th percentile of the onset speeds per flank, the impact
energy rate, the peak penetration and the pairs in contact (mean over the in-contact samples).
A run goes on in chunks from ``min_time`` until it is **settled** or reaches ``max_time`` (then
it is reported as unsettled: a chaotic transient longer than the cap).  The **transient** ends
at the truncation point of the marginal standard error rule (MSER, White 1997: the first window
from which dropping more windows no longer lowers the standard error of the mean of the rest),
on the signature statistics (below) together, each scaled by its variance over the run's
second half, searched in the run's first half.  A run is settled when that end lies inside its
first half and the windows kept are stationary: the means of their two halves agree within 4
standard errors plus a floor per statistic (2 onsets per window, 0.3 % of the penetration,
0.005 pairs, 1 % of the energy rate).  An attractor's statistics are the mean and the
window-to-window standard deviation over the windows kept.  A point whose starts disagree has
every run that stopped early run again to ``max_time``, so that each attractor it reports
persists for the whole cap.

Two settled starts reach the **same attractor** when every signature statistic (onsets per
second per flank, energy rate, peak penetration, pairs) agrees within twice the root sum of
squares of their window scatters plus the floor; otherwise they are told apart.  A point is
*single-valued* when all its starts settled on one attractor, *multistable* with two or more,
and *unsettled* when a start did not settle and the settled ones found at most one.

    python -m drive_rattle_cosim.multistability [--loads 0.3,0.4,0.5,0.6,0.8,1.0]
        [--backlash 0.1e-3,0.2e-3] [--starts smooth,kick-1,...] [--phases 24] [--min-time 20]
        [--max-time 60] [--window 1] [--workers 2] [--set GearMeshRattle.NAME=VALUE]
        [--engine library|fmu] [--fmu-dir dist/fmi3] [--out out/multistability.md]

The runs go to a pool, ``--workers`` at a time: threads on the library engine (the library's
calls release the GIL; its units share no state), processes on the FMU engine (the harness's
loop is Python).
"""

from __future__ import annotations

import json
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor
from dataclasses import asdict, dataclass, field, replace
from fractions import Fraction
from pathlib import Path

import numpy as np

from drive_rattle.parameters import DrivelineParameters, MeshParameters
from drive_rattle.units import DrivelineUnit, MeshUnit, coupled_start_inputs, run_coupled

DRIVE, COAST = 1, -1

#: Statistics of a window, in report order: name -> (label, unit factor for printing).
STATISTICS = {
    "drive_rate": ("drive onsets [1/s]", 1.0),
    "coast_rate": ("coast onsets [1/s]", 1.0),
    "drive_p10": ("drive v p10 [mm/s]", 1e3),
    "drive_p50": ("drive v p50 [mm/s]", 1e3),
    "drive_p90": ("drive v p90 [mm/s]", 1e3),
    "coast_p10": ("coast v p10 [mm/s]", 1e3),
    "coast_p50": ("coast v p50 [mm/s]", 1e3),
    "coast_p90": ("coast v p90 [mm/s]", 1e3),
    "energy_rate": ("impact energy rate [mW]", 1e3),
    "delta_max": ("δmax [µm]", 1e6),
    "pairs": ("pairs in contact", 1.0),
}
#: The statistics that tell attractors apart and detect the transient, with their floors:
#: (absolute floor, relative floor).  The counts' floor is two onsets per window (a window of
#: whole forcing periods need not hold whole periods of a longer orbit).
SIGNATURE = {
    "drive_rate": (2.0, 0.0),  # per window, divided by the window length where used
    "coast_rate": (2.0, 0.0),
    "energy_rate": (0.0, 0.01),
    "delta_max": (0.0, 0.003),
    "pairs": (0.005, 0.0),
}
#: Attractors differ when a signature statistic differs by more than this many root sums of
#: squares of their window scatters (plus the floor).
SEPARATION = 2.0
#: The fewest windows in each half of a settled run's kept windows.
MIN_REFERENCE_WINDOWS = 5


@dataclass(frozen=True)
class Start:
    """How a run starts: the smooth start (the static flank equilibrium), changed by a speed
    kick on the wheel [rad/s], or the free start (mid-backlash at the rigid speed), with the
    engine orders shifted by ``phase`` forcing periods."""

    name: str
    kick: float = 0.0
    free: bool = False
    phase: float = 0.0


STARTS = (
    Start("smooth"),
    Start("kick -1", kick=-1.0),
    Start("kick +1", kick=1.0),
    Start("kick +5", kick=5.0),
    Start("free", free=True),
    Start("phase 1/3", phase=1.0 / 3.0),
    Start("phase 2/3", phase=2.0 / 3.0),
)
STARTS_BY_KEY = {s.name.replace(" ", ""): s for s in STARTS}
#: The most phase starts :func:`phase_starts` makes.
MAX_PHASES = 360


def phase_starts(n: int) -> tuple[Start, ...]:
    """The smooth start at ``n`` evenly spaced points of the forcing cycle: ``phase k/n`` for
    k = 1 .. n - 1 (k = 0 is ``smooth``).  A state with a small basin can lie between the
    seven :data:`STARTS`: at 0.4 M* and 0.2 mm (default physics) a periodic orbit is reached
    from 4 of the 23 starts of ``phase_starts(24)`` and from none of the seven
    (docs/analysis.md section 7)."""
    if not (isinstance(n, int) and not isinstance(n, bool) and 1 <= n <= MAX_PHASES):
        raise ValueError(f"phases = {n!r}: expected an integer in [1, {MAX_PHASES}]")
    return tuple(Start(f"phase {k}/{n}", phase=k / n) for k in range(1, n))


def with_phase_starts(starts, n: int) -> list[Start]:
    """``starts``, then those of :func:`phase_starts` (``n``) at a phase none of them has
    already (a smooth start shifted by that fraction of the period: phase 8/24 is phase 1/3)."""
    taken = {Fraction(s.phase).limit_denominator(MAX_PHASES) for s in starts
             if not s.kick and not s.free}
    return [*starts, *(s for s in phase_starts(n)
                       if Fraction(s.phase).limit_denominator(MAX_PHASES) not in taken)]


def forcing_period(mesh: MeshParameters, drive: DrivelineParameters) -> float:
    """The period [s] of the forcing: the largest of which the mesh (z_p per revolution) and
    every active engine order repeat (36.1 ms for orders 2, 4, 6, z_p = 20 at 830 rpm)."""
    g = Fraction(mesh.z_pinion)
    for order, _, _ in drive.order_terms():
        q = Fraction(order).limit_denominator(64)
        g = Fraction(math.gcd(g.numerator * q.denominator, q.numerator * g.denominator),
                     g.denominator * q.denominator)
    return 2.0 * math.pi / (float(g) * drive.w_mean)


def deepest_deceleration(drive: DrivelineParameters, samples: int = 20000) -> float:
    """The pinion's deepest angular deceleration [rad/s^2] over a forcing period of its engine
    orders (250 rad/s^2 for the defaults), sampled finely."""
    terms = drive.order_terms()
    if not terms:
        return 0.0
    lowest = min(k for k, _, _ in terms)
    t = np.linspace(0.0, 2.0 * math.pi / (lowest * drive.w_mean) * 64, samples * 64,
                    endpoint=False)
    a = sum(A * np.cos(k * drive.w_mean * t + p) for k, A, p in terms)
    return float(-np.min(a))


def separation_load(mesh: MeshParameters | None = None,
                    drive: DrivelineParameters | None = None) -> float:
    """M* = I_w (z_p / z_w) max(-a_p) [N.m]: below this load the engine orders separate the
    teeth quasi-statically (docs/model.md 6.1; 0.1667 N.m for the defaults)."""
    mesh = mesh or MeshParameters()
    drive = drive or DrivelineParameters()
    return mesh.J_wheel * mesh.z_pinion / mesh.z_wheel * deepest_deceleration(drive)


def paper_driveline(load: float, drive: DrivelineParameters | None = None
                    ) -> DrivelineParameters:
    """The paper's model: the pinion from the engine orders, the wheel under the constant load
    ``load`` [N.m] (``vehicle.model`` = 1)."""
    return replace(drive or DrivelineParameters(), vehicle_model=1, drag=load)


def start_parameters(mesh: MeshParameters, drive: DrivelineParameters, start: Start
                     ) -> tuple[MeshParameters, DrivelineParameters]:
    """The parameter sets of a run from ``start``."""
    if start.phase:
        # the same forcing started tau later in its cycle: phi'(t) = phi(t + tau), so the
        # orders' phases move by W_k tau and the start angle by w tau plus the orders' part
        tau = start.phase * forcing_period(mesh, drive)
        shifted = {}
        phi_0 = drive.phi_start + drive.w_mean * tau
        for k in range(1, 5):
            A, p = getattr(drive, f"amplitude_{k}"), getattr(drive, f"phase_{k}")
            W = getattr(drive, f"order_{k}") * drive.w_mean
            q = math.remainder(p + W * tau, 2.0 * math.pi)
            shifted[f"phase_{k}"] = q
            phi_0 += A / (W * W) * (math.cos(p) - math.cos(q))
        drive = replace(drive, phi_start=phi_0, **shifted)
    if start.kick or start.free:
        mesh_in, wheel = coupled_start_inputs(mesh, drive)
        if start.free:  # the centre of the backlash against the start's pinion angle
            ratio = mesh.z_pinion / mesh.z_wheel
            phi, w = ratio * mesh_in["pinion.phi"], ratio * mesh_in["pinion.w"]
        else:
            phi, w = wheel["wheel.phi"], wheel["wheel.w"]
        mesh = replace(mesh, init_in_contact=False, phi_start=phi, w_start=w + start.kick)
    return mesh, drive


@dataclass
class StartRun:
    """One run of one start: its per-window statistics and where its transient ends."""

    start: str
    window: float  # [s]
    windows: dict[str, list[float]]  # statistic -> value per window
    transient_windows: int = 0  # windows dropped as the start transient
    settled: bool = False
    seconds: float = 0.0  # simulated
    wall: float = 0.0  # [s]

    @property
    def n_windows(self) -> int:
        return len(self.windows["drive_rate"])

    @property
    def transient(self) -> float:
        """The start transient [s]."""
        return self.transient_windows * self.window

    def kept(self, name: str) -> np.ndarray:
        return np.asarray(self.windows[name][self.transient_windows:], dtype=float)

    def mean(self, name: str) -> float:
        v = self.kept(name)
        v = v[np.isfinite(v)]
        return float(np.mean(v)) if v.size else math.nan

    def scatter(self, name: str) -> float:
        v = self.kept(name)
        v = v[np.isfinite(v)]
        return float(np.std(v, ddof=1)) if v.size > 1 else math.nan


def _floor(name: str, value: float, window: float) -> float:
    absolute, relative = SIGNATURE[name]
    if name.endswith("_rate") and name != "energy_rate":
        absolute /= window
    return absolute + relative * abs(value)


def _mser_scores(x: np.ndarray, last: int) -> np.ndarray:
    """The marginal standard error rule's score of a series (White 1997) for truncation points
    d = 0 ... last: sum_{j >= d} (x_j - mean_d)^2 / (n - d)^2, mean_d the mean of x[d:]."""
    n = x.size
    k = np.arange(n, 0, -1)  # the length of the tail from window d = 0, 1, ..., n - 1
    total = np.cumsum(x[::-1])[::-1]  # sum of x[d:]
    squares = np.cumsum((x * x)[::-1])[::-1]
    var_sum = np.maximum(squares - total * total / k, 0.0)  # sum of squares about its mean
    return var_sum[: last + 1] / (k[: last + 1] * k[: last + 1])


def _settle(run: StartRun) -> None:
    """The end of the start transient and whether the run is settled (module docstring): the
    truncation point of the marginal standard error rule on the signature statistics together
    (each scaled by its variance over the run's second half plus its floor squared), searched
    in the first half.  Settled when it ends inside the first half and the kept windows are
    stationary: the means of their two halves agree within 4 standard errors plus the floor."""
    n = run.n_windows
    score = np.zeros(n // 2 + 1)
    for name in SIGNATURE:
        x = np.asarray(run.windows[name], dtype=float)
        second = x[n - n // 2:]
        scale = float(np.var(second)) + _floor(name, float(np.mean(second)), run.window) ** 2
        if scale > 0.0:
            score += _mser_scores(x, n // 2) / scale
    cut = int(np.argmin(score))  # the earliest of equal ones (a periodic orbit: zero)
    run.transient_windows = cut
    # (a truncation at the end of the search, the first half, may lie beyond it)
    settled = n - cut >= 2 * MIN_REFERENCE_WINDOWS and cut < n // 2
    for name in SIGNATURE:
        if not settled:
            break
        x = np.asarray(run.windows[name][cut:], dtype=float)
        a, b = x[: x.size // 2], x[x.size // 2:]
        se = math.sqrt(np.var(a, ddof=1) / a.size + np.var(b, ddof=1) / b.size)
        gap = abs(float(np.mean(a)) - float(np.mean(b)))
        settled = gap <= 4.0 * se + _floor(name, float(np.mean(x)), run.window)
    run.settled = settled


class _Record:
    """The samples of a run so far: time, peak penetration and pairs per communication point,
    and the onsets."""

    def __init__(self):
        self.t, self.delta, self.pairs = [], [], []
        self.onset_t, self.onset_v, self.onset_f = [], [], []

    def add(self, chunk: Chunk, first: bool) -> None:
        k0 = 0 if first else 1  # a chunk's first point is the last one of the chunk before
        self.t.append(np.asarray(chunk.time, dtype=float)[k0:])
        self.delta.append(np.asarray(chunk.delta_peak, dtype=float)[k0:])
        self.pairs.append(np.asarray(chunk.n_contact, dtype=float)[k0:])
        self.onset_t += list(chunk.onset_times)
        self.onset_v += list(chunk.onset_speeds)
        self.onset_f += list(chunk.onset_flanks)

    def windows(self, window: float, normal_mass: float) -> dict[str, list[float]]:
        t = np.concatenate(self.t)
        delta, pairs = np.concatenate(self.delta), np.concatenate(self.pairs)
        t0 = t[0]
        n = math.floor((t[-1] - t0) / window * (1 + 1e-12))
        out: dict[str, list[float]] = {name: [] for name in STATISTICS}
        # a sample closes the step that ends at it: window i holds (t0 + i W, t0 + (i+1) W]
        index = np.ceil((t - t0) / window * (1 - 1e-12)).astype(np.int64) - 1
        ot = np.asarray(self.onset_t, dtype=float)
        ov = np.asarray(self.onset_v, dtype=float)
        of = np.asarray(self.onset_f, dtype=int)
        o_index = np.ceil((ot - t0) / window * (1 - 1e-12)).astype(np.int64) - 1
        for i in range(n):
            in_w = index == i
            d, p = delta[in_w], pairs[in_w]
            out["delta_max"].append(float(np.max(d)) if d.size else math.nan)
            touching = p[p > 0]
            out["pairs"].append(float(np.mean(touching)) if touching.size else 0.0)
            sel = o_index == i
            energy = 0.0
            for flank, name in ((DRIVE, "drive"), (COAST, "coast")):
                v = ov[sel & (of == flank)]
                out[f"{name}_rate"].append(v.size / window)
                for q in (10, 50, 90):
                    out[f"{name}_p{q}"].append(float(np.percentile(v, q)) if v.size
                                               else math.nan)
                energy += 0.5 * normal_mass * float(np.sum(v * v))
            out["energy_rate"].append(energy / window)
        return out


#: The engines a start runs on (``run_start``).
ENGINES = ("library", "fmu")


@dataclass
class Chunk:
    """A stretch of a run: every communication point from the stretch's start, the mesh's
    ``mesh.delta_peak`` and ``mesh.n_contact`` there, and the contact onsets after its first
    point (time [s], normal approach speed [m/s], flank)."""

    time: np.ndarray
    delta_peak: np.ndarray
    n_contact: np.ndarray
    onset_times: list
    onset_speeds: list
    onset_flanks: list


class LibraryEngine:
    """A start in the model library's compiled coupled loop (``units.run_coupled``): its two
    units started at the coupled start (``coupled_start_inputs``), and the onsets located
    in time by the mesh's stepper."""

    RECORDED = ("GearMeshRattle.mesh.delta_peak", "GearMeshRattle.mesh.n_contact")

    def __init__(self, mesh: MeshParameters, drive: DrivelineParameters, step: float):
        self.step_ns = round(step * 1e9)
        mesh_in, wheel = coupled_start_inputs(mesh, drive)
        self.mesh = MeshUnit(mesh, mesh_in["pinion.phi"], mesh_in["pinion.w"],
                             mesh_in["wheel.tau_load"], mesh_in["pinion.a"])
        try:
            self.drive = DrivelineUnit(drive, wheel["wheel.phi"], wheel["wheel.w"])
        except BaseException:
            self.mesh.close()
            raise

    @property
    def time(self) -> float:
        return self.mesh.time

    def advance(self, steps: int) -> Chunk:
        start_ns = round(self.mesh.time * 1e9)
        run = run_coupled(self.mesh, self.drive, self.step_ns, steps, list(self.RECORDED))
        return Chunk((start_ns + np.arange(run.steps + 1, dtype=np.int64) * self.step_ns) / 1e9,
                     np.asarray(run.column_buffer(self.RECORDED[0])),
                     np.asarray(run.column_buffer(self.RECORDED[1])),
                     run.onset_times, run.onset_speeds, run.onset_flanks)

    def close(self) -> None:
        self.mesh.close()
        self.drive.close()


class FmuEngine:
    """A start through the FMUs of ``fmu_dir`` (FMI 2.0 or 3.0) coupled by the fmpy harness:
    every parameter of both units set before initialization (the start's parameter sets,
    ``start_parameters``), the harness's initialization and its nanosecond grid -- the
    library's calls, so the same trajectory bit for bit (tested).  The FMUs do not output the
    located onsets: they are read from the mesh's counters (``analysis.onsets_from_counters``:
    dated to the communication point that closes their step, several in one step sharing the
    last one's speed), so the windows' onset statistics can differ from the library engine's
    in the last places where an onset's step straddles a window's end or holds two onsets."""

    RECORDED = tuple(f"GearMeshRattle.{n}" for n in ("mesh.delta_peak", "mesh.n_contact",
                                                      "mesh.impacts_drive", "mesh.impacts_coast",
                                                      "mesh.v_impact"))

    def __init__(self, mesh: MeshParameters, drive: DrivelineParameters, step: float,
                 fmu_dir: Path, grid: str = "nanoseconds"):
        """``grid``: how the points are placed (``harness.time_grid``; another master's
        arithmetic, to see which state a start reaches there)."""
        from .harness import CoSimulation

        parameters = {**{f"GearMeshRattle.{k}": v for k, v in mesh.to_public().items()},
                      **{f"Driveline.{k}": v for k, v in drive.to_public().items()}}
        self.sim = CoSimulation(Path(fmu_dir) / "GearMeshRattle.fmu",
                                Path(fmu_dir) / "Driveline.fmu", parameters, step=step)
        self.step, self.grid = step, grid

    @property
    def time(self) -> float:
        return self.sim.time

    def advance(self, steps: int) -> Chunk:
        from .analysis import onsets_from_counters

        stop = (round(self.sim.time * 1e9) + steps * round(self.step * 1e9)) / 1e9
        res = self.sim.run(stop, list(self.RECORDED), grid=self.grid)
        delta, pairs, drive, coast, speed = (res[name] for name in self.RECORDED)
        times, speeds, flanks = onsets_from_counters(res.time, drive, coast, speed)
        return Chunk(np.asarray(res.time), np.asarray(delta), np.asarray(pairs), times, speeds,
                     flanks)

    def close(self) -> None:
        self.sim.close()


def start_engine(mesh: MeshParameters, drive: DrivelineParameters, step: float,
                 engine: str = "library", fmu_dir: Path | None = None):
    """The engine of a run (:data:`ENGINES`): ``LibraryEngine`` or ``FmuEngine`` on the FMUs of
    ``fmu_dir``."""
    if engine == "library":
        return LibraryEngine(mesh, drive, step)
    if engine == "fmu":
        if fmu_dir is None:
            raise ValueError("engine 'fmu' needs the folder of the FMUs (fmu_dir)")
        return FmuEngine(mesh, drive, step, fmu_dir)
    raise ValueError(f"engine = {engine!r}; allowed: {', '.join(ENGINES)}")


def run_start(mesh: MeshParameters, drive: DrivelineParameters, start: Start = STARTS[0], *,
              step: float = 1e-4, window: float = 1.0, min_time: float = 20.0,
              max_time: float = 60.0, chunk: float = 10.0, engine: str = "library",
              fmu_dir: Path | None = None) -> StartRun:
    """Run one start (module docstring) in chunks of ``chunk`` seconds from ``min_time`` until
    it is settled or reaches ``max_time`` [s], on ``engine`` (:func:`start_engine`)."""
    wall = time.perf_counter()
    mesh, drive = start_parameters(mesh, drive, start)
    period = forcing_period(mesh, drive)
    periods = max(2, 2 * round(window / period / 2))
    win = periods * period
    step_ns = round(step * 1e9)
    normal_mass = mesh.derived()["normal_mass"]
    record = _Record()
    result = StartRun(start.name, win, {})
    runner = start_engine(mesh, drive, step, engine, fmu_dir)
    try:
        done, first = 0.0, True
        while True:
            target = min_time if first else min(done + chunk, max_time)
            steps = round((target - done) * 1e9 / step_ns)
            if steps <= 0:
                break
            record.add(runner.advance(steps), first)
            first = False
            done = runner.time
            result.windows = record.windows(win, normal_mass)
            result.seconds = done
            _settle(result)
            if result.settled or done >= max_time * (1 - 1e-9):
                break
    finally:
        runner.close()
    result.wall = time.perf_counter() - wall
    return result


@dataclass
class Attractor:
    """The starts that settled on one attractor, and its statistics (those of its first
    start: mean and window-to-window scatter)."""

    starts: list[str]
    mean: dict[str, float]
    scatter: dict[str, float]
    transients: dict[str, float]  # start -> its transient [s]
    durations: dict[str, float]  # start -> its run [s]
    windows: int


def same_attractor(a: StartRun, b: StartRun) -> bool:
    """Whether two settled runs are on one attractor: every signature statistic within
    SEPARATION root sums of squares of their scatters, plus the floor."""
    for name in SIGNATURE:
        ma, mb = a.mean(name), b.mean(name)
        sa, sb = (s if math.isfinite(s) else 0.0 for s in (a.scatter(name), b.scatter(name)))
        tol = SEPARATION * math.hypot(sa, sb) + _floor(name, max(abs(ma), abs(mb)), a.window)
        if abs(ma - mb) > tol:
            return False
    return True


def attractors(runs: list[StartRun]) -> list[Attractor]:
    """The settled runs grouped into attractors: each joins the first attractor whose first
    run it agrees with (:func:`same_attractor`), else starts a new one."""
    groups: list[list[StartRun]] = []
    for r in runs:
        if not r.settled:
            continue
        for g in groups:
            if same_attractor(g[0], r):
                g.append(r)
                break
        else:
            groups.append([r])
    out = []
    for g in groups:
        first = g[0]
        out.append(Attractor([r.start for r in g],
                             {n: first.mean(n) for n in STATISTICS},
                             {n: first.scatter(n) for n in STATISTICS},
                             {r.start: r.transient for r in g},
                             {r.start: r.seconds for r in g},
                             first.n_windows - first.transient_windows))
    return out


@dataclass
class PointResult:
    """One operating point: its verdict, its attractors and every run."""

    load_fraction: float  # of M*
    load: float  # [N.m]
    backlash: float  # [m]
    verdict: str  # "single-valued", "multistable" or "unsettled"
    attractors: list[Attractor]
    runs: list[StartRun] = field(repr=False)

    @property
    def unsettled(self) -> list[str]:
        return [r.start for r in self.runs if not r.settled]


def verdict(runs: list[StartRun], found: list[Attractor]) -> str:
    if len(found) >= 2:
        return "multistable"
    if len(found) == 1 and all(r.settled for r in runs):
        return "single-valued"
    return "unsettled"


def study_point(load_fraction: float, backlash: float | None = None,
                mesh: MeshParameters | None = None, drive: DrivelineParameters | None = None,
                starts=STARTS, workers: int = 1, **options) -> PointResult:
    """One operating point from every start (:func:`run_start` options)."""
    return study([load_fraction], [backlash], mesh, drive, starts, workers, **options)[0]


def _run_task(job) -> StartRun:
    """``run_start`` of a job ``(mesh, drive, start, options)`` (a module function: a process
    pool sends it by name)."""
    mesh, drive, start, options = job
    return run_start(mesh, drive, start, **options)


def study(load_fractions, backlashes, mesh: MeshParameters | None = None,
          drive: DrivelineParameters | None = None, starts=STARTS, workers: int = 2,
          progress=None, **options) -> list[PointResult]:
    """The grid load (x M*, of the mesh and driveline given) x backlash [m] (None: the mesh's)
    x starts on the paper's model (``vehicle.model`` = 1), ``workers`` runs at a time (threads
    on the library engine, processes on the FMU engine); ``options`` of :func:`run_start`
    (``engine``, ``fmu_dir`` among them)."""
    mesh = mesh or MeshParameters()
    drive = drive or DrivelineParameters()
    m_star = separation_load(mesh, drive)
    points = []
    for backlash in backlashes:
        mp = mesh if backlash is None else replace(mesh, backlash=backlash)
        for f in load_fractions:
            points.append((f, mp, paper_driveline(f * m_star, drive)))
    tasks = [(i, s) for i in range(len(points)) for s in starts]

    def run_all(pool, which: list[int], run_options: dict) -> list[StartRun]:
        """The runs of the tasks ``which``, reported to ``progress`` in order."""
        jobs = [(points[tasks[k][0]][1], points[tasks[k][0]][2], tasks[k][1], run_options)
                for k in which]
        out = []
        for k, r in zip(which, pool.map(_run_task, jobs), strict=True):
            if progress:
                progress(points[tasks[k][0]][0], points[tasks[k][0]][1].backlash, r)
            out.append(r)
        return out

    def grouped(results):
        return [[r for (j, _), r in zip(tasks, results, strict=True) if j == i]
                for i in range(len(points))]

    # the library's calls release the GIL: threads; the harness's loop is Python: processes
    engine = options.get("engine", "library")
    pool_class = ThreadPoolExecutor if engine == "library" else ProcessPoolExecutor
    with pool_class(max_workers=max(1, workers)) as pool:
        results = run_all(pool, list(range(len(tasks))), options)
        # a point whose starts disagree: every run that stopped early is run again to the
        # cap, so that each attractor reported persists for the whole of it
        max_time = options.get("max_time", 60.0)
        split = [len(attractors(runs)) > 1 for runs in grouped(results)]
        again = [k for k, ((i, _), r) in enumerate(zip(tasks, results, strict=True))
                 if split[i] and r.seconds < max_time * (1 - 1e-9)]
        for k, r in zip(again, run_all(pool, again, {**options, "min_time": max_time}),
                        strict=True):
            results[k] = r
    out = []
    for (f, mp, dp), runs in zip(points, grouped(results), strict=True):
        found = attractors(runs)
        out.append(PointResult(f, dp.drag, mp.backlash, verdict(runs, found), found, runs))
    return out


# ------------------------------------------------------------------ report
def _fmt(name: str, mean: float, scatter: float) -> str:
    factor = STATISTICS[name][1]
    if not math.isfinite(mean):
        return "—"
    m = mean * factor
    digits = 4 if name == "delta_max" else 3
    text = f"{m:.{digits}g}"
    if math.isfinite(scatter) and scatter * factor >= 10 ** (math.floor(
            math.log10(abs(m))) - digits + 1 if m else -9):
        text += f" ± {scatter * factor:.2g}"
    return text


def report(results: list[PointResult], settings: dict) -> str:
    """The grid as markdown: a summary table of the points, then each point's attractors."""
    lines = ["# Multistability of the rattle: load × backlash × starts", "",
             "Settings: " + ", ".join(f"{k} = {v}" for k, v in settings.items()), "",
             "| load [M*] | load [N·m] | backlash [mm] | verdict | attractors: drive / coast "
             "onsets [1/s], δmax [µm], pairs (starts) |", "|---|---|---|---|---|"]
    for p in results:
        parts = [f"{a.mean['drive_rate']:.4g} / {a.mean['coast_rate']:.4g}, "
                 f"{a.mean['delta_max'] * 1e6:.4g}, {a.mean['pairs']:.3g} "
                 f"({', '.join(a.starts)})" for a in p.attractors]
        if p.unsettled:
            parts.append(f"unsettled: {', '.join(p.unsettled)}")
        lines.append(f"| {p.load_fraction:g} | {p.load:.4g} | {p.backlash * 1e3:g} | "
                     f"{p.verdict} | {'; '.join(parts)} |")
    lines.append("")
    for p in results:
        lines += [f"## {p.load_fraction:g} M*, backlash {p.backlash * 1e3:g} mm: {p.verdict}",
                  ""]
        names = list(STATISTICS)
        lines.append("| attractor | starts (transient / run [s]) | windows | "
                     + " | ".join(STATISTICS[n][0] for n in names) + " |")
        lines.append("|---" * (len(names) + 3) + "|")
        for k, a in enumerate(p.attractors, 1):
            starts = ", ".join(f"{s} ({a.transients[s]:.3g} / {a.durations[s]:.3g})"
                               for s in a.starts)
            lines.append(f"| {k} | {starts} | {a.windows} | "
                         + " | ".join(_fmt(n, a.mean[n], a.scatter[n]) for n in names) + " |")
        for r in p.runs:
            if not r.settled:
                lines.append(f"| unsettled | {r.start} (ran {r.seconds:.3g} s) | "
                             f"{r.n_windows} | "
                             + " | ".join(_fmt(n, r.mean(n), r.scatter(n)) for n in names)
                             + " |")
        lines.append("")
    return "\n".join(lines)


def to_json(results: list[PointResult]) -> list[dict]:
    """The results as plain data (every run's windows included)."""
    out = []
    for p in results:
        out.append({"load_fraction": p.load_fraction, "load": p.load, "backlash": p.backlash,
                    "verdict": p.verdict, "attractors": [asdict(a) for a in p.attractors],
                    "runs": [asdict(r) for r in p.runs]})
    return out


def _floats(text: str) -> list[float]:
    return [float(x) for x in text.split(",") if x.strip()]


def main(argv=None) -> int:
    """The command line: exit status 0, or 2 for a request refused before any work (one line
    on stderr)."""
    from drive_rattle.catalog import check_settings, parse_settings

    from .cli import Parser
    from .paths import DIST

    ap = Parser(prog="python -m drive_rattle_cosim.multistability",
                description=__doc__.splitlines()[0])
    ap.add_argument("--loads", default="0.3,0.4,0.5,0.6,0.8,1.0",
                    help="loads as fractions of M* (comma-separated)")
    ap.add_argument("--backlash", default="0.1e-3,0.2e-3", help="normal backlash [m]")
    ap.add_argument("--starts", default=",".join(STARTS_BY_KEY),
                    help=f"starts (of {', '.join(STARTS_BY_KEY)})")
    ap.add_argument("--phases", type=int, default=0, metavar="N",
                    help="also start from the smooth start at N evenly spaced points of the "
                         "forcing cycle (phase k/N, k = 1..N-1) beside --starts: a state with "
                         "a small basin needs more starts (24: docs/analysis.md section 7)")
    ap.add_argument("--min-time", type=float, default=20.0, help="shortest run [s]")
    ap.add_argument("--max-time", type=float, default=60.0, help="longest run [s]")
    ap.add_argument("--window", type=float, default=1.0,
                    help="window [s] (rounded to an even number of forcing periods)")
    ap.add_argument("--step", type=float, default=1e-4, help="communication step [s]")
    ap.add_argument("--workers", type=int, default=2, help="runs at a time (threads)")
    ap.add_argument("--engine", choices=ENGINES, default="library",
                    help="library: the model library's compiled loop (default); fmu: the FMUs "
                         "of --fmu-dir (FMI 2.0 or 3.0) in the fmpy harness, the same "
                         "trajectories bit for bit")
    ap.add_argument("--fmu-dir", type=Path, default=DIST,
                    help="folder of GearMeshRattle.fmu and Driveline.fmu, for --engine fmu")
    ap.add_argument("--set", action="append", default=[], metavar="UNIT.NAME=VALUE",
                    help="a parameter of either unit by its declared type (SI units; an "
                         "enumeration by its code or item name, a Boolean true/false), e.g. "
                         "GearMeshRattle.contact.restitution=0.9; checked with the model "
                         "library before the runs")
    ap.add_argument("--out", type=Path, default=Path("out") / "multistability.md")
    args = ap.parse_args(argv)
    try:
        keys = [k.strip().replace(" ", "") for k in args.starts.split(",")]
        unknown = [k for k in keys if k not in STARTS_BY_KEY]
        if unknown:
            raise ValueError(f"--starts: unknown start {unknown[0]!r}; allowed: "
                             f"{', '.join(STARTS_BY_KEY)}")
        starts = [STARTS_BY_KEY[k] for k in keys]
        if args.phases:
            try:
                starts = with_phase_starts(starts, args.phases)
            except ValueError as err:
                raise ValueError(f"--phases: {err}") from None
        settings = parse_settings(args.set)
        check_settings(settings)
        if args.engine == "fmu":
            for name in ("GearMeshRattle.fmu", "Driveline.fmu"):
                if not (args.fmu_dir / name).is_file():
                    raise ValueError(f"--fmu-dir {args.fmu_dir} holds no {name}; allowed: a "
                                     "folder of both FMUs (build them: python build_fmu.py)")
    except ValueError as err:
        ap.error(str(err))
    mesh = MeshParameters.from_public({k.partition(".")[2]: v for k, v in settings.items()
                                       if k.startswith("GearMeshRattle.")})
    drive = DrivelineParameters.from_public({k.partition(".")[2]: v for k, v in settings.items()
                                             if k.startswith("Driveline.")})
    wall = time.perf_counter()

    def progress(f, backlash, r):
        print(f"  {f:g} M*, {backlash * 1e3:g} mm, {r.start}: {r.seconds:.0f} s simulated, "
              f"{'settled' if r.settled else 'unsettled'} after {r.transient:.2f} s, "
              f"{r.wall:.1f} s", flush=True)

    fmu_dir = args.fmu_dir if args.engine == "fmu" else None
    results = study(_floats(args.loads), _floats(args.backlash), mesh, drive, starts,
                    args.workers, progress, step=args.step, window=args.window,
                    min_time=args.min_time, max_time=args.max_time, engine=args.engine,
                    fmu_dir=fmu_dir)
    settings = {"M*": f"{separation_load(mesh, drive):.4g} N·m",
                "starts": ", ".join(s.name for s in starts),
                "runs": f"{args.min_time:g}–{args.max_time:g} s",
                "window": f"{results[0].runs[0].window:.4g} s" if results else "",
                "step": f"{args.step:g} s", "model": "vehicle.model = 1 (constant load)",
                "engine": (f"the FMUs of {args.fmu_dir} in the fmpy harness" if fmu_dir
                           else "the model library's compiled loop"),
                "changed": ", ".join(args.set) or "none",
                "wall time": f"{time.perf_counter() - wall:.0f} s"}
    text = report(results, settings)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text, encoding="utf-8")
    args.out.with_suffix(".json").write_text(json.dumps(to_json(results), indent=1),
                                             encoding="utf-8")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
