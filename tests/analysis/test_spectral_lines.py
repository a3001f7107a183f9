"""The line search against synthetic signals with known answers: no line in white or coloured
noise (at the stated false-alarm rate), the right line at the right frequency with the right
name above the threshold, none below it.

All spectra: 2 s at 10 kHz, 0.25 s Hann segments (15 segments, 4 Hz bins), searched in
20-2000 Hz at 1 % family-wise significance -- the paper scenario's windows.  Measured on 1000
seeded trials each (docs/analysis.md): spectra with any line 1.0 % (white), 1.3 % (AR(1),
rho 0.9), 0.8 % (random walk); a tone on a bin centre is found in 50 % of trials at a line SNR
of 2.2 dB (the threshold ratio 2.61 minus 1) and in 100 % at 8 dB.
"""

import math

import numpy as np
import pytest
from scipy import signal, stats

from drive_rattle_cosim.spectral_lines import (
    UNEXPLAINED,
    LineCatalogue,
    LineSearch,
    Spectrum,
    detect_lines,
    median_of_chi2,
    welch_dof,
    welch_spectrum,
)

FS, T = 10_000.0, 2.0
TIME = np.arange(int(FS * T)) / FS
SEARCH = LineSearch(f_min=20.0, f_max=2000.0, significance=0.01)
#: The paper scenario: 830 rpm, z_p = 20, engine orders 2, 4, 6.
CATALOGUE = LineCatalogue(shaft_frequency=830.0 / 60.0, z_pinion=20, orders=(2.0, 4.0, 6.0))
TRIALS = 50
#: A correct detector at 1 % family-wise significance shows a line in 0.5 of 50 noise spectra
#: on average; 3 or more happen with probability 1.4 % (Poisson), so at most 2 are allowed.
MAX_FALSE_ALARMS = 2


def noise(kind: str, seed: int) -> np.ndarray:
    e = np.random.default_rng(seed).standard_normal(TIME.size)
    if kind == "white":
        return e
    if kind == "ar1":  # x_k = 0.9 x_{k-1} + e_k: PSD falls 25 dB from DC to Nyquist
        return signal.lfilter([1.0], [1.0, -0.9], e)
    if kind == "random walk":  # PSD ~ 1/f^2
        return np.cumsum(e)
    raise ValueError(kind)


def tone_amplitude(snr_db: float, spec: Spectrum, noise_psd: float) -> float:
    """Amplitude of a sinusoid whose power is ``snr_db`` over the noise power in one
    equivalent noise bandwidth of the estimate: its expected psd/floor on a bin centre is
    1 + 10^(snr/10)."""
    power = 10 ** (snr_db / 10) * noise_psd * spec.enbw_bins * spec.resolution
    return math.sqrt(2.0 * power)


WHITE_PSD = 2.0 / FS  # one-sided PSD of unit-variance white noise [1/Hz]


def test_welch_degrees_of_freedom_are_percival_walden():
    for n_samples in (2500, 5000, 20000, 40000):
        t = np.arange(n_samples) / FS
        spec = welch_spectrum(t, np.sin(t))
        K = spec.segments
        assert spec.segments == 2 * n_samples // 2500 - 1
        # Hann at 50 % overlap: nu = 36 K^2 / (19 K - 1) (Percival & Walden 1993, p. 292)
        assert spec.dof == pytest.approx(36 * K * K / (19 * K - 1), rel=1e-12)
    # Without overlap the segments are independent: 2 per segment.
    assert welch_dof(signal.get_window("hann", 100), 100, 7) == 14.0
    # Hann: the DFT of white noise correlates 2/3 with the next bin, 1/6 with the one after;
    # the power 4/9 and 1/36.  ENBW 1.5 bins.
    assert spec.bin_correlation == pytest.approx(1 + 2 * (4 / 9 + 1 / 36), rel=1e-12)
    assert spec.enbw_bins == pytest.approx(1.5, rel=1e-12)


@pytest.mark.parametrize("kind", ["white", "ar1", "random walk"])
def test_noise_shows_no_line(kind):
    alarms = [seed for seed in range(TRIALS)
              if detect_lines(welch_spectrum(TIME, noise(kind, seed)), SEARCH).lines]
    assert len(alarms) <= MAX_FALSE_ALARMS, alarms


