"""Parameter sweeps of the co-simulation on dask.distributed, with rattle metrics per case.

A design (full grid or Latin hypercube) over any FMU parameters becomes a list of cases; each
case is a full co-simulation run in a dask worker process.  Results are appended to a CSV file
case by case, as they finish, so that an interrupted sweep resumes without redoing finished
cases; a failed case is recorded with its error and the sweep goes on.  One client writes a
result file at a time (``ResultWriter``: the lock of ``<out>.lock`` held for the writer's life,
released by the system when a client dies); a last row cut short is dropped on resuming and its
case run again.  A request is checked before any work (``check_request``, the designs), at most
``MAX_CASES`` cases.  Exit statuses of the command line: ``EXIT_OK``, ``EXIT_STOPPED``,
``EXIT_BAD_REQUEST``, ``EXIT_CASES_FAILED`` (docs/cosim.md).

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
import io
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


#: Most cases a design may hold, checked before it is built: 1e5 cases of 0.3 s are about a
#: day of one core on the library engine, and a design far beyond (3 parameters x 2000 values
#: are 8e9 cases) would only exhaust the client's memory; a larger study is several sweeps,
#: each with its own result file.
MAX_CASES = 100_000


def _sweepable(name: str):
    """The spec of a swept parameter: a Real or Integer (an enumeration by its codes)."""
    from drive_rattle.catalog import parameter_spec

    spec = parameter_spec(name)
    if spec.fmi_type not in ("Real", "Integer"):
        raise ValueError(f"sweep parameter {name} is a {spec.fmi_type}; allowed: Real and "
                         "Integer parameters (an enumeration by its codes)")
    return spec


def _ranges(params: dict[str, tuple[float, float]]) -> dict[str, tuple[float, float]]:
    """The ranges of a design, checked: known Real or Integer parameters, finite ends with
    lo <= hi (lo == hi holds the parameter at that value), each end accepted by the model
    library (the other parameters at their defaults)."""
    from drive_rattle.catalog import check_settings

    if not params:
        raise ValueError("a design of no parameters; allowed: one range or more")
    out = {}
    for name, (lo, hi) in params.items():
        _sweepable(name)
        if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
            raise ValueError(f"sweep parameter {name}: range {lo!r}..{hi!r} is invalid; "
                             "allowed: finite numbers with lo <= hi")
        for end in dict.fromkeys((lo, hi)):
            try:
                check_settings({name: end})
            except ValueError as err:
                raise ValueError(f"sweep parameter {name}: {err}") from None
        out[name] = (float(lo), float(hi))
    return out


def _check_size(cases: int, what: str) -> None:
    if cases > MAX_CASES:
        raise ValueError(f"{what} holds {cases} cases; allowed: at most {MAX_CASES} "
                         "(a larger study is several sweeps, each with its own --out)")


def _distinct(cases: list[Case]) -> list[Case]:
    """``cases``, refused when two are the same point: a case runs once, under its id."""
    seen: dict[str, Case] = {}
    for case in cases:
        if case.case_id in seen:
            raise ValueError(f"the cases repeat case {case.case_id} ({case.parameters}); "
                             "allowed: distinct points (a range wider than the rounding of "
                             "its values)")
        seen[case.case_id] = case
    return cases


def _count(value, what: str, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{what} = {value!r}; allowed: a whole number >= {minimum}")
    return int(value)


def grid_design(params: dict[str, tuple[float, float]], points: int | dict[str, int]) -> list[Case]:
    """Full factorial grid: ``points`` values per parameter (evenly spaced, ends included; at
    least 2), one value for a parameter held at lo == hi.  An Integer parameter's values must
    be whole numbers.  At most ``MAX_CASES`` cases, checked before the grid is built."""
    params = _ranges(params)
    counts = {}
    for name, (lo, hi) in params.items():
        if lo == hi:
            counts[name] = 1
            continue
        n = _count(points[name] if isinstance(points, dict) else points,
                   f"grid (values of {name})", 2)
        if _sweepable(name).fmi_type == "Integer" and (hi - lo) % (n - 1):
            raise ValueError(f"grid of {n} values of the Integer parameter {name} from {lo:g} "
                             f"to {hi:g} falls between whole numbers; allowed: n - 1 dividing "
                             f"{hi - lo:g} (e.g. n = {int(hi - lo) + 1})")
        counts[name] = n
    _check_size(math.prod(counts.values()),
                "a grid of " + " x ".join(str(n) for n in counts.values()) + " values")
    axes = [np.linspace(lo, hi, counts[n]) if counts[n] > 1 else np.array([lo])
            for n, (lo, hi) in params.items()]
    names = list(params)
    return _distinct([Case.of({n: float(v) for n, v in zip(names, values, strict=True)})
                      for values in itertools.product(*axes)])


def latin_hypercube_design(params: dict[str, tuple[float, float]], samples: int,
                           seed: int = 0) -> list[Case]:
    """Latin hypercube of ``samples`` cases (scipy.stats.qmc, reproducible by ``seed``) over
    Real parameters (an Integer one only held at lo == hi); at most ``MAX_CASES``."""
    from scipy.stats import qmc

    params = _ranges(params)
    samples = _count(samples, "Latin hypercube samples", 1)
    _check_size(samples, f"a Latin hypercube of {samples} samples")
    ranged = [n for n, (lo, hi) in params.items() if lo < hi]
    if samples > 1 and not ranged:
        raise ValueError(f"a Latin hypercube of {samples} samples with every parameter held "
                         "fixed repeats one case; allowed: one range lo < hi or more")
    integers = [n for n in ranged if _sweepable(n).fmi_type == "Integer"]
    if integers:
        raise ValueError(f"a Latin hypercube draws real values, and {integers[0]} is an "
                         "Integer parameter; allowed: Real parameters (sweep an Integer one "
                         "by a grid)")
    unit = qmc.LatinHypercube(d=len(params), seed=seed).random(samples)
    lo = np.array([r[0] for r in params.values()])
    hi = np.array([r[1] for r in params.values()])
    scaled = qmc.scale(unit, lo, hi) if np.all(hi > lo) else lo + unit * (hi - lo)
    names = list(params)
    return _distinct([Case.of({n: float(v) for n, v in zip(names, row, strict=True)})
                      for row in scaled])


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


def _row_bytes(fields: list) -> bytes:
    """One CSV row as the result file holds it (csv's excel dialect, ``\\r\\n`` ended)."""
    text = io.StringIO()
    csv.writer(text).writerow(fields)
    return text.getvalue().encode("utf-8")


def _whole_rows(data: bytes) -> tuple[list[str], list[list[str]], int]:
    """``(header, rows, end)`` of a result file's bytes: the rows up to the last whole one and
    the byte offset where it ends.  A last line without its newline (a write cut short: a
    killed client, a full disk), or with another field count than the header's, is not a
    whole row: ``end`` leaves it out, so that a resumed sweep runs its case again."""
    header: list[str] = []
    rows: list[list[str]] = []
    end = start = 0
    while (stop := data.find(b"\n", start)) >= 0:
        [fields] = list(csv.reader([data[start:stop + 1].decode("utf-8", "replace")])) or [[]]
        start = stop + 1
        if not header:
            header, end = fields, start
        elif fields:
            rows.append(fields)
            end = start
    if rows and len(rows[-1]) != len(header):
        rows.pop()
        end = data.rfind(b"\n", 0, end - 1) + 1
    return header, rows, end


def _finished_errors(path: Path) -> dict[str, str]:
    """``{case id: error}`` of the whole rows of a result file (empty error: the case ran)."""
    if not path.exists():
        return {}
    header, rows, _ = _whole_rows(path.read_bytes())
    if "case_id" not in header or "error" not in header:
        return {}
    k, e = header.index("case_id"), header.index("error")
    return {r[k]: r[e] for r in rows if len(r) == len(header)}


def finished_case_ids(path: Path, retry_failed: bool = False) -> set[str]:
    """Ids of the cases already in the result file (failed ones too, unless retried)."""
    return {c for c, error in _finished_errors(Path(path)).items()
            if not (retry_failed and error)}


class ResultFileBusyError(RuntimeError):
    """Another sweep holds the result file's lock."""


class SweepInterruptedError(RuntimeError):
    """The sweep stopped before its end, its finished rows kept: the cluster lost what the
    cases needed (every worker died), or the result file could not be written (a full disk).
    The message says how to resume."""


class ResultWriteError(SweepInterruptedError):
    """A row could not be written (``OSError``: a full disk); the file is cut back to its
    whole rows."""


#: Tries at the lock when its file is replaced between opening and locking it (a writer
#: ending in between removes it).
LOCK_TRIES = 50


def _try_lock(fd: int) -> bool:
    """Whether the exclusive lock of the open file ``fd`` was taken (never waits).  The lock
    belongs to the open file, and the system releases it when the process ends however it
    ends, so a client that died leaves no lock behind, only a lock file nobody holds."""
    try:
        import fcntl
    except ImportError:  # Windows: a lock on the first byte, released with the handle
        import msvcrt

        try:
            msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)
        except OSError:
            return False
        return True
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return False
    return True


