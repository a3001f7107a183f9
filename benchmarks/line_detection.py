"""Error rates of the spectral statistics (drive_rattle_cosim.spectral_lines), measured on
seeded synthetic signals: the figures quoted in docs/analysis.md.

    python benchmarks/line_detection.py [--trials 1000] [--part all|lines|resonances|
                                          subharmonics|extent]

* false alarms: the fraction of noise spectra (white, AR(1) rho = 0.9, random walk) with any
  line in 20-2000 Hz at 1 % family-wise significance, and the per-bin exceedance rate against
  its nominal level;
* detection: the fraction of trials in which a sinusoid in white noise is found (within one
  bin) as a line, against its line SNR, on a bin centre and half-way between bins;
* resonances: the fraction of AR(2) noise spectra (Q 5-40, 300-1900 Hz) with any line, with
  the width and stability tests off, one of them, and both (the default);
* sub-harmonics: the fraction of windows flagged for noise, trains periodic with T and with
  2T (tests/analysis/synthetic.py), and the flag rate against the strength of the 2T change;
* extent: the spectral extent of impulse trains and low-pass noise with the band ending at
  2 kHz, 4.9 kHz and Nyquist.

Every spectrum: 2 s at 10 kHz, 0.25 s Hann segments at 50 % overlap (the paper scenario's
windows).  The synthetic signals come from tests/analysis/synthetic.py.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np
from scipy import signal

from drive_rattle_cosim.analysis import markdown_table
from drive_rattle_cosim.spectral_lines import (
    ExtentSearch,
    LineSearch,
    detect_lines,
    spectral_extent,
    subharmonic_test,
    welch_spectra,
    welch_spectrum,
)

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from tests.analysis import synthetic as syn

FS, T = syn.FS, syn.DURATION
TIME = syn.TIME
WHITE_PSD = 2.0 / FS
CHUNK = 250  # rows generated at once


def noise(kind: str, rng) -> np.ndarray:
    e = rng.standard_normal(TIME.size)
    if kind == "white":
        return e
    if kind == "AR(1), rho 0.9":
        return signal.lfilter([1.0], [1.0, -0.9], e)
    return np.cumsum(e)  # random walk, PSD ~ 1/f^2


def false_alarms(trials: int) -> list[tuple]:
    search = LineSearch()
    per_bin = LineSearch(significance=0.5)
    rows = []
    for kind in ("white", "AR(1), rho 0.9", "random walk (1/f²)"):
        alarms, exceed, expected = 0, 0, 0.0
        for seed in range(trials):
            spec = welch_spectrum(TIME, noise(kind, np.random.default_rng(seed)))
            alarms += bool(detect_lines(spec, search).lines)
            d = detect_lines(spec, per_bin)
            tested = np.isfinite(d.threshold)
            exceed += int(np.sum(spec.psd[tested] > (d.threshold * d.floor)[tested]))
            expected += np.sum(tested) * per_bin.significance / d.bins_searched
        rows.append((kind, trials, f"{alarms} ({alarms / trials:.1%})",
                     f"{exceed} / {expected:.0f} = {exceed / expected:.2f}"))
    return rows


def detection(trials: int) -> list[tuple]:
    searches = (LineSearch(max_width_ratio=None, stability_alpha=None), LineSearch())
    base = welch_spectrum(TIME, TIME)
    bandwidth = base.enbw_bins * base.resolution
    rows = []
    for snr_db in (-3, 0, 2, 3, 4, 5, 6, 7, 8, 10):
        amp = math.sqrt(2 * 10 ** (snr_db / 10) * WHITE_PSD * bandwidth)
        found = []
        for f0 in (600.0, 602.0):  # on a bin centre, half-way between bins (4 Hz bins)
            hits = [0, 0]
            for seed in range(trials):
                rng = np.random.default_rng(100_000 + seed)
                x = rng.standard_normal(TIME.size) + amp * np.sin(
                    2 * np.pi * f0 * TIME + rng.uniform(0, 2 * np.pi))
                spec = welch_spectrum(TIME, x)
                for i, search in enumerate(searches):
                    hits[i] += detect_lines(spec, search).near(f0) is not None
            found += [f"{hits[0] / trials:.1%}", f"{hits[1] / trials:.1%}"]
        total_snr = snr_db + 10 * math.log10(bandwidth / (FS / 2))
        rows.append((snr_db, f"{total_snr:.1f}", *found))
    return rows


def _spectra(make, trials: int, seed: int):
    """Welch spectra of ``trials`` rows of ``make(rows, rng)``, generated in chunks."""
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < trials:
        out += welch_spectra(TIME, make(min(CHUNK, trials - len(out)), rng))
    return out


def resonances(trials: int) -> list[tuple]:
    searches = (LineSearch(max_width_ratio=None, stability_alpha=None),
                LineSearch(stability_alpha=None), LineSearch(max_width_ratio=None),
                LineSearch())
    rows = []
    for q in (5, 10, 20, 40):
        for f_r in (300.0, 700.0, 1300.0, 1900.0):
            specs = _spectra(lambda n, rng, f_r=f_r, q=q: syn.ar2_noise(n, f_r, q, rng),
                             trials, int(q * 10_000 + f_r))
            counts = [sum(bool(detect_lines(s, se).lines) for s in specs) for se in searches]
            rows.append((q, f"{f_r:g}", f"{f_r / q:.1f}",
                         *(f"{c} ({c / trials:.1%})" for c in counts)))
    return rows


def subharmonics(trials: int) -> tuple[list[tuple], list[tuple]]:
    cases = (
        ("white noise, f0 = forcing", lambda n, rng: rng.standard_normal((n, TIME.size)),
         syn.F_FORCING),
        ("white noise, f0 = mesh", lambda n, rng: rng.standard_normal((n, TIME.size)),
         syn.F_MESH),
        ("mesh train, period T", lambda n, rng: syn.impulse_train(n, rng, **syn.MESH_TRAIN),
         syn.F_MESH),
        ("mesh train, period 2T (±20 %)",
         lambda n, rng: syn.impulse_train(n, rng, **syn.MESH_TRAIN_2T), syn.F_MESH),
        ("engine-cycle pattern, period T",
         lambda n, rng: syn.impulse_train(n, rng, **syn.CYCLE_TRAIN), syn.F_FORCING),
        ("engine-cycle pattern, period 2T",
         lambda n, rng: syn.impulse_train(n, rng, **syn.CYCLE_TRAIN_2T), syn.F_FORCING),
    )
    rows = []
    for i, (label, make, f0) in enumerate(cases):
        res = [subharmonic_test(s, f0) for s in _spectra(make, trials, 500 + i)]
        flags = sum(r.flag for r in res)
        ratio = np.nanmedian([r.ratio_db for r in res]) if any(
            math.isfinite(r.ratio_db) for r in res) else math.nan
        rows.append((label, f"{f0:.2f}", trials, f"{flags} ({flags / trials:.1%})",
                     f"{np.median([r.statistic for r in res]):.3f}",
                     f"{np.median([r.threshold for r in res]):.3f}", f"{ratio:.1f}"))
    curve = []
    n = max(50, trials // 2)
    for alt in (0.05, 0.1, 0.15, 0.2, 0.25):
        kw = dict(syn.MESH_TRAIN, amplitudes=(1 + alt,), odd_amplitudes=(1 - alt,))
        res = [subharmonic_test(s, syn.F_MESH)
               for s in _spectra(lambda m, rng, kw=kw: syn.impulse_train(m, rng, **kw), n, 7)]
        curve.append((f"mesh train, amplitudes alternate ±{alt:.0%}",
                      f"{10 * math.log10(alt * alt):.1f}",
                      f"{sum(r.flag for r in res) / n:.1%}"))
    for shift in (0.1e-3, 0.2e-3, 0.3e-3, 0.5e-3):
        kw = syn.cycle_train_2t(shift=shift, weaker=1.0)
        res = [subharmonic_test(s, syn.F_FORCING)
               for s in _spectra(lambda m, rng, kw=kw: syn.impulse_train(m, rng, **kw), n, 8)]
        curve.append((f"engine-cycle pattern, one impact {shift * 1e3:g} ms later", "—",
                      f"{sum(r.flag for r in res) / n:.1%}"))
    return rows, curve


def extent(trials: int) -> list[tuple]:
    cases = (
        ("Hertz-like pulses 0.5–0.9 ms, mesh train",
         lambda n, rng: syn.impulse_train(n, rng, **dict(syn.MESH_TRAIN, noise=0.02,
                                                         pulse=(0.5e-3, 0.9e-3)))),
        ("Hertz-like pulses 0.2–0.4 ms, engine-cycle pattern, white noise",
         lambda n, rng: syn.impulse_train(n, rng, **syn.CYCLE_TRAIN)),
        ("low-pass noise, Butterworth 4th order 1 kHz (−10 dB at 1316 Hz)",
         lambda n, rng: syn.lowpass_noise(n, 1000.0, rng)),
        ("pulses of 0.1 ms (one sample), mesh train",
         lambda n, rng: syn.impulse_train(n, rng, **dict(syn.MESH_TRAIN, noise=0.0,
                                                         pulse=(0.08e-3, 0.12e-3)))),
    )
    rows = []
    n = max(50, trials // 5)
    for i, (label, make) in enumerate(cases):
        specs = _spectra(make, n, 900 + i)
        values = {}
        for top in (2000.0, 4900.0, None):
            res = [spectral_extent(s, ExtentSearch(f_max=top)) for s in specs]
            values[top] = np.array([r.frequency for r in res])
            censored = sum(r.censored for r in res)
            values[top, "c"] = censored
        if values[2000.0, "c"] or values[4900.0, "c"]:
            change = "— (censored: lower bounds)"
        else:
            change = f"{np.max(np.abs(values[4900.0] / values[2000.0] - 1.0)):.1%}"
        rows.append((label, *(f"{np.median(values[top]):.0f} "
                              f"({np.percentile(values[top], 5):.0f}–"
                              f"{np.percentile(values[top], 95):.0f}); censored "
                              f"{values[top, 'c']}/{n}" for top in (2000.0, 4900.0, None)),
                     change))
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=1000, help="noise spectra per kind")
    ap.add_argument("--part", default="all",
                    choices=("all", "lines", "resonances", "subharmonics", "extent"))
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    part = args.part
    if part in ("all", "lines"):
        spec = welch_spectrum(TIME, TIME)
        d = detect_lines(welch_spectrum(TIME, noise("white", np.random.default_rng(0))))
        print(f"Welch: {spec.segments} segments, dof {spec.dof:.2f}, {spec.resolution:g} Hz "
              f"bins, ENBW {spec.enbw_bins:g} bins; {d.bins_searched} bins searched; "
              f"threshold psd/floor {np.nanmin(d.threshold):.3f} (inside the band) .. "
              f"{np.nanmax(d.threshold):.3f} (at its ends)\n")
        print(markdown_table(false_alarms(args.trials), (
            "noise", "spectra", "with a line (1 % family-wise)",
            "per-bin exceedances / nominal (alpha 0.5 / bins)")))
        print(markdown_table(detection(max(50, args.trials // 5)), (
            "line SNR [dB] (over the noise in one ENBW)", "SNR over 0-5 kHz [dB]",
            "found, bin centre, no width/stability test", "found, bin centre (default)",
            "found, half-way, no width/stability test", "found, half-way (default)")))
    if part in ("all", "resonances"):
        trials = min(args.trials, 500)
        print(f"AR(2) resonances, {trials} spectra each: spectra with any line\n")
        print(markdown_table(resonances(trials), (
            "Q", "f_r [Hz]", "bandwidth f_r/Q [Hz]", "no width/stability test",
            "width test only", "stability test only", "both (default)")))
    if part in ("all", "subharmonics"):
        trials = min(args.trials, 500)
        rows, curve = subharmonics(trials)
        print(markdown_table(rows, (
            "signal", "f0 [Hz]", "windows", "flagged", "statistic (median)",
            "threshold (median)", "half comb / comb [dB] (median)")))
        print(markdown_table(curve, ("2T change", "half comb / comb [dB] (low harmonics)",
                                     "flagged")))
    if part in ("all", "extent"):
        print(markdown_table(extent(args.trials), (
            "signal", "band to 2 kHz: median (5–95 %)", "band to 4.9 kHz",
            "band to Nyquist", "largest change 2 → 4.9 kHz")))
    print(f"{time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
