"""Statistics of rattle runs: impact rates and speeds, force levels, spectra, and the
comparison with the paper's reported figures.  Needs numpy and scipy (not the FMUs)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import signal

#: The paper's reported figures (Theodossiades et al. 2008, section 3 and Figures 3-5).
PAPER_FIGURES = {
    "mean wheel speed [rad/s]": 44.5,
    "max deflection [um]": 1.0,  # "of the order of 1 um"
    "typical impact velocity [mm/s]": 4.0,  # "of the order of 4 mm/s"
    "dominant impact line [Hz]": 380.0,
    "sub-harmonic line [Hz]": 190.0,
    "sub-harmonic / dominant [1]": 0.5,
    # How far the dominant line stands out of the 100-1500 Hz band; the paper shows a clear
    # line but gives no number.
    "dominant line / band median PSD [1]": math.nan,
}


@dataclass
class Spectrum:
    """One-sided power spectral density (Welch)."""

    frequency: np.ndarray  # Hz
    psd: np.ndarray  # signal unit^2 / Hz


def welch_spectrum(time, values, segment_seconds: float = 0.25) -> Spectrum:
    """Welch PSD of a uniformly sampled signal, mean removed, Hann window, 50 % overlap."""
    t = np.asarray(time, dtype=float)
    x = np.asarray(values, dtype=float)
    fs = 1.0 / float(np.median(np.diff(t)))
    nper = min(len(x), max(16, round(segment_seconds * fs)))
    f, p = signal.welch(x - x.mean(), fs=fs, nperseg=nper, detrend="constant")
    return Spectrum(f, p)


def spectral_peaks(spec: Spectrum, f_min: float, f_max: float, count: int = 5,
                   prominence_decades: float = 0.5) -> list[tuple[float, float]]:
    """The ``count`` strongest peaks ``(frequency [Hz], psd)`` between f_min and f_max,
    strongest first; a peak must stand ``prominence_decades`` above its surroundings on a
    log scale."""
    band = (spec.frequency >= f_min) & (spec.frequency <= f_max) & (spec.psd > 0)
    f, p = spec.frequency[band], spec.psd[band]
    if len(p) < 3:
        return []
    idx, _ = signal.find_peaks(np.log10(p), prominence=prominence_decades)
    order = idx[np.argsort(p[idx])[::-1]][:count]
    return [(float(f[i]), float(p[i])) for i in order]


def nearest_peak(spec: Spectrum, f_target: float, rel_window: float = 0.15):
    """Strongest local maximum within ``rel_window`` of ``f_target``, or None."""
    peaks = spectral_peaks(spec, f_target * (1 - rel_window), f_target * (1 + rel_window),
                           count=1, prominence_decades=0.1)
    return peaks[0] if peaks else None


@dataclass
class RattleStatistics:
    """Summary of a run (SI units unless stated)."""

    duration: float  # s
    mean_wheel_speed: float  # rad/s
    impacts_per_second_drive: float
    impacts_per_second_coast: float
    median_impact_speed: float  # m/s
    mean_impact_speed: float  # m/s
    peak_impact_speed: float  # m/s
    max_penetration: float  # m
    rms_normal_force: float  # N
    peak_normal_force: float  # N
    contact_fraction: float  # fraction of samples with a pair in contact
    impact_energy_rate: float  # W: sum of 1/2 m_n v^2 over onsets per second


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


def rattle_statistics(time, signals: dict, onset_speeds, onset_flanks,
                      normal_mass: float) -> RattleStatistics:
    """Statistics of a recorded run.  ``signals`` holds the unit outputs by name;
    ``normal_mass`` [kg] is the wheel's effective mass on the tooth normal."""
    t = np.asarray(time, dtype=float)
    duration = float(t[-1] - t[0])
    phi = np.asarray(signals["wheel.phi"], dtype=float)
    W = np.asarray(signals["mesh.W"], dtype=float)
    speeds = np.asarray(onset_speeds, dtype=float)
    flanks = np.asarray(onset_flanks, dtype=int)
    return RattleStatistics(
        duration=duration,
        mean_wheel_speed=float((phi[-1] - phi[0]) / duration),
        impacts_per_second_drive=float(np.sum(flanks > 0) / duration),
        impacts_per_second_coast=float(np.sum(flanks < 0) / duration),
        median_impact_speed=float(np.median(speeds)) if len(speeds) else 0.0,
        mean_impact_speed=float(np.mean(speeds)) if len(speeds) else 0.0,
        peak_impact_speed=float(np.max(speeds)) if len(speeds) else 0.0,
        max_penetration=float(np.max(signals["mesh.delta_peak"])),
        rms_normal_force=float(np.sqrt(np.mean(W * W))),
        peak_normal_force=float(np.max(signals["mesh.W_peak"])),
        contact_fraction=float(np.mean(np.asarray(signals["mesh.n_contact"]) > 0)),
        impact_energy_rate=float(0.5 * normal_mass * np.sum(speeds * speeds) / duration),
    )


def paper_comparison(stats: RattleStatistics, spec: Spectrum) -> list[tuple[str, float, float]]:
    """Rows ``(quantity, this run, paper)`` for the figures the paper reports."""
    dominant = spectral_peaks(spec, 100.0, 1500.0, count=1)
    f_dom = dominant[0][0] if dominant else math.nan
    sub = nearest_peak(spec, f_dom / 2) if dominant else None
    f_sub = sub[0] if sub else math.nan
    run = {
        "mean wheel speed [rad/s]": stats.mean_wheel_speed,
        "max deflection [um]": stats.max_penetration * 1e6,
        "typical impact velocity [mm/s]": stats.median_impact_speed * 1e3,
        "dominant impact line [Hz]": f_dom,
        "sub-harmonic line [Hz]": f_sub,
        "sub-harmonic / dominant [1]": f_sub / f_dom if dominant else math.nan,
        "dominant line / band median PSD [1]": band_prominence(spec, dominant),
    }
    return [(k, run[k], PAPER_FIGURES[k]) for k in PAPER_FIGURES]


def band_prominence(spec: Spectrum, peaks, f_min: float = 100.0,
                    f_max: float = 1500.0) -> float:
    """PSD of the first of ``peaks`` over the median PSD between f_min and f_max (nan if no
    peak): about 1-3 for a flat broadband spectrum, much more for a distinct line."""
    if not peaks:
        return math.nan
    band = (spec.frequency >= f_min) & (spec.frequency <= f_max)
    return float(peaks[0][1] / np.median(spec.psd[band]))


def markdown_table(rows, headers=("quantity", "this run", "paper")) -> str:
    """A Markdown table; floats printed with 4 significant digits."""
    def fmt(v):
        return f"{v:.4g}" if isinstance(v, float) else str(v)

    lines = ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    lines += ["| " + " | ".join(fmt(v) for v in row) + " |" for row in rows]
    return "\n".join(lines) + "\n"
