"""Parameter sweeps of the co-simulation on dask.distributed, with rattle metrics per case.

A design (full grid or Latin hypercube) over any FMU parameters becomes a list of cases; each
case is a full co-simulation run in a dask worker process.  Results are appended to a CSV file
case by case, as they finish, so that an interrupted sweep resumes without redoing finished
cases; a failed case is recorded with its error and the sweep goes on.  One client writes a
result file at a time (a lock file beside it refuses a second).

Two engines, named in every result row (``engine``):

* ``library`` (the default): the two units of the model library coupled in its compiled loop
  (``drive_rattle.units.run_coupled``) -- the same calls the FMUs make, so the same numbers
  as the co-simulation of the FMUs, bit for bit (tests/cosim/test_sweep.py), at the model's
  own cost.  Each worker loads the library once; a case only instantiates its two units.
* ``fmu``: the FMUs of ``--fmu-dir`` in the fmpy harness (either flavour).  The FMUs travel
  with the work: the client reads their bytes once and scatters them to every worker
  (``FmuBundle``), and each worker process unpacks them once into its own local folder, so
  workers on other machines need no copy of ``dist/``.

Workers on other machines need this package installed with the client's versions of dask and
numpy (dask refuses mismatched versions).

    python -m drive_rattle_cosim.sweep \\
        --param GearMeshRattle.gear.backlash=0.05e-3:0.2e-3 \\
        --param Driveline.vehicle.drag=0.1:0.3 --grid 4 --stop-time 4 \\
        --transient 1 --window 1 --out out/sweep.csv [--workers 2 | --scheduler tcp://host:8786]

Rattle metrics (``rattle_metrics``): impacts per second per flank, mean and peak impact speed,
peak and RMS total normal force, fraction of time with a pair in contact, band levels of the
normal-force spectrum, and the **rattle index**: the kinetic energy of the impacts per second,
``1/2 m_n sum(v_i^2) / T`` [W], with ``m_n`` the wheel's effective mass on the tooth normal and
``v_i`` the normal approach speed of each contact onset -- the power the mesh turns into impact
energy, which is what the housing radiates as rattle.  The metrics leave out a start
transient and are means over equal windows, each with its window-to-window standard deviation
(``<metric>_std``; drive_rattle_cosim.analysis.windowed_statistics).
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import hashlib
import itertools
import json
import math
import os
import shutil
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .paths import DIST

#: Frequency bands [Hz] of the normal-force spectrum reported per case.
BANDS = ((20.0, 100.0), (100.0, 500.0), (500.0, 1500.0), (1500.0, 5000.0))
#: Outputs a case records (the rattle metrics need no more).
RECORDED = ["GearMeshRattle.wheel.phi", "GearMeshRattle.mesh.W", "GearMeshRattle.mesh.W_peak",
            "GearMeshRattle.mesh.n_contact", "GearMeshRattle.mesh.v_impact",
            "GearMeshRattle.mesh.impacts_drive", "GearMeshRattle.mesh.impacts_coast",
            "GearMeshRattle.mesh.delta_peak"]
#: Metric column -> the drive_rattle_cosim.analysis.RattleStatistics field it reports.
STATISTIC_OF = {
    "impacts_per_s_drive": "impacts_per_second_drive",
    "impacts_per_s_coast": "impacts_per_second_coast",
    "mean_impact_speed": "mean_impact_speed",
    "peak_impact_speed": "peak_impact_speed",
    "peak_normal_force": "peak_normal_force",
    "rms_normal_force": "rms_normal_force",
    "contact_fraction": "contact_fraction",
    "rattle_index_W": "impact_energy_rate",
    "mean_wheel_speed": "mean_wheel_speed",
}
_MEANS = [*list(STATISTIC_OF)[:7], *(f"band_{int(lo)}_{int(hi)}_Hz_dB" for lo, hi in BANDS),
          *list(STATISTIC_OF)[7:]]
#: Result columns: each metric (mean over the windows after the transient), then each
#: metric's window-to-window standard deviation, the number of windows, the wall time and the
#: engine that ran the case.
TEXT_COLUMNS = ("case_id", "error", "engine")  # the rest are numbers
METRICS = [*_MEANS, *(f"{m}_std" for m in _MEANS), "windows", "wall_seconds", "engine"]
#: The engines of a case (module docstring).
ENGINES = ("library", "fmu")


@dataclass(frozen=True)
class Case:
    """One point of a design: an id that is stable across runs, and its parameters."""

    case_id: str
    parameters: dict

    @staticmethod
    def of(parameters: dict) -> Case:
        blob = json.dumps(parameters, sort_keys=True).encode()
        return Case(hashlib.sha1(blob).hexdigest()[:12], dict(parameters))


def _ranges(params: dict[str, tuple[float, float]]):
    for name, (lo, hi) in params.items():
        if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
            raise ValueError(f"sweep parameter {name}: range {lo!r}..{hi!r} is invalid; "
                             "allowed: finite numbers with lo <= hi")
    return params


def grid_design(params: dict[str, tuple[float, float]], points: int | dict[str, int]) -> list[Case]:
    """Full factorial grid: ``points`` values per parameter (evenly spaced, ends included)."""
    params = _ranges(params)
    counts = {n: (points[n] if isinstance(points, dict) else points) for n in params}
    axes = [np.linspace(lo, hi, counts[n]) if counts[n] > 1 else np.array([lo])
            for n, (lo, hi) in params.items()]
    names = list(params)
    return [Case.of({n: float(v) for n, v in zip(names, values, strict=True)})
            for values in itertools.product(*axes)]


def latin_hypercube_design(params: dict[str, tuple[float, float]], samples: int,
                           seed: int = 0) -> list[Case]:
    """Latin hypercube of ``samples`` cases (scipy.stats.qmc, reproducible by ``seed``)."""
    from scipy.stats import qmc

    params = _ranges(params)
    unit = qmc.LatinHypercube(d=len(params), seed=seed).random(samples)
    lo = np.array([r[0] for r in params.values()])
    hi = np.array([r[1] for r in params.values()])
    scaled = qmc.scale(unit, lo, hi) if np.all(hi > lo) else lo + unit * (hi - lo)
    names = list(params)
    return [Case.of({n: float(v) for n, v in zip(names, row, strict=True)}) for row in scaled]


def rattle_metrics(time_s, signals: dict, normal_mass: float, transient: float = 0.0,
                   window: float | None = None) -> dict[str, float]:
    """The metrics of one run from the mesh outputs recorded at every communication point:
    the first ``transient`` seconds dropped, the rest cut into windows of ``window`` seconds
    (None: one window), each metric the mean over the windows and ``<metric>_std`` its
    window-to-window standard deviation (nan with one window)."""
    from .analysis import onsets_from_counters, welch_spectrum, windowed_statistics

    t = np.asarray(time_s, dtype=float)
    onset_t, speeds, flanks = onsets_from_counters(t, signals["mesh.impacts_drive"],
                                                   signals["mesh.impacts_coast"],
                                                   signals["mesh.v_impact"])
    ws = windowed_statistics(t, signals, onset_t, speeds, flanks, normal_mass, transient, window)
    per_window = {metric: [getattr(w, name) for w in ws.windows]
                  for metric, name in STATISTIC_OF.items()}
    W = np.asarray(signals["mesh.W"], dtype=float)
    for lo, hi in BANDS:
        per_window[f"band_{int(lo)}_{int(hi)}_Hz_dB"] = []
    for span, w in zip(ws.slices, ws.windows, strict=True):
        steps = slice(span.start + 1, span.stop)  # the samples that close the window's steps
        spec = welch_spectrum(t[steps], W[steps], segment_seconds=min(0.1, w.duration / 4))
        df = spec.frequency[1] - spec.frequency[0]
        for lo, hi in BANDS:
            band = (spec.frequency >= lo) & (spec.frequency < hi)
            power = float(np.sum(spec.psd[band]) * df)
            per_window[f"band_{int(lo)}_{int(hi)}_Hz_dB"].append(
                10.0 * math.log10(power) if power > 0 else -300.0)
    out: dict[str, float] = {"windows": float(len(ws.windows))}
    for metric, values in per_window.items():
        v = np.asarray(values, dtype=float)
        out[metric] = float(np.mean(v))
        out[f"{metric}_std"] = float(np.std(v, ddof=1)) if v.size > 1 else math.nan
    return out


#: The FMUs a case needs.
FMU_FILES = ("GearMeshRattle.fmu", "Driveline.fmu")
#: Unpacked bundles of this process: digest -> folder.
_UNPACKED: dict[str, Path] = {}


@dataclass(frozen=True)
class FmuBundle:
    """The FMUs' bytes (file name -> content), shipped to the workers with the work instead of
    a path that only exists on the client's machine."""

    files: dict
    digest: str

    @staticmethod
    def from_dir(folder: Path) -> FmuBundle:
        """The FMUs of ``folder`` (FileNotFoundError naming the missing one)."""
        files = {}
        for name in FMU_FILES:
            path = Path(folder) / name
            if not path.is_file():
                raise FileNotFoundError(f"{path} does not exist (build it: python build_fmu.py)")
            files[name] = path.read_bytes()
        digest = hashlib.sha256(b"".join(hashlib.sha256(files[n]).digest()
                                         for n in FMU_FILES)).hexdigest()[:16]
        return FmuBundle(files, digest)

    def folder(self) -> Path:
        """A folder holding the FMUs in this process: written once per process and content,
        inside the dask worker's local directory (removed with the worker) when there is one."""
        folder = _UNPACKED.get(self.digest)
        if folder is not None and folder.is_dir():
            return folder
        base = Path(tempfile.gettempdir())
        with contextlib.suppress(ImportError, ValueError):
            from distributed import get_worker

            base = Path(get_worker().local_directory)
        folder = base / f"drive_rattle_fmus_{self.digest}"
        if not folder.is_dir():
            staging = Path(tempfile.mkdtemp(prefix=".fmus_", dir=base))
            for name, data in self.files.items():
                (staging / name).write_bytes(data)
            try:
                staging.rename(folder)
            except OSError:  # another process of this machine was first
                shutil.rmtree(staging, ignore_errors=True)
        _UNPACKED[self.digest] = folder
        return folder


