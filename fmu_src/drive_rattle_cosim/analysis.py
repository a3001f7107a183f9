"""Statistics of rattle runs after the start transient, with their window-to-window scatter,
and the comparison with the paper's reported figures.  Needs numpy and scipy (not the FMUs).

Rattle is chaotic: a run is judged by statistics, never by its trajectory, and a statistic
means something only with its scatter.  ``windowed_statistics`` drops a stated start
transient, cuts the rest of the record into equal windows, computes ``rattle_statistics`` in
each, and reports every figure as mean +- standard deviation (and min/max) over the windows.
The spectral figures come from the line search of ``drive_rattle_cosim.spectral_lines``.
docs/analysis.md describes the method.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, fields

import numpy as np

from .spectral_lines import (
    UNEXPLAINED,
    LineCatalogue,
    LineDetection,
    LineSearch,
    Spectrum,
    detect_lines,
    welch_spectrum,
)

__all__ = [
    "DOMINANT_BAND", "PAPER_FIGURES", "LineCatalogue", "LineSearch", "RattleStatistics",
    "Scatter", "Spectrum", "WindowedStatistics", "catalogue_for", "detect_lines",
    "markdown_table", "onsets_from_counters", "paper_comparison", "rattle_statistics",
    "welch_spectrum", "windowed_statistics",
]

#: Band [Hz] of the paper's "dominant impact line" (its Fig. 5 shows lines up to ~1.5 kHz).
DOMINANT_BAND = (100.0, 1500.0)
#: Outputs ``rattle_statistics`` needs; the others it reads are optional (nan when absent).
REQUIRED_SIGNALS = ("wheel.phi", "mesh.W")

#: The paper's reported figures (Theodossiades et al. 2008, section 3 and Figures 3-5), as
#: printed next to this run's: quantity -> text.  The paper's own gear data are unpublished.
PAPER_FIGURES = {
    "mean wheel speed [rad/s]": "44.5",
    "max deflection [µm]": "≈ 1 (\"of the order of 1 µm\")",
    "typical impact velocity (median) [mm/s]": "≈ 4 (\"of the order of 4 mm/s\")",
    "pairs loaded while in contact [1]": "3–4 (\"in simultaneous impact\")",
    "highest detected line [Hz]": "≈ 1500 (impact lines up to about 1.5 kHz)",
    "strongest line 100–1500 Hz [Hz]": "380 (its gear; this pair's mesh is 277 Hz)",
    "strongest line above the noise floor [dB]": "not given (a clear line)",
    "windows with a line at half the strongest's frequency [1]": "yes (190 Hz)",
}


@dataclass
class RattleStatistics:
    """Statistics of one stretch of a run (SI units unless stated).  Per-step figures (peaks,
    time averages) are taken over the samples after the first: each sample closes the step
    that ends at it."""

    duration: float  # s
    mean_wheel_speed: float  # rad/s, from the angle advanced
    impacts_per_second_drive: float  # contact onsets per second, drive flank
    impacts_per_second_coast: float
    median_impact_speed: float  # m/s, normal approach speed at onsets (0 without onsets)
    mean_impact_speed: float  # m/s
    peak_impact_speed: float  # m/s
    max_penetration: float  # m
    rms_normal_force: float  # N
    peak_normal_force: float  # N
    contact_fraction: float  # fraction of samples with a pair in contact
    impact_energy_rate: float  # W: sum of 1/2 m_n v^2 over onsets per second
    mean_loaded_pairs: float = math.nan  # pairs in contact, averaged over samples in contact
    max_loaded_pairs: float = math.nan
    # --- spectral lines of the total normal force (nan unless a line search was asked for)
    lines_detected: float = math.nan  # detected lines in DOMINANT_BAND
    lines_unexplained: float = math.nan  # of those, lines no catalogue entry explains
    highest_line_frequency: float = math.nan  # Hz, highest detected line in the search band
    dominant_line_frequency: float = math.nan  # Hz, strongest detected line in DOMINANT_BAND
    dominant_line_level: float = math.nan  # dB above the noise floor
    #: 1 when a line was detected at half the strongest line's frequency (within the
    #: resolution), 0 when not or when there is no line: over windows, the fraction of windows.
    half_line_found: float = math.nan
    #: The strongest line's name in the catalogue, "unexplained", or "none found" ("" without
    #: a line search).
    dominant_line_name: str = ""


def onsets_from_counters(time, impacts_drive, impacts_coast, v_impact):
    """Contact onsets recovered from a unit's recorded outputs: ``(times, speeds, flanks)``.

    At each communication point where a cumulative counter (``mesh.impacts_drive`` /
    ``mesh.impacts_coast``) grew, one onset per increment is dated to that point; its speed is
    ``mesh.v_impact``, the approach speed of the *last* onset within the step (several onsets in
    one step share it)."""
    t = np.asarray(time, dtype=float)
    d = np.diff(np.asarray(impacts_drive, dtype=int), prepend=int(impacts_drive[0]))
    c = np.diff(np.asarray(impacts_coast, dtype=int), prepend=int(impacts_coast[0]))
    v = np.asarray(v_impact, dtype=float)
    times, speeds, flanks = [], [], []
    for k in np.nonzero((d > 0) | (c > 0))[0]:
        for flank, count in ((1, d[k]), (-1, c[k])):
            times += [t[k]] * int(count)
            speeds += [v[k]] * int(count)
            flanks += [flank] * int(count)
    return times, speeds, flanks


def catalogue_for(mesh_params, drive_params) -> LineCatalogue:
    """The expected lines of a run: mesh of ``mesh_params.z_pinion`` teeth, engine orders of
    ``drive_params`` at its mean speed."""
    return LineCatalogue(shaft_frequency=drive_params.w_mean / (2.0 * math.pi),
                         z_pinion=int(mesh_params.z_pinion),
                         orders=tuple(float(k) for k, _a, _p in drive_params.order_terms()))


def _signal(signals: dict, name: str, n: int):
    return np.asarray(signals[name], dtype=float) if name in signals else np.full(n, np.nan)


def rattle_statistics(time, signals: dict, onset_speeds, onset_flanks, normal_mass: float, *,
                      lines: LineSearch | None = None, catalogue: LineCatalogue | None = None,
                      segment_seconds: float = 0.25) -> RattleStatistics:
    """Statistics of a recorded stretch.  ``signals`` holds the unit outputs by name
    (``wheel.phi`` and ``mesh.W`` required; ``mesh.W_peak``, ``mesh.delta_peak``,
    ``mesh.n_contact`` optional, nan when absent); the onsets are those within the stretch;
    ``normal_mass`` [kg] is the wheel's effective mass on the tooth normal.  With ``lines``,
    the total normal force is searched for spectral lines (Welch segments of
    ``segment_seconds``), named from ``catalogue``."""
    t = np.asarray(time, dtype=float)
    missing = [n for n in REQUIRED_SIGNALS if n not in signals]
    if missing:
        raise ValueError(f"rattle_statistics: outputs {missing} are missing; required: "
                         f"{list(REQUIRED_SIGNALS)}")
    if t.ndim != 1 or len(t) < 2 or not t[-1] > t[0]:
        raise ValueError(f"rattle_statistics: need at least 2 increasing time points; got "
                         f"{len(t)} over {t[-1] - t[0] if len(t) else 0!r} s")
    duration = float(t[-1] - t[0])
    phi = np.asarray(signals["wheel.phi"], dtype=float)
    steps = slice(1, None)  # the samples that close a step of the stretch
    W = np.asarray(signals["mesh.W"], dtype=float)[steps]
    W_peak = _signal(signals, "mesh.W_peak", len(t))[steps]
    n_contact = _signal(signals, "mesh.n_contact", len(t))[steps]
    speeds = np.asarray(onset_speeds, dtype=float)
    flanks = np.asarray(onset_flanks, dtype=int)
    in_contact = n_contact[n_contact > 0]
    stats = RattleStatistics(
        duration=duration,
        mean_wheel_speed=float((phi[-1] - phi[0]) / duration),
        impacts_per_second_drive=float(np.sum(flanks > 0) / duration),
        impacts_per_second_coast=float(np.sum(flanks < 0) / duration),
        median_impact_speed=float(np.median(speeds)) if len(speeds) else 0.0,
        mean_impact_speed=float(np.mean(speeds)) if len(speeds) else 0.0,
        peak_impact_speed=float(np.max(speeds)) if len(speeds) else 0.0,
        max_penetration=float(np.max(_signal(signals, "mesh.delta_peak", len(t))[steps])),
        rms_normal_force=float(np.sqrt(np.mean(W * W))),
        peak_normal_force=float(np.max(np.where(np.isnan(W_peak), W, W_peak))),
        contact_fraction=(float(np.mean(n_contact > 0)) if not np.isnan(n_contact).any()
                          else math.nan),
        impact_energy_rate=float(0.5 * normal_mass * np.sum(speeds * speeds) / duration),
        mean_loaded_pairs=float(np.mean(in_contact)) if in_contact.size else 0.0,
        max_loaded_pairs=float(np.max(n_contact)) if len(n_contact) else math.nan,
    )
    if np.isnan(n_contact).any():
        stats.mean_loaded_pairs = stats.max_loaded_pairs = math.nan
    if lines is not None:
        detection = detect_lines(welch_spectrum(t[steps], W, segment_seconds), lines, catalogue)
        _line_figures(stats, detection)
    return stats


def _line_figures(stats: RattleStatistics, detection: LineDetection) -> None:
    band = detection.in_band(*DOMINANT_BAND)
    stats.lines_detected = float(len(band))
    stats.lines_unexplained = float(sum(ln.kind == UNEXPLAINED for ln in band))
    stats.highest_line_frequency = (max(ln.frequency for ln in detection.lines)
                                    if detection.lines else math.nan)
    dominant = detection.strongest(*DOMINANT_BAND)
    stats.half_line_found = 0.0
    stats.dominant_line_name = "none found"
    if dominant is not None:
        stats.dominant_line_frequency = dominant.frequency
        stats.dominant_line_level = dominant.ratio_db
        stats.dominant_line_name = dominant.name or UNEXPLAINED
        stats.half_line_found = float(detection.near(dominant.frequency / 2) is not None)


@dataclass(frozen=True)
class Scatter:
    """A statistic over windows: mean, sample standard deviation (ddof 1; nan for one
    window), min, max, and the number of windows that had a value (nan values left out)."""

    mean: float
    std: float
    min: float
    max: float
    n: int

    @staticmethod
    def of(values) -> Scatter:
        v = np.asarray([x for x in values if not math.isnan(x)], dtype=float)
        if v.size == 0:
            return Scatter(math.nan, math.nan, math.nan, math.nan, 0)
        return Scatter(float(np.mean(v)), float(np.std(v, ddof=1)) if v.size > 1 else math.nan,
                       float(np.min(v)), float(np.max(v)), int(v.size))

    def text(self, scale: float = 1.0, digits: int = 4) -> str:
        """``"mean ± std (min–max)"`` of the values times ``scale``."""
        if self.n == 0:
            return "none in any window"
        m, lo, hi = self.mean * scale, self.min * scale, self.max * scale
        if self.n == 1:
            return f"{m:.{digits}g} (one window)"
        return (f"{m:.{digits}g} ± {self.std * abs(scale):.2g} "
                f"({lo:.{digits}g}–{hi:.{digits}g})")

    @property
    def relative_scatter(self) -> float:
        """std / |mean| (nan when undefined)."""
        return self.std / abs(self.mean) if self.mean and not math.isnan(self.std) else math.nan


@dataclass
class WindowedStatistics:
    """``rattle_statistics`` of equal windows after a discarded start transient."""

    transient: float  # s discarded from the record's start
    window: float  # s per window (a whole number of samples)
    starts: list[float]  # s, start time of each window
    slices: list[slice]  # sample index range of each window (its first sample opens it)
    windows: list[RattleStatistics]
    unused_tail: float  # s at the record's end that fill no whole window

    def scatter(self, name: str) -> Scatter:
        """Mean, scatter and range over the windows of the numeric statistic ``name``."""
        return Scatter.of([float(getattr(w, name)) for w in self.windows])

    def text(self, name: str, scale: float = 1.0) -> str:
        """``Scatter.text`` of ``name``, saying in how many windows it had a value when not
        in all (a spectral line is not found in every window)."""
        sc = self.scatter(name)
        text = sc.text(scale)
        if 0 < sc.n < len(self.windows):
            text += f"; in {sc.n} of {len(self.windows)} windows"
        return text

    def summary(self) -> dict[str, Scatter]:
        """Every numeric statistic with its scatter over the windows."""
        return {f.name: self.scatter(f.name) for f in fields(RattleStatistics)
                if f.type in ("float", float)}

    def most_common(self, name: str) -> tuple[str, int]:
        """The most frequent value of a text statistic over the windows, and in how many."""
        value, count = Counter(getattr(w, name) for w in self.windows).most_common(1)[0]
        return value, count


def windowed_statistics(time, signals: dict, onset_times, onset_speeds, onset_flanks,
                        normal_mass: float, transient: float = 0.0,
                        window: float | None = None, *, lines: LineSearch | None = None,
                        catalogue: LineCatalogue | None = None,
                        segment_seconds: float = 0.25) -> WindowedStatistics:
    """Statistics of a recorded run in windows of ``window`` seconds (None: one window over
    everything after the transient) after dropping the first ``transient`` seconds.

    The record must be uniformly sampled.  Window i spans samples ``a_i .. a_i + n`` (n the
    window in samples): its onsets are those with ``t[a_i] < t_onset <= t[a_i + n]``.  A tail
    shorter than a window is left out (``unused_tail``)."""
    t = np.asarray(time, dtype=float)
    if t.ndim != 1 or len(t) < 3:
        raise ValueError(f"windowed_statistics: need at least 3 time points; got {len(t)}")
    dt = np.diff(t)
    h = float(np.median(dt))
    if not h > 0 or np.max(np.abs(dt - h)) > 1e-6 * h:
        raise ValueError("windowed_statistics: the time points are not uniformly spaced "
                         f"(steps {np.min(dt)!r}..{np.max(dt)!r} s); allowed: a fixed step")
    record = float(t[-1] - t[0])
    if not (math.isfinite(transient) and 0.0 <= transient < record):
        raise ValueError(f"windowed_statistics: transient = {transient!r} s; allowed: "
                         f"0 <= transient < the record's {record:g} s")
    first = round(transient / h)
    available = len(t) - 1 - first
    if window is None:
        width = available
    else:
        if not (math.isfinite(window) and window > 0):
            raise ValueError(f"windowed_statistics: window = {window!r} s; allowed: > 0")
        width = round(window / h)
        if width < 2 or width > available:
            raise ValueError(
                f"windowed_statistics: a window of {window!r} s ({width} samples) does not "
                f"fit the {available * h:g} s after a transient of {transient:g} s of the "
                f"{record:g} s record (at a {h:g} s step); allowed: 2 samples up to that")
    count = available // width
    onset_t = np.asarray(onset_times, dtype=float)
    onset_v = np.asarray(onset_speeds, dtype=float)
    onset_f = np.asarray(onset_flanks, dtype=int)
    series = {k: np.asarray(v) for k, v in signals.items()}
    starts, slices, results = [], [], []
    for i in range(count):
        a, b = first + i * width, first + (i + 1) * width
        span = slice(a, b + 1)
        inside = (onset_t > t[a]) & (onset_t <= t[b])
        results.append(rattle_statistics(
            t[span], {k: v[span] for k, v in series.items()}, onset_v[inside], onset_f[inside],
            normal_mass, lines=lines, catalogue=catalogue, segment_seconds=segment_seconds))
        starts.append(float(t[a]))
        slices.append(span)
    end = first + count * width
    return WindowedStatistics(transient=float(t[first] - t[0]), window=float(width * h),
                              starts=starts, slices=slices, windows=results,
                              unused_tail=float(t[-1] - t[end]))


#: Rows of the paper comparison: (quantity as in PAPER_FIGURES, statistic, display scale).
PAPER_ROWS = (
    ("mean wheel speed [rad/s]", "mean_wheel_speed", 1.0),
    ("max deflection [µm]", "max_penetration", 1e6),
    ("typical impact velocity (median) [mm/s]", "median_impact_speed", 1e3),
    ("pairs loaded while in contact [1]", "mean_loaded_pairs", 1.0),
    ("highest detected line [Hz]", "highest_line_frequency", 1.0),
    ("strongest line 100–1500 Hz [Hz]", "dominant_line_frequency", 1.0),
    ("strongest line above the noise floor [dB]", "dominant_line_level", 1.0),
    ("windows with a line at half the strongest's frequency [1]", "half_line_found", 1.0),
)

#: Further statistics: (quantity, statistic, display scale).
FURTHER_ROWS = (
    ("impacts per second, drive flank [1/s]", "impacts_per_second_drive", 1.0),
    ("impacts per second, coast flank [1/s]", "impacts_per_second_coast", 1.0),
    ("mean impact velocity [mm/s]", "mean_impact_speed", 1e3),
    ("peak impact velocity [mm/s]", "peak_impact_speed", 1e3),
    ("rattle index: impact energy per second [mW]", "impact_energy_rate", 1e3),
    ("RMS normal force [N]", "rms_normal_force", 1.0),
    ("peak normal force [N]", "peak_normal_force", 1.0),
    ("fraction of time in contact [1]", "contact_fraction", 1.0),
    ("most pairs loaded at once [1]", "max_loaded_pairs", 1.0),
    ("detected lines 100–1500 Hz [1]", "lines_detected", 1.0),
    ("of those, unexplained [1]", "lines_unexplained", 1.0),
)


def paper_comparison(ws: WindowedStatistics) -> list[tuple[str, str, str]]:
    """Rows ``(quantity, this run: "mean ± scatter (min–max over windows)", paper)``."""
    rows = [(q, ws.text(name, scale), PAPER_FIGURES[q]) for q, name, scale in PAPER_ROWS]
    name, n = ws.most_common("dominant_line_name")
    rows.insert(6, ("strongest line's name (most windows)",
                    f"{name or '—'} ({n} of {len(ws.windows)} windows)",
                    "—"))
    return rows


def further_statistics(ws: WindowedStatistics) -> list[tuple[str, str]]:
    """Rows ``(quantity, this run: "mean ± scatter (min–max over windows)")``."""
    return [(q, ws.text(name, scale)) for q, name, scale in FURTHER_ROWS]


def markdown_table(rows, headers=("quantity", "this run", "paper")) -> str:
    """A Markdown table; floats printed with 4 significant digits."""
    def fmt(v):
        return f"{v:.4g}" if isinstance(v, float) else str(v)

    lines = ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    lines += ["| " + " | ".join(fmt(v) for v in row) + " |" for row in rows]
    return "\n".join(lines) + "\n"
