"""Statistics of rattle runs after the start transient, with their window-to-window scatter,
and the comparison with the paper's reported figures.  Needs numpy and scipy (not the FMUs).

Rattle is chaotic: a run is judged by statistics, never by its trajectory, and a statistic
means something only with its scatter.  ``windowed_statistics`` drops a stated start
transient, cuts the rest of the record into equal windows, computes ``rattle_statistics`` in
each, and reports every figure as mean +- standard deviation (and min/max) over the windows.
The spectral figures come from ``drive_rattle_cosim.spectral_lines``: the line search (lines
against the noise floor, resonances told apart), the spectral extent and the sub-harmonic test.
docs/analysis.md describes the method.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field, fields

import numpy as np

from .spectral_lines import (
    UNEXPLAINED,
    ExtentSearch,
    LineCatalogue,
    LineDetection,
    LineSearch,
    SpectralExtent,
    Spectrum,
    Subharmonic,
    SubharmonicSearch,
    detect_lines,
    spectral_extent,
    subharmonic_test,
    welch_spectrum,
)

__all__ = [
    "DOMINANT_BAND", "PAPER_FIGURES", "ExtentSearch", "LineCatalogue", "LineSearch",
    "RattleStatistics", "Scatter", "Spectrum", "StrongestLine", "SubharmonicSearch",
    "WindowedStatistics", "catalogue_for", "detect_lines", "markdown_table", "number_text",
    "onsets_from_counters", "paper_comparison", "rattle_statistics", "strongest_line",
    "welch_spectrum", "windowed_statistics",
]

#: Band [Hz] of the paper's "dominant impact line" (its Fig. 5 shows lines up to ~1.5 kHz).
DOMINANT_BAND = (100.0, 1500.0)
#: Outputs ``rattle_statistics`` needs; the others it reads are optional (nan when absent).
REQUIRED_SIGNALS = ("wheel.phi", "mesh.W")

#: Flanks of the per-flank statistics: (suffix of the statistic's name, sign in onset_flanks).
FLANKS = (("drive", 1), ("coast", -1))
#: Percentiles of the impact speeds reported per flank.
PERCENTILES = (10, 50, 90)

#: Rows of the strongest line (``strongest_line``): one line, the same in every window.
STRONGEST_ROW = ("strongest line 100–1500 Hz: the line with the highest mean PSD level over "
                 "the windows [Hz]")
STRONGEST_LEVEL_ROW = "strongest line: PSD level, mean over the windows [dB re 1 N²/Hz]"
STRONGEST_ABOVE_FLOOR_ROW = "strongest line above the noise floor [dB]"

#: The paper's reported figures (Theodossiades et al. 2008, section 3 and Figures 3-5), as
#: printed next to this run's: quantity -> text.  The paper's own gear data are unpublished,
#: and it does not say which statistic its "typical" figures are, so no row claims agreement.
PAPER_FIGURES = {
    "mean wheel speed [rad/s]": "44.5",
    "max deflection [µm]": "≈ 1 (\"of the order of 1 µm\")",
    "impact speed at onsets, drive flank: 10th percentile [mm/s]": "—",
    "impact speed at onsets, drive flank: median [mm/s]":
        "\"of the order of 4 mm/s\": which statistic and flank is not stated (its own gear "
        "data); not a like-for-like figure",
    "impact speed at onsets, drive flank: 90th percentile [mm/s]": "—",
    "impact speed at onsets, drive flank: RMS [mm/s]": "—",
    "impact energy rate, drive flank: Σ ½ m_n v² per second [mW]": "—",
    "impact speed at onsets, coast flank: 10th percentile [mm/s]": "—",
    "impact speed at onsets, coast flank: median [mm/s]": "—",
    "impact speed at onsets, coast flank: 90th percentile [mm/s]": "—",
    "impact speed at onsets, coast flank: RMS [mm/s]": "—",
    "impact energy rate, coast flank: Σ ½ m_n v² per second [mW]": "—",
    "pairs loaded while in contact [1]": "3–4 (\"in simultaneous impact\")",
    "spectral extent: 1/3-octave PSD 10 dB below its 100–500 Hz mean [Hz]":
        "impact lines \"up to about 1.5 kHz\" (its band and criterion not stated)",
    STRONGEST_ROW: "380 (its gear; this pair's mesh is 277 Hz)",
    STRONGEST_LEVEL_ROW: "—",
    STRONGEST_ABOVE_FLOOR_ROW: "not given (a clear line)",
    "windows with a sub-harmonic of the forcing (power at odd multiples of f0/2) [1]":
        "yes (190 Hz, half its 380 Hz line)",
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
    impact_energy_rate: float  # W: sum of 1/2 m_n v^2 over onsets per second, both flanks
    mean_loaded_pairs: float = math.nan  # pairs in contact, averaged over samples in contact
    max_loaded_pairs: float = math.nan
    # --- impact speeds per flank [m/s]: percentiles and RMS of the speeds at the flank's
    # onsets (nan without onsets there); energy rate [W] = sum of 1/2 m_n v^2 / duration
    impact_speed_p10_drive: float = math.nan
    impact_speed_p50_drive: float = math.nan
    impact_speed_p90_drive: float = math.nan
    impact_speed_rms_drive: float = math.nan
    impact_energy_rate_drive: float = math.nan
    impact_speed_p10_coast: float = math.nan
    impact_speed_p50_coast: float = math.nan
    impact_speed_p90_coast: float = math.nan
    impact_speed_rms_coast: float = math.nan
    impact_energy_rate_coast: float = math.nan
    # --- spectral figures of the total normal force (nan unless a line search was asked for)
    lines_detected: float = math.nan  # detected lines in DOMINANT_BAND
    lines_unexplained: float = math.nan  # of those, lines no catalogue entry explains
    #: Peaks over the threshold in DOMINANT_BAND that are resonances, not lines.
    resonances_detected: float = math.nan
    dominant_line_frequency: float = math.nan  # Hz, strongest detected line in DOMINANT_BAND
    dominant_line_level: float = math.nan  # dB above the noise floor
    #: Hz: where the smoothed PSD falls ``drop_db`` below its reference-band mean (band open
    #: to Nyquist); the band top when it never does (then ``spectral_extent_censored`` = 1).
    spectral_extent: float = math.nan
    spectral_extent_censored: float = math.nan  # 1 or 0: over windows, the fraction
    #: 1 when the sub-harmonic test flags power at (k + 1/2) f0, 0 when not (nan when no
    #: test was possible): over windows, the fraction of windows.
    subharmonic_flag: float = math.nan
    subharmonic_ratio_db: float = math.nan  # the half comb's power over the comb's [dB]
    subharmonic_fundamental: float = math.nan  # Hz, f0 of the test
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
                      segment_seconds: float = 0.25, extent: ExtentSearch | None = None,
                      subharmonics: SubharmonicSearch | None = None,
                      fundamental: float | None = None) -> RattleStatistics:
    """Statistics of a recorded stretch.  ``signals`` holds the unit outputs by name
    (``wheel.phi`` and ``mesh.W`` required; ``mesh.W_peak``, ``mesh.delta_peak``,
    ``mesh.n_contact`` optional, nan when absent); the onsets are those within the stretch;
    ``normal_mass`` [kg] is the wheel's effective mass on the tooth normal.

    With ``lines``, the spectral figures of the total normal force are computed from one
    Welch spectrum (segments of ``segment_seconds``, up to Nyquist): its lines (named from
    ``catalogue``), its extent (``extent``, default ``ExtentSearch()``) and the sub-harmonic
    test (``subharmonics``, default ``SubharmonicSearch()``) with the fundamental
    ``fundamental`` [Hz] -- by default the catalogue's (the forcing's period), without a
    catalogue the strongest line in DOMINANT_BAND."""
    return _statistics_and_lines(time, signals, onset_speeds, onset_flanks, normal_mass,
                                 lines=lines, catalogue=catalogue,
                                 segment_seconds=segment_seconds, extent=extent,
                                 subharmonics=subharmonics, fundamental=fundamental)[0]


def _statistics_and_lines(time, signals: dict, onset_speeds, onset_flanks, normal_mass: float,
                          *, lines, catalogue, segment_seconds, extent, subharmonics,
                          fundamental) -> tuple[RattleStatistics, LineDetection | None]:
    """``rattle_statistics`` and its line search (None without one)."""
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
    for flank, sign in FLANKS:
        v = speeds[flanks == sign]
        if v.size:
            for q, value in zip(PERCENTILES, np.percentile(v, PERCENTILES), strict=True):
                setattr(stats, f"impact_speed_p{q}_{flank}", float(value))
            setattr(stats, f"impact_speed_rms_{flank}", float(np.sqrt(np.mean(v * v))))
        setattr(stats, f"impact_energy_rate_{flank}",
                float(0.5 * normal_mass * np.sum(v * v) / duration))
    detection = None
    if lines is not None:
        spec = welch_spectrum(t[steps], W, segment_seconds)
        detection = detect_lines(spec, lines, catalogue)
        _line_figures(stats, detection)
        ext = spectral_extent(spec, extent)
        stats.spectral_extent = ext.frequency
        stats.spectral_extent_censored = (float(ext.censored) if math.isfinite(ext.frequency)
                                          else math.nan)
        f0 = fundamental
        if f0 is None:
            f0 = (catalogue.fundamental if catalogue is not None
                  else stats.dominant_line_frequency)
        stats.subharmonic_fundamental = float(f0)
        if math.isfinite(f0):
            sub = subharmonic_test(spec, f0, subharmonics)
            if sub.positions:
                stats.subharmonic_flag = float(sub.flag)
                stats.subharmonic_ratio_db = sub.ratio_db
    return stats, detection


def _line_figures(stats: RattleStatistics, detection: LineDetection) -> None:
    band = detection.in_band(*DOMINANT_BAND)
    stats.lines_detected = float(len(band))
    stats.lines_unexplained = float(sum(ln.kind == UNEXPLAINED for ln in band))
    stats.resonances_detected = float(sum(DOMINANT_BAND[0] <= r.frequency <= DOMINANT_BAND[1]
                                          for r in detection.resonances))
    dominant = detection.strongest(*DOMINANT_BAND)
    stats.dominant_line_name = "none found"
    if dominant is not None:
        stats.dominant_line_frequency = dominant.frequency
        stats.dominant_line_level = dominant.ratio_db
        stats.dominant_line_name = dominant.name or UNEXPLAINED


def number_text(value: float, missing: str, scale: float = 1.0, digits: int = 4,
                spec: str | None = None) -> str:
    """``value`` times ``scale`` to ``digits`` significant digits (or in the format ``spec``,
    e.g. ``".2f"``), or ``missing`` -- why there is no value, in words -- when it is not a
    finite number: a report never prints nan or inf.  Every statistic of the reports is
    written through this function."""
    x = value * scale
    if not math.isfinite(x):
        return missing
    return format(x, spec if spec is not None else f".{digits}g")


@dataclass(frozen=True)
class Scatter:
    """A statistic over windows: mean, sample standard deviation (ddof 1; nan for one
    window), min, max, and the number of windows that had a value (nan and infinite values
    left out)."""

    mean: float
    std: float
    min: float
    max: float
    n: int

    @staticmethod
    def of(values) -> Scatter:
        v = np.asarray([x for x in values if math.isfinite(x)], dtype=float)
        if v.size == 0:
            return Scatter(math.nan, math.nan, math.nan, math.nan, 0)
        return Scatter(float(np.mean(v)), float(np.std(v, ddof=1)) if v.size > 1 else math.nan,
                       float(np.min(v)), float(np.max(v)), int(v.size))

    def text(self, scale: float = 1.0, digits: int = 4,
             missing: str = "none in any window") -> str:
        """``"mean ± std (min–max)"`` of the values times ``scale``; ``missing`` when no
        window had a value."""
        if self.n == 0:
            return missing
        m = number_text(self.mean, missing, scale, digits)
        if self.n == 1:
            return f"{m} (one window)"
        lo, hi = (number_text(x, missing, scale, digits) for x in (self.min, self.max))
        dash = " to " if min(self.min * scale, self.max * scale) < 0 else "–"  # not "-1–-0.5"
        return f"{m} ± {number_text(self.std, missing, abs(scale), 2)} ({lo}{dash}{hi})"

    @property
    def relative_scatter(self) -> float:
        """std / |mean| (nan when undefined)."""
        return self.std / abs(self.mean) if self.mean and not math.isnan(self.std) else math.nan


#: Statistics that only a line search computes (``rattle_statistics(lines=...)``).
SPECTRAL = ("lines_detected", "lines_unexplained", "resonances_detected",
            "dominant_line_frequency", "dominant_line_level", "spectral_extent",
            "spectral_extent_censored", "subharmonic_flag", "subharmonic_ratio_db",
            "subharmonic_fundamental")
NO_LINE_SEARCH = "no spectrum analysed (no line search asked for)"
NO_LINE = f"no line found in {DOMINANT_BAND[0]:g}–{DOMINANT_BAND[1]:g} Hz"


def missing_reason(name: str, window: RattleStatistics, line_search: bool = True) -> str:
    """Why the statistic ``name`` has no value in ``window``, in words (``line_search``:
    whether the spectral statistics were asked for)."""
    if name in SPECTRAL and not line_search:
        return NO_LINE_SEARCH
    for flank, _sign in FLANKS:
        if name.startswith("impact_speed_") and name.endswith("_" + flank):
            return f"no {flank}-flank onset"
    if name.startswith("dominant_line"):
        return NO_LINE
    if name.startswith("spectral_extent"):
        return "no power in the 100–500 Hz reference band"
    if name == "subharmonic_fundamental":
        return f"no fundamental: no catalogue and {NO_LINE}"
    if name.startswith("subharmonic"):
        if name == "subharmonic_ratio_db" and math.isfinite(window.subharmonic_flag):
            return ("no power above the noise floor at the odd multiples of f0/2 (or at the "
                    "multiples of f0)")
        return "no sub-harmonic test possible (no position with a noise floor in the band)"
    if name == "max_penetration":
        return "mesh.delta_peak not recorded"
    if name in ("contact_fraction", "mean_loaded_pairs", "max_loaded_pairs"):
        return "mesh.n_contact not recorded"
    return "no value"


@dataclass
class WindowedStatistics:
    """``rattle_statistics`` of equal windows after a discarded start transient."""

    transient: float  # s discarded from the record's start
    window: float  # s per window (a whole number of samples)
    starts: list[float]  # s, start time of each window
    slices: list[slice]  # sample index range of each window (its first sample opens it)
    windows: list[RattleStatistics]
    unused_tail: float  # s at the record's end that fill no whole window
    #: The line search of each window's force spectrum (empty without a line search).
    detections: list[LineDetection] = field(default_factory=list)

    def scatter(self, name: str) -> Scatter:
        """Mean, scatter and range over the windows of the numeric statistic ``name``."""
        return Scatter.of([float(getattr(w, name)) for w in self.windows])

    def missing_text(self, name: str) -> str:
        """Why ``name`` has no value in the windows that lack one, in words: "no coast-flank
        onset", "no line found in 100–1500 Hz", ... (the reasons of the windows, joined)."""
        reasons = dict.fromkeys(missing_reason(name, w, bool(self.detections))
                                for w in self.windows
                                if not math.isfinite(float(getattr(w, name))))
        return " or ".join(reasons) or "no value"

    def text(self, name: str, scale: float = 1.0) -> str:
        """``Scatter.text`` of ``name``; where a window has no value, why, in words ("no
        coast-flank onset in any window"; "...; in 2 of 4 windows (no line found in
        100–1500 Hz in the others)")."""
        sc = self.scatter(name)
        if sc.n == 0:
            reason = self.missing_text(name)
            return reason if reason == NO_LINE_SEARCH else f"{reason} in any window"
        text = sc.text(scale)
        if sc.n < len(self.windows):
            text += (f"; in {sc.n} of {len(self.windows)} windows ({self.missing_text(name)} "
                     "in the others)")
        return text

    def summary(self) -> dict[str, Scatter]:
        """Every numeric statistic with its scatter over the windows."""
        return {f.name: self.scatter(f.name) for f in fields(RattleStatistics)
                if f.type in ("float", float)}

    def most_common(self, name: str) -> tuple[str, int]:
        """The most frequent value of a text statistic over the windows, and in how many."""
        value, count = Counter(getattr(w, name) for w in self.windows).most_common(1)[0]
        return value, count