def _unit_parameters(parameters: dict, unit: str) -> dict:
    prefix = f"{unit}."
    return {k[len(prefix):]: v for k, v in parameters.items() if k.startswith(prefix)}


def _run_library(parameters: dict, stop_time: float, step: float) -> tuple[list, dict]:
    """The co-simulation of ``parameters`` in the model library's compiled loop: the
    communication points and the recorded outputs (public names), as the harness gives them."""
    from drive_rattle.parameters import DrivelineParameters, MeshParameters
    from drive_rattle.units import DrivelineUnit, MeshUnit, coupled_start_inputs, run_coupled

    from .system import communication_points

    unknown = sorted(k for k in parameters if k.split(".", 1)[0] not in (
        "GearMeshRattle", "Driveline"))
    if unknown:
        raise ValueError(f"parameter(s) {', '.join(unknown)}: expected '<Unit>.<name>' of "
                         "GearMeshRattle or Driveline")
    mp = MeshParameters.from_public(_unit_parameters(parameters, "GearMeshRattle"))
    dp = DrivelineParameters.from_public(_unit_parameters(parameters, "Driveline"))
    steps = len(communication_points(0.0, step, stop_time)) - 1
    step_ns = round(step * 1e9)
    # the points as the harness computes them, (k step_ns) / 1e9 (exact integers below 2**53)
    points = np.arange(steps + 1, dtype=np.int64) * step_ns / 1e9
    mesh_in, wheel = coupled_start_inputs(mp, dp)
    with MeshUnit(mp, mesh_in["pinion.phi"], mesh_in["pinion.w"], mesh_in["wheel.tau_load"],
                  mesh_in["pinion.a"]) as mesh, \
            DrivelineUnit(dp, wheel["wheel.phi"], wheel["wheel.w"]) as drive:
        run = run_coupled(mesh, drive, step_ns, steps, RECORDED)
    return points, {name: np.asarray(run.column_buffer(name)) for name in RECORDED}