def test_per_bin_false_alarm_rate_is_the_nominal_one():
    """Bin by bin, psd/floor exceeds the threshold as often as its level says: this holds
    only with the right degrees of freedom for the estimate *and* for its floor (ignoring the
    floor's scatter gives 1.7 times the rate)."""
    search = LineSearch(f_min=20.0, f_max=2000.0, significance=0.99)
    exceed, expected = 0, 0.0
    for seed in range(200):
        d = detect_lines(welch_spectrum(TIME, noise("white", 1000 + seed)), search)
        tested = np.isfinite(d.threshold)
        exceed += int(np.sum(d.spectrum.psd[tested] > (d.threshold * d.floor)[tested]))
        expected += np.sum(tested) * search.significance / d.bins_searched
    # Bins are correlated (Hann, 1.94 bins per independent one): std ~ sqrt(1.94 expected).
    assert abs(exceed - expected) < 3 * math.sqrt(1.94 * expected), (exceed, expected)


def test_floor_of_noise_is_unbiased():
    floors = [np.nanmedian(detect_lines(welch_spectrum(TIME, noise("white", s)), SEARCH).floor
                           / WHITE_PSD) for s in range(20)]
    assert np.mean(floors) == pytest.approx(1.0, abs=0.02)


def test_line_above_the_threshold_is_found_named_and_placed():
    f_mesh = CATALOGUE.mesh_frequency  # 276.67 Hz: between bins
    found, others, errors = 0, 0, []
    for seed in range(TRIALS):
        rng = np.random.default_rng(5000 + seed)
        base = welch_spectrum(TIME, np.zeros(TIME.size) + TIME)
        amp = tone_amplitude(8.0, base, WHITE_PSD)
        x = rng.standard_normal(TIME.size) + amp * np.sin(
            2 * np.pi * f_mesh * TIME + rng.uniform(0, 2 * np.pi))
        d = detect_lines(welch_spectrum(TIME, x), SEARCH, CATALOGUE)
        line = d.near(f_mesh)
        if line is not None:
            found += 1
            errors.append(line.frequency - f_mesh)
            assert (line.name, line.kind) == ("mesh", "mesh")
        others += len(d.lines) - (line is not None)
    # Measured: found in 100 % of 400 trials at 8 dB, on or between bins.
    assert found >= TRIALS - 1
    assert others <= MAX_FALSE_ALARMS
    # The parabola through the log PSD puts the line well inside a bin (4 Hz).
    assert np.max(np.abs(errors)) < 0.25 * d.resolution


def test_line_below_the_threshold_is_not_found():
    f0 = 600.0  # on a bin centre: the most favourable place for the detector
    base = welch_spectrum(TIME, np.zeros(TIME.size) + TIME)
    amp = tone_amplitude(-3.0, base, WHITE_PSD)  # expected psd/floor 1.5, threshold 2.61
    found = 0
    for seed in range(TRIALS):
        rng = np.random.default_rng(7000 + seed)
        x = rng.standard_normal(TIME.size) + amp * np.sin(2 * np.pi * f0 * TIME)
        found += detect_lines(welch_spectrum(TIME, x), SEARCH).near(f0) is not None
    # Measured: 0.5 % of 200 trials.
    assert found <= MAX_FALSE_ALARMS


def test_decision_is_the_threshold():
    """A spectrum without noise: a bin just over threshold x floor is a line, just under is
    not; and the floor of a flat PSD is the PSD over the median of chi2_nu / nu."""
    spec = welch_spectrum(TIME, noise("white", 0))
    flat = Spectrum(spec.frequency, np.ones_like(spec.psd), spec.dof, spec.segments,
                    spec.segment_length, spec.sample_rate, spec.bin_correlation, spec.enbw_bins)
    d = detect_lines(flat, SEARCH)
    assert d.lines == []
    k = int(np.searchsorted(spec.frequency, 800.0))
    assert d.floor[k] == pytest.approx(1.0 / median_of_chi2(spec.dof), rel=1e-12)
    # Bonferroni: the threshold is an F quantile at alpha / bins, above the chi-squared one
    # (floor known exactly) and below that of a floor from 8 bins.
    alpha = SEARCH.significance / d.bins_searched
    assert stats.chi2.isf(alpha, spec.dof) / spec.dof < d.threshold[k] < stats.f.isf(
        alpha, spec.dof, 8)
    for factor, expect in ((0.999, False), (1.001, True)):
        psd = flat.psd.copy()
        psd[k] = factor * d.threshold[k] * d.floor[k]
        probe = Spectrum(flat.frequency, psd, spec.dof, spec.segments, spec.segment_length,
                         spec.sample_rate, spec.bin_correlation, spec.enbw_bins)
        lines = detect_lines(probe, SEARCH).lines
        assert (len(lines) == 1 and lines[0].frequency == pytest.approx(spec.frequency[k],
                                                                         abs=0.5)) is expect