class ResultWriter:
    """Appends one CSV row per finished case, each in one unbuffered write (resume-safe).

    One client writes a result file at a time: the writer holds the exclusive lock
    (``flock``) of ``<out>.lock`` beside it for its life, so a second client is refused and a
    dead client's lock is free at once (the system drops it with the process; no process ids
    to judge).  Opening an existing file drops a last row cut short (:func:`_whole_rows`); a
    write that fails (a full disk) cuts the file back to its whole rows and raises
    :class:`ResultWriteError` naming the file and ``resume_hint``."""

    def __init__(self, path: Path, parameter_names: list[str],
                 resume_hint: str = "run the same sweep again"):
        self.path = Path(path)
        self.columns = ["case_id", *parameter_names, *METRICS, "error"]
        self.resume_hint = resume_hint
        self.lock = self.path.with_name(self.path.name + ".lock")
        self._file = self._lock_fd = None
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._lock_fd = self._take_lock()
            self._open()
        except OSError as err:  # a folder, a file of no permission: a bad --out
            self.close()
            where = f": {err.filename}" if err.filename else ""
            raise ValueError(f"cannot write the result file {self.path} ({err.strerror or err}"
                             f"{where}); allowed: a file in a folder this user can write"
                             ) from None
        except BaseException:
            self.close()
            raise

    def _take_lock(self) -> int:
        """An open descriptor of the lock file holding its lock.  Locking the file that is at
        the lock's path when the lock is held is what counts: a file a finished writer
        removed between our opening and our locking it is let go and the lock file opened
        again (never a FileNotFoundError)."""
        for _ in range(LOCK_TRIES):
            fd = os.open(self.lock, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                if not _try_lock(fd):
                    owner = os.read(fd, 32).decode("ascii", "replace").strip()
                    raise ResultFileBusyError(
                        f"{self.path} is being written by another sweep (process "
                        f"{owner or '?'}, lock {self.lock}); wait for it to end, or use "
                        "another --out")
                if self._is_lock_file(fd):
                    os.ftruncate(fd, 0)
                    os.write(fd, f"{os.getpid()}\n".encode("ascii"))
                    return fd
            except BaseException:
                os.close(fd)
                raise
            os.close(fd)
        raise ResultFileBusyError(f"{self.lock} was replaced {LOCK_TRIES} times while this "
                                  f"sweep took it; allowed: one sweep at a time on {self.path}")

    def _is_lock_file(self, fd: int) -> bool:
        """Whether ``fd`` is the file now at the lock's path."""
        try:
            return os.path.samestat(os.fstat(fd), os.stat(self.lock))
        except FileNotFoundError:
            return False

    def _open(self) -> None:
        header = _row_bytes(self.columns)
        data = self.path.read_bytes() if self.path.exists() else b""
        found, rows, end = _whole_rows(data)
        if found != self.columns and not (not found and header.startswith(data)):
            raise ValueError(f"{self.path} is not a result file of this sweep (its first "
                             "line is not the header of these parameters' results); allowed: "
                             "the result file of the same parameters, or another --out")
        self._file = self.path.open("r+b" if data else "wb", buffering=0)
        self._file.truncate(end)  # a row (or header) cut short is dropped: its case reruns
        self._file.seek(end)
        self._end, self.rows = end, len(rows)
        if not found:
            self._append(header)

    def write(self, row: dict) -> None:
        self._append(_row_bytes([row.get(c, "") for c in self.columns]))
        self.rows += 1

    def drop(self, case_ids: set[str]) -> None:
        """Remove the rows of ``case_ids`` (failed cases about to run again, so that each case
        keeps one row): the file rewritten beside itself and renamed into place, under the
        lock, so that a crash leaves either the old file or the new one."""
        if not case_ids:
            return
        header, rows, _ = _whole_rows(self.path.read_bytes())
        k = header.index("case_id")
        kept = [r for r in rows if r[k] not in case_ids]
        part = self.path.with_name(f".{self.path.name}.{os.getpid()}.part")
        try:
            with part.open("wb") as f:
                f.write(b"".join(_row_bytes(r) for r in [header, *kept]))
                f.flush()
                os.fsync(f.fileno())
            os.replace(part, self.path)
        except OSError as err:
            part.unlink(missing_ok=True)
            raise ResultWriteError(
                f"cannot rewrite {self.path} without the failed rows to retry "
                f"({err.strerror or err}); it is unchanged: make room, then "
                f"{self.resume_hint}") from None
        self._file.close()
        self._file = None
        self._open()

    def _append(self, data: bytes) -> None:
        view = memoryview(data)
        try:
            while view:
                view = view[self._file.write(view):]
        except OSError as err:
            with contextlib.suppress(OSError):  # only whole rows stay (truncating needs no space)
                self._file.truncate(self._end)
            raise ResultWriteError(
                f"cannot write {self.path} ({err.strerror or err}); its {self.rows} finished "
                f"rows are kept: make room, then {self.resume_hint} to run the rest") from None
        self._end += len(data)

    def close(self) -> None:
        """Close the file and let the lock go (its file removed while still held, so that no
        client locks a file that is no longer the lock)."""
        try:
            if self._file is not None:
                self._file.close()
        finally:
            self._file = None
            fd, self._lock_fd = self._lock_fd, None
            if fd is not None:
                if os.name == "posix" and self._is_lock_file(fd):
                    self.lock.unlink()
                os.close(fd)


def run_sweep(cases: list[Case], out: Path, fmu_dir: Path | None = None,
              stop_time: float = 0.3, step: float = 1e-4, workers: int = 2,
              scheduler: str | None = None, progress: bool = True,
              retry_failed: bool = False, stop_after: int | None = None,
              transient: float = 0.0, window: float | None = None,
              resume_hint: str = "run the same sweep again") -> dict:
    """Run the cases not yet in ``out`` on dask (a LocalCluster of ``workers`` processes, or
    the cluster at ``scheduler``); metrics after ``transient`` seconds in windows of
    ``window`` seconds (``rattle_metrics``).  ``fmu_dir`` None runs the model library's
    compiled loop (engine "library"), else the FMUs of that folder in the fmpy harness
    (engine "fmu").  ``stop_after`` ends the sweep after that many new cases (an
    interruption, for tests).

    The request is checked before any work (ValueError: :func:`check_request`).  Returns
    counts: ``total``, ``skipped`` (already in ``out``) and of those ``failed_before`` (with
    an error, not retried), ``done`` (run now) and of those ``failed``.  Raises
    :class:`ResultFileBusyError` when another sweep writes ``out``, and
    :class:`SweepInterruptedError` when the cluster lost every worker or a row could not be
    written (the finished rows are kept; the message says how to resume)."""
    from dask.distributed import Client, LocalCluster, as_completed

    check_request(cases, stop_time, step, transient, window, workers)
    out = Path(out)
    bundle = FmuBundle.from_dir(fmu_dir) if fmu_dir is not None else None
    names = sorted({n for c in cases for n in c.parameters})
    writer = ResultWriter(out, names, resume_hint)
    finished = _finished_errors(out)
    todo = [c for c in cases
            if c.case_id not in finished or (retry_failed and finished[c.case_id])]
    cluster = None
    counts = {"total": len(cases), "skipped": len(cases) - len(todo), "done": 0, "failed": 0,
              "failed_before": sum(1 for c in cases if finished.get(c.case_id)
                                   and not retry_failed)}
    try:
        if retry_failed:  # a retried case's failed row gives way to its new one
            writer.drop({c.case_id for c in todo if finished.get(c.case_id)})
        if not todo:
            return counts
        if scheduler:
            client = Client(scheduler)
        else:
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                   dashboard_address=None)
            client = Client(cluster)
        with client:
            fmus = None
            if bundle is not None:
                # One copy of the FMUs per worker, not per task (and none read from a path).
                [fmus] = client.scatter([bundle], broadcast=True)
            futures = [client.submit(run_case, c, fmus, stop_time, step, transient, window,
                                     pure=False)
                       for c in todo]
            stream = as_completed(futures)
            if progress:
                from tqdm import tqdm

                stream = tqdm(stream, total=len(todo), unit="case", desc="sweep",
                              disable=None)  # no bar where stderr is not a terminal
            try:
                for future in stream:
                    try:
                        row = future.result()
                    except Exception as err:  # the cluster, not the case: it never ran
                        raise SweepInterruptedError(
                            f"the sweep lost its workers ({type(err).__name__}) after "
                            f"{counts['done']} new cases; {out} keeps them: {resume_hint} to "
                            "run the rest") from None
                    writer.write(row)
                    counts["done"] += 1
                    counts["failed"] += bool(row["error"])
                    if stop_after is not None and counts["done"] >= stop_after:
                        break
            finally:
                for f in futures:
                    f.cancel()
    finally:
        writer.close()
        if cluster is not None:
            cluster.close()
    return counts