@dataclass(frozen=True)
class StrongestLine:
    """The line with the highest mean level over the windows: one line, followed through
    every window's spectrum (never a mean of different lines' frequencies)."""

    frequency: float  # Hz: its refined frequency, averaged over the windows that found it
    name: str  # its catalogue name ("unexplained" when none fits), the most frequent
    kind: str  # mesh, sideband, engine order, unexplained
    found_in: int  # windows whose own line search found it
    windows: int  # windows in all
    #: The PSD at the line [dB re 1 unit²/Hz] in every window (the highest bin within one
    #: bin of ``frequency``), whether or not that window's search found the line there.
    level_db: Scatter
    #: The same bin over the window's noise floor [dB] (windows with a floor there).
    above_floor_db: Scatter

    def text(self) -> str:
        """``"830.1 (3×mesh), found in 4 of 5 windows"``."""
        return (f"{self.frequency:.1f} ({self.name}), found in {self.found_in} of "
                f"{self.windows} windows")


def strongest_line(ws: WindowedStatistics, band: tuple[float, float] = DOMINANT_BAND
                   ) -> StrongestLine | None:
    """The strongest line of the windows in ``band`` [Hz], or None when no window's line
    search found a line there (or none was made).

    The candidates are the lines the windows' own searches found in the band, taken as one
    line where they lie within one bin of each other.  Each candidate's level is read from
    every window's spectrum at its frequency -- in a window that did not find it, too, so a
    line found in few windows is not ranked by those alone -- and the candidate with the
    highest mean level (dB, over all windows) is the strongest line."""
    found = sorted(((ln.frequency, i, ln) for i, d in enumerate(ws.detections)
                    for ln in d.in_band(*band)), key=lambda x: x[0])
    if not found:
        return None
    resolution = ws.detections[0].resolution
    groups: list[list] = []
    for member in found:
        if groups and member[0] - groups[-1][0][0] <= resolution:
            groups[-1].append(member)
        else:
            groups.append([member])
    best = None
    for group in groups:
        frequency = float(np.mean([f for f, _i, _ln in group]))
        levels, above = zip(*(_level_at(d, frequency) for d in ws.detections), strict=True)
        mean = float(np.mean(levels))
        if best is None or mean > best[0]:
            best = (mean, frequency, group, levels, above)
    _mean, frequency, group, levels, above = best
    named = Counter((ln.name or UNEXPLAINED, ln.kind) for _f, _i, ln in group)
    (name, kind), _count = named.most_common(1)[0]
    return StrongestLine(frequency, name, kind, len({i for _f, i, _ln in group}),
                         len(ws.detections), Scatter.of(levels), Scatter.of(above))