def test_comb_in_coloured_noise_is_found_and_named():
    """Engine orders, the mesh, a sideband, the second mesh harmonic and a line no
    excitation explains, each 10 dB over the local floor of AR(1) noise."""
    fe = CATALOGUE.shaft_frequency
    comb = {2 * fe: ("E2", "engine order"), 4 * fe: ("E4", "engine order"),
            12 * fe: ("E12", "engine order"), 20 * fe: ("mesh", "mesh"),
            18 * fe: ("mesh−E2", "sideband"), 26 * fe: ("mesh+E6", "sideband"),
            40 * fe: ("2×mesh", "mesh"), 731.0: ("", UNEXPLAINED)}
    rho = 0.9
    for seed in range(10):
        rng = np.random.default_rng(9000 + seed)
        x = noise("ar1", 9000 + seed)
        base = welch_spectrum(TIME, np.zeros(TIME.size) + TIME)
        for f0 in comb:
            # the AR(1) PSD at f0: white PSD / |1 - rho e^(-i w)|^2
            local = WHITE_PSD / abs(1 - rho * np.exp(-2j * np.pi * f0 / FS)) ** 2
            x = x + tone_amplitude(10.0, base, local) * np.sin(
                2 * np.pi * f0 * TIME + rng.uniform(0, 2 * np.pi))
        d = detect_lines(welch_spectrum(TIME, x), SEARCH, CATALOGUE)
        got = {(ln.name, ln.kind) for ln in d.lines}
        assert got >= set(comb.values()), (seed, sorted(got))
        assert len(d.lines) <= len(comb) + MAX_FALSE_ALARMS
        for f0, (name, _) in comb.items():
            assert d.near(f0).name == name


def test_catalogue_names():
    fe = CATALOGUE.shaft_frequency
    tol = 4.0
    assert CATALOGUE.mesh_frequency == pytest.approx(20 * 830 / 60)
    assert CATALOGUE.name(20 * fe + 1.0, tol) == ("mesh", "mesh")
    assert CATALOGUE.name(60 * fe, tol) == ("3×mesh", "mesh")
    assert CATALOGUE.name(16 * fe, tol) == ("mesh−E4", "sideband")
    assert CATALOGUE.name(46 * fe, tol) == ("2×mesh+E6", "sideband")
    assert CATALOGUE.name(10 * fe, tol) == ("E10", "engine order")  # 5th harmonic of E2
    assert CATALOGUE.name(7 * fe, tol) == ("", UNEXPLAINED)  # no odd order is excited
    assert CATALOGUE.name(20 * fe + 4.5, tol) == ("", UNEXPLAINED)  # beyond the resolution
    three_cyl = LineCatalogue(50.0, 17, (1.5, 3.0))
    assert three_cyl.name(75.0, 1.0) == ("E1.5", "engine order")
    assert three_cyl.name(17 * 50.0 - 75.0, 1.0) == ("mesh−E1.5", "sideband")


@pytest.mark.parametrize("kwargs, word", [
    ({"f_min": 100.0, "f_max": 50.0}, "band"),
    ({"significance": 1.5}, "significance"),
    ({"floor_half_width": 3}, "floor_half_width"),
])
def test_bad_settings_are_refused(kwargs, word):
    with pytest.raises(ValueError, match=word):
        LineSearch(**kwargs)


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="equal length"):
        welch_spectrum(TIME, TIME[:-1])
    with pytest.raises(ValueError, match="segment_seconds"):
        welch_spectrum(TIME, TIME, segment_seconds=0.0)
    with pytest.raises(ValueError, match="degrees of freedom"):
        detect_lines(Spectrum(np.arange(10.0), np.ones(10)))
    with pytest.raises(ValueError, match="z_pinion"):
        LineCatalogue(10.0, 0, (2.0,))