#: Most communication points of a case: its recorded outputs (8 float64 columns) are held in
#: a worker's memory, 640 MB at this limit (1000 s at the default step).
MAX_POINTS = 10_000_000


def check_run_options(stop_time: float, step: float, transient: float = 0.0,
                      window: float | None = None) -> None:
    """ValueError, one sentence with the value and what is allowed, unless every case can be
    run and measured with these options: a step of whole nanoseconds
    (``system.step_nanoseconds``), a stop time of a whole number of steps (at most
    ``MAX_POINTS``), a transient and windows that fit the run (``analysis.window_layout``),
    each window long enough for the band levels' spectrum (``spectral_lines.MIN_SAMPLES``)."""
    from .analysis import window_layout
    from .spectral_lines import MIN_SAMPLES
    from .system import step_nanoseconds

    step_nanoseconds(step)
    if not (math.isfinite(stop_time) and stop_time > 0):
        raise ValueError(f"stop time {stop_time!r} s; allowed: a finite time > 0")
    steps = stop_time / step
    if abs(steps - round(steps)) > 1e-6 * steps:
        raise ValueError(f"stop time {stop_time!r} s is {steps:.6g} steps of {step!r} s; "
                         "allowed: a whole number of steps")
    if round(steps) + 1 > MAX_POINTS:
        raise ValueError(f"stop time {stop_time!r} s at a {step!r} s step is {round(steps)} "
                         f"steps; allowed: at most {MAX_POINTS - 1} (the recorded outputs of "
                         "a case are held in memory)")
    _, width, _ = window_layout(round(steps) + 1, step, transient, window, stop_time)
    if width < MIN_SAMPLES:
        what = (f"window {window!r} s" if window is not None else
                f"the {stop_time - transient:g} s after the transient of {transient!r} s")
        raise ValueError(f"{what} is {width} steps of {step!r} s; allowed: {MIN_SAMPLES} steps "
                         f"({MIN_SAMPLES * step:g} s) or more, for the band levels' spectrum")