def _level_at(detection: LineDetection, frequency: float) -> tuple[float, float]:
    """(PSD level [dB re 1 unit²/Hz], level above the floor [dB]) of the highest bin within
    one bin of ``frequency``.  A bin without power counts at the smallest positive float,
    so that it ranks every candidate alike; no floor there gives nan above it."""
    spec = detection.spectrum
    near = np.nonzero(np.abs(spec.frequency - frequency) <= spec.resolution * (1 + 1e-9))[0]
    k = int(near[np.argmax(spec.psd[near])])
    psd = max(float(spec.psd[k]), np.finfo(float).tiny)
    floor = float(detection.floor[k])
    above = 10.0 * math.log10(psd / floor) if floor > 0 and math.isfinite(floor) else math.nan
    return 10.0 * math.log10(psd), above


def window_layout(points: int, h: float, transient: float = 0.0,
                  window: float | None = None, record: float | None = None
                  ) -> tuple[int, int, int]:
    """``(first, width, count)`` of the windows of a record of ``points`` samples at the step
    ``h`` [s] (``record`` [s] long, default ``(points - 1) h``): the sample after the first
    ``transient`` seconds, the samples per window of ``window`` seconds (None: all that
    follow) and the number of whole windows; ValueError naming the value and what is allowed
    when the transient or a window does not fit the record."""
    record = (points - 1) * h if record is None else record
    if not (math.isfinite(transient) and 0.0 <= transient < record):
        raise ValueError(f"transient = {transient!r} s; allowed: "
                         f"0 <= transient < the record's {record:g} s")
    first = round(transient / h)
    available = points - 1 - first
    if window is None:
        width = available
        if width < 1:
            raise ValueError(
                f"transient = {transient!r} s leaves no step of the "
                f"{record:g} s record (at a {h:g} s step); allowed: a transient that leaves "
                "one step or more")
    else:
        if not (math.isfinite(window) and window > 0):
            raise ValueError(f"window = {window!r} s; allowed: > 0")
        width = round(window / h)
        if width < 2 or width > available:
            raise ValueError(
                f"a window of {window!r} s ({width} samples) does not "
                f"fit the {available * h:g} s after a transient of {transient:g} s of the "
                f"{record:g} s record (at a {h:g} s step); allowed: 2 samples up to that")
    return first, width, available // width