def _run_fmus(parameters: dict, fmus, stop_time: float, step: float) -> tuple[list, dict]:
    """The co-simulation of ``parameters`` by the fmpy harness on the FMUs ``fmus`` (a bundle
    or a local folder)."""
    from .harness import CoSimulation

    folder = fmus.folder() if isinstance(fmus, FmuBundle) else Path(fmus)
    with CoSimulation(folder / "GearMeshRattle.fmu", folder / "Driveline.fmu", parameters,
                      step=step) as sim:
        res = sim.run(stop_time, RECORDED)
    return res.time, res.columns


def run_case(case: Case, fmus: FmuBundle | str | Path | None, stop_time: float, step: float,
             transient: float = 0.0, window: float | None = None) -> dict:
    """One co-simulation (runs in a worker process): the case's parameters, then metrics
    after ``transient`` seconds in windows of ``window`` seconds.  ``fmus``: None for the
    model library's compiled loop (engine "library"), else the FMUs' bundle or a local
    folder holding them (engine "fmu").  Never raises: an error becomes the row's ``error``
    field."""
    engine = "library" if fmus is None else "fmu"
    row = {"case_id": case.case_id, **case.parameters, "error": "", "engine": engine}
    start = time.perf_counter()
    try:
        from drive_rattle.parameters import MeshParameters

        if fmus is None:
            times, columns = _run_library(case.parameters, stop_time, step)
        else:
            times, columns = _run_fmus(case.parameters, fmus, stop_time, step)
        mesh = MeshParameters.from_public(_unit_parameters(case.parameters, "GearMeshRattle"))
        normal_mass = mesh.derived()["normal_mass"]
        signals = {k.split(".", 1)[1]: np.asarray(v, dtype=float) for k, v in columns.items()}
        row.update(rattle_metrics(times, signals, normal_mass, transient, window))
    except Exception as err:  # recorded, never stops the sweep
        row["error"] = f"{type(err).__name__}: {err}".replace("\n", " ")[:2000]
    row["wall_seconds"] = time.perf_counter() - start
    return row