def check_request(cases: list[Case], stop_time: float, step: float, transient: float = 0.0,
                  window: float | None = None, workers: int = 1) -> None:
    """ValueError, one sentence with the value and what is allowed, unless ``run_sweep`` can
    do what it is given: 1 to ``MAX_CASES`` distinct cases of known parameter names, run
    options that every case can be run and measured with (:func:`check_run_options`), a whole
    number of workers >= 1.  The values of a case are the model library's to check when it
    runs (a refused one is that case's error)."""
    from drive_rattle.catalog import parameter_spec

    _count(workers, "workers", 1)
    if not cases:
        raise ValueError("no cases to run; allowed: 1 case or more")
    _check_size(len(cases), "the list of cases")
    _distinct(cases)
    for name in sorted({n for c in cases for n in c.parameters}):
        parameter_spec(name)
    check_run_options(stop_time, step, transient, window)


def read_results(path: Path) -> list[dict]:
    """The whole rows of a result file (a last row cut short left out: :func:`_whole_rows`),
    numbers as floats (empty strings as NaN)."""
    header, rows, _ = _whole_rows(Path(path).read_bytes())
    for k, r in enumerate(rows, start=2):
        if len(r) != len(header):
            raise ValueError(f"{path} row {k} has {len(r)} fields, the header {len(header)}; "
                             "allowed: one field per column (the file was edited or spoilt)")
    return [{k: (v if k in TEXT_COLUMNS else (float(v) if v != "" else math.nan))
             for k, v in zip(header, r, strict=True)} for r in rows]