def windowed_statistics(time, signals: dict, onset_times, onset_speeds, onset_flanks,
                        normal_mass: float, transient: float = 0.0,
                        window: float | None = None, *, lines: LineSearch | None = None,
                        catalogue: LineCatalogue | None = None,
                        segment_seconds: float = 0.25, extent: ExtentSearch | None = None,
                        subharmonics: SubharmonicSearch | None = None,
                        fundamental: float | None = None) -> WindowedStatistics:
    """Statistics of a recorded run in windows of ``window`` seconds (None: one window over
    everything after the transient) after dropping the first ``transient`` seconds; the
    keyword arguments are those of ``rattle_statistics``.

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
    try:
        first, width, count = window_layout(len(t), h, transient, window, float(t[-1] - t[0]))
    except ValueError as err:
        raise ValueError(f"windowed_statistics: {err}") from None
    onset_t = np.asarray(onset_times, dtype=float)
    onset_v = np.asarray(onset_speeds, dtype=float)
    onset_f = np.asarray(onset_flanks, dtype=int)
    series = {k: np.asarray(v) for k, v in signals.items()}
    starts, slices, results, detections = [], [], [], []
    for i in range(count):
        a, b = first + i * width, first + (i + 1) * width
        span = slice(a, b + 1)
        inside = (onset_t > t[a]) & (onset_t <= t[b])
        stats, detection = _statistics_and_lines(
            t[span], {k: v[span] for k, v in series.items()}, onset_v[inside], onset_f[inside],
            normal_mass, lines=lines, catalogue=catalogue, segment_seconds=segment_seconds,
            extent=extent, subharmonics=subharmonics, fundamental=fundamental)
        results.append(stats)
        if detection is not None:
            detections.append(detection)
        starts.append(float(t[a]))
        slices.append(span)
    end = first + count * width
    return WindowedStatistics(transient=float(t[first] - t[0]), window=float(width * h),
                              starts=starts, slices=slices, windows=results,
                              unused_tail=float(t[-1] - t[end]), detections=detections)


#: Rows of the paper comparison: (quantity as in PAPER_FIGURES, statistic, display scale).
#: The energy rates, the spectral extent, the strongest line and the sub-harmonic flag have
#: rows of their own (``paper_comparison``).
PAPER_ROWS = (
    ("mean wheel speed [rad/s]", "mean_wheel_speed", 1.0),
    ("max deflection [µm]", "max_penetration", 1e6),
    *((f"impact speed at onsets, {flank} flank: {label} [mm/s]", f"impact_speed_{q}_{flank}",
       1e3) for flank, _sign in FLANKS
      for label, q in (("10th percentile", "p10"), ("median", "p50"),
                       ("90th percentile", "p90"), ("RMS", "rms"))),
    ("pairs loaded while in contact [1]", "mean_loaded_pairs", 1.0),
)
#: Keys of PAPER_FIGURES of the rows built apart.
ENERGY_ROW = "impact energy rate, {flank} flank: Σ ½ m_n v² per second [mW]"
EXTENT_ROW = "spectral extent: 1/3-octave PSD 10 dB below its 100–500 Hz mean [Hz]"
SUBHARMONIC_ROW = ("windows with a sub-harmonic of the forcing (power at odd multiples of "
                   "f0/2) [1]")

#: Further statistics: (quantity, statistic, display scale).
FURTHER_ROWS = (
    ("impacts per second, drive flank [1/s]", "impacts_per_second_drive", 1.0),
    ("impacts per second, coast flank [1/s]", "impacts_per_second_coast", 1.0),
    ("mean impact velocity, both flanks [mm/s]", "mean_impact_speed", 1e3),
    ("peak impact velocity [mm/s]", "peak_impact_speed", 1e3),
    ("rattle index: impact energy per second, both flanks [mW]", "impact_energy_rate", 1e3),
    ("RMS normal force [N]", "rms_normal_force", 1.0),
    ("peak normal force [N]", "peak_normal_force", 1.0),
    ("fraction of time in contact [1]", "contact_fraction", 1.0),
    ("most pairs loaded at once [1]", "max_loaded_pairs", 1.0),
    ("detected lines 100–1500 Hz [1]", "lines_detected", 1.0),
    ("of those, unexplained [1]", "lines_unexplained", 1.0),
    ("peaks 100–1500 Hz over the threshold that are resonances, not lines [1]",
     "resonances_detected", 1.0),
    ("sub-harmonic comb over the comb at k·f0 (power above the floor) [dB]",
     "subharmonic_ratio_db", 1.0),
)


def paper_comparison(ws: WindowedStatistics) -> list[tuple[str, str, str]]:
    """Rows ``(quantity, this run: "mean ± scatter (min–max over windows)", paper)``."""
    rows = [(q, ws.text(name, scale), PAPER_FIGURES[q]) for q, name, scale in PAPER_ROWS]
    per_flank = 4  # p10, median, p90, RMS rows of each flank, then its energy rate
    for i, (flank, _sign) in enumerate(FLANKS):
        q = ENERGY_ROW.format(flank=flank)
        rows.insert(2 + (i + 1) * per_flank + i,
                    (q, ws.text(f"impact_energy_rate_{flank}", 1e3), PAPER_FIGURES[q]))
    rows.append((EXTENT_ROW, extent_text(ws), PAPER_FIGURES[EXTENT_ROW]))
    rows += [(q, text, PAPER_FIGURES[q]) for q, text in strongest_line_rows(ws)]
    rows.append((SUBHARMONIC_ROW, subharmonic_text(ws), PAPER_FIGURES[SUBHARMONIC_ROW]))
    return rows


def strongest_line_rows(ws: WindowedStatistics) -> list[tuple[str, str]]:
    """Rows ``(quantity, this run)`` of the strongest line (``strongest_line``): where it is,
    its name and in how many windows it is found; its level; its level above the floor."""
    missing = f"{NO_LINE} in any window" if ws.detections else NO_LINE_SEARCH
    line = strongest_line(ws)
    if line is None:
        return [(STRONGEST_ROW, missing), (STRONGEST_LEVEL_ROW, missing),
                (STRONGEST_ABOVE_FLOOR_ROW, missing)]
    above = line.above_floor_db.text(missing="no noise floor at the line in any window")
    if 0 < line.above_floor_db.n < line.windows:
        above += (f"; in {line.above_floor_db.n} of {line.windows} windows (no noise floor "
                  "at the line in the others)")
    return [(STRONGEST_ROW, line.text()), (STRONGEST_LEVEL_ROW, line.level_db.text()),
            (STRONGEST_ABOVE_FLOOR_ROW, above)]


def further_statistics(ws: WindowedStatistics) -> list[tuple[str, str]]:
    """Rows ``(quantity, this run: "mean ± scatter (min–max over windows)")``."""
    return [(q, ws.text(name, scale)) for q, name, scale in FURTHER_ROWS]


def extent_text(ws: WindowedStatistics) -> str:
    """The spectral extent over the windows: mean ± scatter of the windows where the smoothed
    PSD fell below the level, and in how many it did not up to the band top (there the
    extent is only a lower bound, and no mean is taken)."""
    values = [(w.spectral_extent, w.spectral_extent_censored) for w in ws.windows
              if math.isfinite(w.spectral_extent)]
    if not values:
        return ws.text("spectral_extent")
    n = len(ws.windows)
    found = [f for f, c in values if not c]
    tops = [f for f, c in values if c]
    parts = []
    if found:
        text = Scatter.of(found).text()
        parts.append(text if len(found) == n else f"{text} in {len(found)} of {n} windows")
    if tops:
        parts.append(f"≥ {min(tops):.0f} (the band top, below Nyquist) in {len(tops)} of "
                     f"{n} windows: the PSD stays within 10 dB of its 100–500 Hz level "
                     "up to there")
    if len(values) < n:
        parts.append(f"{ws.missing_text('spectral_extent')} in {n - len(values)} of {n} "
                     "windows")
    return "; ".join(parts)


def subharmonic_text(ws: WindowedStatistics) -> str:
    """The sub-harmonic flag over the windows: in how many it was raised, and f0."""
    flags = [w.subharmonic_flag for w in ws.windows if math.isfinite(w.subharmonic_flag)]
    if not flags:
        return ws.text("subharmonic_flag")
    n = len(ws.windows)
    f0 = Scatter.of([w.subharmonic_fundamental for w in ws.windows])
    text = f"{int(sum(flags))} of {len(flags)} windows"
    if len(flags) < n:
        text += f" with a test ({n} windows)"
    return text + f" (f0 = {f0.mean:.4g} Hz)"


def extent_result_text(extent: SpectralExtent, sample_rate: float) -> str:
    """The spectral extent of one spectrum, in words where it is not a value."""
    if extent.censored:
        return (f"≥ {extent.frequency:.0f} Hz: the 1/3-octave PSD stays within 10 dB of its "
                "100–500 Hz mean up to the band top next to Nyquist "
                f"({sample_rate / 2:g} Hz)")
    return number_text(extent.frequency, "none: no power in the 100–500 Hz reference band",
                       digits=4) + (" Hz" if math.isfinite(extent.frequency) else "")


def subharmonic_result_text(sub: Subharmonic) -> str:
    """The sub-harmonic test of one spectrum: its verdict, statistic and threshold, and the
    sub-harmonic comb's power over the comb's -- each said in words where it has no value."""
    if sub.positions == 0:
        return (f"no test possible (f0 = {number_text(sub.fundamental, 'none', digits=4)} "
                "Hz: no position (k + ½)·f0 with a noise floor in the band)")
    if not sub.half_excess > 0:
        ratio = ("the sub-harmonic comb has no power above the noise floor, so no ratio to "
                 "the comb")
    elif not sub.comb_excess > 0:
        ratio = "the comb at k·f0 has no power above the noise floor, so no ratio to it"
    else:
        ratio = f"sub-harmonic comb over the comb {sub.ratio_db:.1f} dB"
    missing = "not computable"
    return (f"{'flagged' if sub.flag else 'not flagged'} (f0 = {sub.fundamental:.2f} Hz, "
            f"{sub.positions} positions, statistic {number_text(sub.statistic, missing, digits=3)}"
            f" against the threshold {number_text(sub.threshold, missing, digits=3)}; {ratio})")


def markdown_table(rows, headers=("quantity", "this run", "paper")) -> str:
    """A Markdown table; floats printed with 4 significant digits."""
    def fmt(v):
        return number_text(v, "no value") if isinstance(v, float) else str(v)

    lines = ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    lines += ["| " + " | ".join(fmt(v) for v in row) + " |" for row in rows]
    return "\n".join(lines) + "\n"