def finished_case_ids(path: Path, retry_failed: bool = False) -> set[str]:
    """Ids of the cases already in the result file (failed ones too, unless retried)."""
    if not path.exists():
        return set()
    with path.open(newline="", encoding="utf-8") as f:
        return {r["case_id"] for r in csv.DictReader(f)
                if not (retry_failed and r.get("error"))}


class ResultWriter:
    """Appends one CSV row per finished case, flushed at once (resume-safe).  A lock file
    beside the result (``<out>.lock``, holding the writer's process id) refuses a second
    client writing the same file: their rows would repeat cases."""

    def __init__(self, path: Path, parameter_names: list[str]):
        self.path = Path(path)
        self.columns = ["case_id", *parameter_names, *METRICS, "error"]
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.lock = self.path.with_name(self.path.name + ".lock")
        self._take_lock()
        try:
            self._open()
        except BaseException:
            self.lock.unlink(missing_ok=True)
            raise

    def _take_lock(self) -> None:
        for _ in range(2):
            try:
                fd = os.open(self.lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                owner = self.lock.read_text(encoding="utf-8").strip() if self.lock.exists() else ""
                if owner.isdigit() and not _alive(int(owner)):
                    self.lock.unlink(missing_ok=True)  # left by a client that died
                    continue
                raise ValueError(
                    f"{self.path} is being written by another sweep (process {owner or '?'}, "
                    f"lock {self.lock}); wait for it, or use another --out") from None
            with os.fdopen(fd, "w", encoding="utf-8") as f:
                f.write(f"{os.getpid()}\n")
            return

    def _open(self) -> None:
        if self.path.exists() and self.path.stat().st_size > 0:
            with self.path.open(newline="", encoding="utf-8") as f:
                header = next(csv.reader(f))
            if header != self.columns:
                raise ValueError(f"{self.path} holds another sweep (columns {header}); "
                                 "use another --out")
            self._file = self.path.open("a", newline="", encoding="utf-8")
            self._csv = csv.DictWriter(self._file, fieldnames=self.columns)
        else:
            self._file = self.path.open("w", newline="", encoding="utf-8")
            self._csv = csv.DictWriter(self._file, fieldnames=self.columns)
            self._csv.writeheader()
            self._file.flush()

    def write(self, row: dict) -> None:
        self._csv.writerow({c: row.get(c, "") for c in self.columns})
        self._file.flush()

    def close(self) -> None:
        self._file.close()
        self.lock.unlink(missing_ok=True)


def _alive(pid: int) -> bool:
    """Whether a process of this machine with ``pid`` exists."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True
    return True


class SweepInterruptedError(RuntimeError):
    """The cluster lost what the cases needed (every worker died): the message says how to
    resume."""


def run_sweep(cases: list[Case], out: Path, fmu_dir: Path | None = None,
              stop_time: float = 0.3, step: float = 1e-4, workers: int = 2,
              scheduler: str | None = None, progress: bool = True,
              retry_failed: bool = False, stop_after: int | None = None,
              transient: float = 0.0, window: float | None = None,
              resume_hint: str = "run the same command again") -> dict:
    """Run the cases not yet in ``out`` on dask (a LocalCluster of ``workers`` processes, or
    the cluster at ``scheduler``); metrics after ``transient`` seconds in windows of
    ``window`` seconds (``rattle_metrics``).  ``fmu_dir`` None runs the model library's
    compiled loop (engine "library"), else the FMUs of that folder in the fmpy harness
    (engine "fmu").  ``stop_after`` ends the sweep after that many new cases (an
    interruption, for tests).  Returns counts of done, skipped and failed cases;
    :class:`SweepInterruptedError` when the cluster lost every worker (the finished rows are
    kept)."""
    from dask.distributed import Client, LocalCluster, as_completed

    out = Path(out)
    bundle = FmuBundle.from_dir(fmu_dir) if fmu_dir is not None else None
    names = sorted({n for c in cases for n in c.parameters})
    writer = ResultWriter(out, names)
    done = finished_case_ids(out, retry_failed)
    todo = [c for c in cases if c.case_id not in done]
    cluster = None
    counts = {"total": len(cases), "skipped": len(cases) - len(todo), "done": 0, "failed": 0}
    try:
        if scheduler:
            client = Client(scheduler)
        else:
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                   dashboard_address=None)
            client = Client(cluster)
        with client:
            fmus = None
            if bundle is not None and todo:
                # One copy of the FMUs per worker, not per task (and none read from a path).
                [fmus] = client.scatter([bundle], broadcast=True)
            futures = [client.submit(run_case, c, fmus, stop_time, step, transient, window,
                                     pure=False)
                       for c in todo]
            stream = as_completed(futures)
            if progress and todo:
                from tqdm import tqdm

                stream = tqdm(stream, total=len(todo), unit="case", desc="sweep",
                              disable=None)  # no bar where stderr is not a terminal
            for future in stream:
                try:
                    row = future.result()
                except Exception as err:  # the cluster, not the case: the case never ran
                    for f in futures:
                        f.cancel()
                    raise SweepInterruptedError(
                        f"the sweep lost its workers ({type(err).__name__}) after "
                        f"{counts['done']} new cases; {out} keeps them: {resume_hint} to run "
                        "the rest") from None
                writer.write(row)
                counts["done"] += 1
                counts["failed"] += bool(row["error"])
                if stop_after is not None and counts["done"] >= stop_after:
                    for f in futures:
                        f.cancel()
                    break
    finally:
        writer.close()
        if cluster is not None:
            cluster.close()
    return counts


def read_results(path: Path) -> list[dict]:
    """Rows of a result file, numbers as floats (empty strings as NaN)."""
    rows = []
    with Path(path).open(newline="", encoding="utf-8") as f:
        for r in csv.DictReader(f):
            rows.append({k: (v if k in TEXT_COLUMNS else
                             (float(v) if v != "" else math.nan)) for k, v in r.items()})
    return rows


def _parse_param(text: str) -> tuple[str, tuple[float, float]]:
    name, sep, rng = text.partition("=")
    lo, colon, hi = rng.partition(":")
    if not sep or not name:
        raise argparse.ArgumentTypeError(f"--param {text!r}: expected UNIT.NAME=LO:HI")
    try:
        return name, (float(lo), float(hi if colon else lo))
    except ValueError:
        raise argparse.ArgumentTypeError(f"--param {text!r}: LO and HI must be numbers") from None


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m drive_rattle_cosim.sweep",
                                 description="Parameter sweep of the rattle co-simulation.")
    ap.add_argument("--param", type=_parse_param, action="append", required=True,
                    metavar="UNIT.NAME=LO:HI", help="a swept parameter and its range (SI)")
    design = ap.add_mutually_exclusive_group(required=True)
    design.add_argument("--grid", type=int, metavar="N", help="N values per parameter")
    design.add_argument("--lhs", type=int, metavar="N", help="N Latin-hypercube cases")
    ap.add_argument("--seed", type=int, default=0, help="Latin-hypercube seed")
    ap.add_argument("--stop-time", type=float, default=0.3, help="simulated time per case [s]")
    ap.add_argument("--step", type=float, default=1e-4, help="communication step [s]")
    ap.add_argument("--transient", type=float, default=0.0,
                    help="start transient left out of the metrics [s]")
    ap.add_argument("--window", type=float, default=None,
                    help="window of the statistics [s] (default: all after the transient)")
    ap.add_argument("--engine", choices=ENGINES, default="library",
                    help="library: the model library's compiled loop (default; the FMUs' "
                         "numbers at the model's cost); fmu: the FMUs of --fmu-dir in the "
                         "fmpy harness")
    ap.add_argument("--fmu-dir", type=Path, default=DIST,
                    help="folder of the FMUs on this machine, for --engine fmu (they are sent "
                         "to the workers)")
    ap.add_argument("--out", type=Path, default=Path("out") / "sweep.csv")
    ap.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes")
    ap.add_argument("--scheduler", default=None, help="address of an existing dask scheduler")
    ap.add_argument("--retry-failed", action="store_true")
    args = ap.parse_args(argv)
    params = dict(args.param)
    cases = (grid_design(params, args.grid) if args.grid
             else latin_hypercube_design(params, args.lhs, args.seed))
    try:
        counts = run_sweep(cases, args.out, args.fmu_dir if args.engine == "fmu" else None,
                           args.stop_time, args.step, args.workers, args.scheduler,
                           retry_failed=args.retry_failed, transient=args.transient,
                           window=args.window,
                           resume_hint="run `python -m drive_rattle_cosim.sweep "
                                       + " ".join(argv if argv is not None else sys.argv[1:])
                                       + "` again")
    except (FileNotFoundError, ValueError, SweepInterruptedError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 1
    print(f"{counts['done']} cases run ({counts['failed']} failed), {counts['skipped']} "
          f"already done, {counts['total']} in the design -> {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