def _parse_param(text: str) -> tuple[str, tuple[float, float]]:
    """``(name, (lo, hi))`` of ``--param NAME=LO:HI`` (a range, LO < HI) or ``NAME=VALUE``
    (the parameter held at VALUE in every case); LO, HI and VALUE read by the parameter's
    declared type (``ParameterSpec.parse``: an enumeration's item names too)."""
    name, sep, rng = text.partition("=")
    name = name.strip()
    if not sep or not name:
        raise ValueError(f"--param {text!r} is not NAME=LO:HI or NAME=VALUE; allowed: e.g. "
                         "GearMeshRattle.gear.backlash=0.05e-3:0.2e-3")
    spec = _sweepable(name)
    lo_text, colon, hi_text = rng.partition(":")
    lo = spec.parse(lo_text, name)
    hi = spec.parse(hi_text, name) if colon else lo
    if colon and lo == hi:
        raise ValueError(f"--param {text!r} is a range of one point, which every case of the "
                         f"grid would repeat; allowed: LO < HI, or {name}={lo_text} to hold it "
                         "fixed")
    if lo > hi:
        raise ValueError(f"--param {text!r} runs from {lo!r} down to {hi!r}; allowed: LO < HI")
    return name, (lo, hi)


def _whole_number(text: str) -> int:
    """A count on the command line: ``20``, or ``1e5`` when it is whole."""
    try:
        return int(text)
    except ValueError:
        pass
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value == int(value)):
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number; allowed: a whole "
                                         "number such as 20 or 1e4")
    return int(value)


#: Exit statuses of the command line.
EXIT_OK, EXIT_STOPPED, EXIT_BAD_REQUEST, EXIT_CASES_FAILED = 0, 1, 2, 3


def main(argv=None) -> int:
    from .cli import Parser
    from .spectral_lines import MIN_SAMPLES

    ap = Parser(prog="python -m drive_rattle_cosim.sweep",
                description="Parameter sweep of the rattle co-simulation.",
                epilog=f"Exit status: {EXIT_OK} every case of the design ran without error; "
                       f"{EXIT_STOPPED} the sweep could not start or stopped before its end "
                       "(the result file held by another sweep, the workers lost, the disk "
                       "full: the message says how to resume); "
                       f"{EXIT_BAD_REQUEST} the request was refused before any work (one "
                       f"line); {EXIT_CASES_FAILED} the sweep ran, but cases failed (their "
                       "count printed, their errors in the error column; --retry-failed "
                       "runs them again).")
    ap.add_argument("--param", action="append", required=True,
                    metavar="UNIT.NAME=LO:HI",
                    help="a swept parameter (Real or Integer; an enumeration by its codes or "
                         "item names) and its range, LO < HI (SI units); UNIT.NAME=VALUE holds "
                         "it at VALUE in every case; each parameter once")
    design = ap.add_mutually_exclusive_group(required=True)
    design.add_argument("--grid", type=_whole_number, metavar="N",
                        help=f"N >= 2 values per parameter (at most {MAX_CASES} cases in all)")
    design.add_argument("--lhs", type=_whole_number, metavar="N",
                        help=f"N Latin-hypercube cases, 1 <= N <= {MAX_CASES}, Real "
                             "parameters")
    ap.add_argument("--seed", type=int, default=0, help="Latin-hypercube seed")
    ap.add_argument("--stop-time", type=float, default=0.3,
                    help="simulated time per case [s]: a whole number of steps")
    ap.add_argument("--step", type=float, default=1e-4,
                    help="communication step [s]: a whole number of nanoseconds")
    ap.add_argument("--transient", type=float, default=0.0,
                    help="start transient left out of the metrics [s], below the stop time")
    ap.add_argument("--window", type=float, default=None,
                    help=f"window of the statistics [s], at least {MIN_SAMPLES} steps and at "
                         "most what follows the transient (default: all after the transient)")
    ap.add_argument("--engine", choices=ENGINES, default="library",
                    help="library: the model library's compiled loop (default; the FMUs' "
                         "numbers at the model's cost); fmu: the FMUs of --fmu-dir in the "
                         "fmpy harness")
    ap.add_argument("--fmu-dir", type=Path, default=DIST,
                    help="folder of the FMUs on this machine, for --engine fmu (they are sent "
                         "to the workers)")
    ap.add_argument("--out", type=Path, default=Path("out") / "sweep.csv",
                    help="result CSV, appended case by case; run the same command again to "
                         "resume (a last row cut short is dropped and its case run again); "
                         "one sweep at a time (<out>.lock)")
    ap.add_argument("--workers", type=int, default=2,
                    help="LocalCluster worker processes (>= 1)")
    ap.add_argument("--scheduler", default=None, help="address of an existing dask scheduler")
    ap.add_argument("--retry-failed", action="store_true",
                    help="run the cases that failed before again")
    args = ap.parse_args(argv)
    resume = ("run `python -m drive_rattle_cosim.sweep "
              + " ".join(argv if argv is not None else sys.argv[1:]) + "` again")
    try:
        params: dict[str, tuple[float, float]] = {}
        for text in args.param:
            name, rng = _parse_param(text)
            if name in params:
                raise ValueError(f"--param {name} is given twice; allowed: each parameter once")
            params[name] = rng
        cases = (grid_design(params, args.grid) if args.grid is not None
                 else latin_hypercube_design(params, args.lhs, args.seed))
        counts = run_sweep(cases, args.out, args.fmu_dir if args.engine == "fmu" else None,
                           args.stop_time, args.step, args.workers, args.scheduler,
                           retry_failed=args.retry_failed, transient=args.transient,
                           window=args.window, resume_hint=resume)
    except (ValueError, FileNotFoundError) as err:
        ap.error(str(err))
    except (ResultFileBusyError, SweepInterruptedError) as err:
        print(f"error: {err}", file=sys.stderr)
        return EXIT_STOPPED
    print(f"{counts['done']} cases run ({counts['failed']} failed), {counts['skipped']} "
          f"already done ({counts['failed_before']} of them failed), {counts['total']} in the "
          f"design -> {args.out}")
    failed = counts["failed"] + counts["failed_before"]
    if failed:
        print(f"error: {failed} of {counts['total']} cases failed (their errors are in the "
              f"error column of {args.out}; --retry-failed runs them again)", file=sys.stderr)
        return EXIT_CASES_FAILED
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
