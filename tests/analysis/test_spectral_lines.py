"""The spectral line search and its companions (drive_rattle_cosim.spectral_lines) against
signals with known answers -- each tested where it must find nothing and where it must find
something.

The line search: no line in white or coloured noise (at the stated false-alarm rate), the
right line at the right frequency with the right name above the threshold, none below it.
Its spectra: 2 s at 10 kHz, 0.25 s Hann segments (15 segments, 4 Hz bins), searched in
20-2000 Hz at 1 % family-wise significance -- the paper scenario's windows.  Measured on 1000
seeded trials each (docs/analysis.md): spectra with any line 1.0 % (white), 1.3 % (AR(1),
rho 0.9), 0.8 % (random walk); a tone on a bin centre is found in 50 % of trials at a line SNR
of 2.2 dB (the threshold ratio 2.61 minus 1) and in 100 % at 8 dB.

The statistics that replace the flattering rows of the paper comparison:

* the line detector's width and stability tests: AR(2) noise resonances (Q 5-40, 300-1900 Hz)
  give a line in at most 2 % of 500 spectra, while a tone in noise, also on a resonance hump,
  is still found as a line;
* the sub-harmonic flag: trains periodic with T flagged in at most 2 %, with 2T in at least
  90 % of 500 windows; noise not flagged;
* the spectral extent: the same when the band grows from 2 to 4.9 kHz on an impulse train
  whose spectrum falls off, the -10 dB point of a low-pass noise, a lower bound (censored) on
  a flat spectrum.

Their spectra: 2 s at 10 kHz, 0.25 s Hann segments (the paper scenario's windows); the signals
come from tests/analysis/synthetic.py, seeded.  Measured rates: benchmarks/line_detection.py
and docs/analysis.md.
"""

import math

import numpy as np
import pytest
from scipy import signal, stats

from drive_rattle_cosim.spectral_lines import (
    RESONANCE,
    UNEXPLAINED,
    ExtentSearch,
    LineCatalogue,
    LineSearch,
    Spectrum,
    SubharmonicSearch,
    detect_lines,
    median_of_chi2,
    spectral_extent,
    subharmonic_test,
    tone_widths,
    welch_dof,
    welch_spectra,
    welch_spectrum,
)

from . import synthetic as syn

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


# ---------------------------------------------------------------- resonances, sub-harmonics, extent
SPECTRA = 500
#: At most 2 % of the spectra may show what is not there.
MAX_FALSE = int(0.02 * SPECTRA)
#: The detector before the width and stability tests.
OLD = LineSearch(max_width_ratio=None, stability_alpha=None)


def spectra(make, n: int, seed: int) -> list[Spectrum]:
    """Welch spectra of ``n`` rows of ``make(rows, rng)``, 250 rows at a time."""
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        out += welch_spectra(syn.TIME, make(min(250, n - len(out)), rng))
    return out


# --- the line detector: resonances are not lines ------------------------------------------

#: (Q, f_r [Hz]): every Q once, 300-1900 Hz; Q 40 at 300 Hz is 7.5 Hz wide, under two bins,
#: so only the stability test tells it from a line.
FAST_CELLS = [(5.0, 700.0), (10.0, 1300.0), (20.0, 1900.0), (40.0, 300.0), (40.0, 1300.0)]
SLOW_CELLS = [(q, f) for q in (5.0, 10.0, 20.0, 40.0) for f in (300.0, 700.0, 1300.0, 1900.0)
              if (q, f) not in FAST_CELLS]


def _ar2_rates(q: float, f_r: float):
    specs = spectra(lambda n, rng: syn.ar2_noise(n, f_r, q, rng), SPECTRA, int(q * 1000 + f_r))
    now = [s for s in specs if detect_lines(s).lines]
    before = sum(bool(detect_lines(s, OLD).lines) for s in specs[:100])
    return len(now), before


@pytest.mark.parametrize("q, f_r", FAST_CELLS)
def test_ar2_resonance_gives_no_line(q, f_r):
    """Measured (seeded, 500 spectra, benchmarks/line_detection.py): at most 0.6 % in every
    cell of Q 5-40 x 300-1900 Hz; without the width and stability tests 21-100 % (Q 5 at
    700 Hz: 21 %)."""
    found, before = _ar2_rates(q, f_r)
    assert found <= MAX_FALSE, found
    assert before >= 10, before  # the input is hard: the old detector fails on it


@pytest.mark.slow
@pytest.mark.parametrize("q, f_r", SLOW_CELLS)
def test_ar2_resonance_gives_no_line_everywhere(q, f_r):
    found, _ = _ar2_rates(q, f_r)
    assert found <= MAX_FALSE, found


def test_the_contact_mode_is_reported_as_a_resonance():
    """Q 40 at 1.3 kHz (the contact mode's): a peak there in every spectrum, of kind
    "resonance", wider than a tone."""
    specs = spectra(lambda n, rng: syn.ar2_noise(n, 1300.0, 40.0, rng), 50, 4)
    hits = []
    for s in specs:
        d = detect_lines(s)
        near = [r for r in d.resonances if abs(r.frequency - 1300.0) <= 1300.0 / 40.0]
        hits.append(bool(near) and all(r.kind == RESONANCE for r in near))
        assert d.lines == []
    assert sum(hits) >= 48
    widths = [r.width_ratio for s in specs[:10] for r in detect_lines(s).resonances]
    assert np.median(widths) > 2.0


def test_tone_widths_of_the_window():
    """A noise-free Hann tone: 1.33 bins at -3 dB on a bin centre, 2.04 half-way."""
    offsets, widths = tone_widths("hann", 2500)
    assert offsets[0] == 0.0 and offsets[-1] == 0.5
    assert widths[0] == pytest.approx(4 / 3, abs=0.01)
    assert widths[-1] == pytest.approx(2.04, abs=0.01)
    assert np.all(np.diff(widths) >= 0)


def test_tone_in_noise_is_still_a_line():
    """A line 8 dB over white noise (its power over the noise in one ENBW), between bins:
    found as a line in at least 98 % (measured 100 % of 200 on and between bins)."""
    rng = np.random.default_rng(21)
    amp = math.sqrt(2 * 10 ** 0.8 * 2.0 / syn.FS * 1.5 * 4.0)
    x = rng.standard_normal((200, syn.TIME.size)) + amp * np.sin(
        2 * np.pi * 601.3 * syn.TIME + rng.uniform(0, 2 * np.pi, (200, 1)))
    found = [detect_lines(s).near(601.3) for s in welch_spectra(syn.TIME, x)]
    assert sum(ln is not None for ln in found) >= 196
    assert max(ln.width_ratio for ln in found if ln is not None) < 1.5


def test_tone_on_a_resonance_hump_is_a_line():
    """A line 15 dB over the top of a Q 20 resonance it sits on (1.3 kHz) is still a line:
    narrow, and steady against the hump's own level (measured: 200 of 200; at 10 dB 185 of
    200, the rest reported as resonances)."""
    rng = np.random.default_rng(22)
    x = syn.ar2_noise(200, 1300.0, 20.0, rng)
    top = np.mean([s.psd[325] for s in welch_spectra(syn.TIME, x[:20])])  # 1300 Hz bin
    amp = math.sqrt(2 * 10 ** 1.5 * top * 1.5 * 4.0)
    x += amp * np.sin(2 * np.pi * 1301.3 * syn.TIME + rng.uniform(0, 2 * np.pi, (200, 1)))
    found = sum(detect_lines(s).near(1301.3) is not None for s in welch_spectra(syn.TIME, x))
    assert found >= 196


def test_noise_gives_no_line_and_no_subharmonic():
    """Pure noise: no line, no resonance taken for a line, no sub-harmonic flag."""
    specs = spectra(lambda n, rng: rng.standard_normal((n, syn.TIME.size)), 300, 23)
    assert sum(bool(detect_lines(s).lines) for s in specs) <= 6
    for f0 in (syn.F_FORCING, syn.F_MESH):
        flags = sum(subharmonic_test(s, f0).flag for s in specs)
        assert flags <= 6, (f0, flags)  # measured: 0 and 1.0 % of 500


# --- the sub-harmonic flag -----------------------------------------------------------------

@pytest.mark.parametrize("label, train, train_2t, f0", [
    ("mesh", syn.MESH_TRAIN, syn.MESH_TRAIN_2T, syn.F_MESH),
    ("engine cycle", syn.CYCLE_TRAIN, syn.CYCLE_TRAIN_2T, syn.F_FORCING),
])
@pytest.mark.slow
def test_subharmonic_flag_tells_period_2t_from_t(label, train, train_2t, f0):
    """Measured (500 windows): mesh train 1.4 % vs 97.6 %; engine-cycle pattern 0.2 % vs
    100 %.  The 2T changes are small against the scatter of single impacts (mesh: +-20 %
    alternation under 30 % amplitude scatter and 3 % jitter; engine cycle: one of six impacts
    0.5 ms later and one 25 % weaker)."""
    period_t = [subharmonic_test(s, f0) for s in spectra(
        lambda n, rng: syn.impulse_train(n, rng, **train), SPECTRA, 31)]
    period_2t = [subharmonic_test(s, f0) for s in spectra(
        lambda n, rng: syn.impulse_train(n, rng, **train_2t), SPECTRA, 32)]
    assert sum(r.flag for r in period_t) <= MAX_FALSE
    assert sum(r.flag for r in period_2t) >= 0.9 * SPECTRA
    # The half comb's power against the comb's: far below it for T, about the designed
    # change for 2T (mesh: (0.2)^2 = -14 dB at low harmonics).
    assert np.nanmedian([r.ratio_db for r in period_t]) < -20.0
    assert -18.0 < np.nanmedian([r.ratio_db for r in period_2t]) < -8.0


def test_subharmonic_flag_needs_power_and_size():
    """A sub-harmonic comb far below the comb (amplitudes alternating +-5 %: -26 dB) is not
    flagged even where it is significant, for min_ratio_db = -20 dB; without that bound it
    is."""
    kw = dict(syn.MESH_TRAIN, amplitudes=(1.05,), odd_amplitudes=(0.95,), noise=0.0,
              amplitude_sd=0.0, jitter=0.0)
    specs = spectra(lambda n, rng: syn.impulse_train(n, rng, **kw), 20, 33)
    res = [subharmonic_test(s, syn.F_MESH) for s in specs]
    assert all(r.statistic > r.threshold for r in res)
    assert not any(r.flag for r in res)
    assert np.median([r.ratio_db for r in res]) == pytest.approx(-26.0, abs=1.5)
    loose = SubharmonicSearch(min_ratio_db=-40.0)
    assert all(subharmonic_test(s, syn.F_MESH, loose).flag for s in specs)


def test_forcing_fundamental():
    assert LineCatalogue(830 / 60, 20, (2.0, 4.0, 6.0)).fundamental == pytest.approx(830 / 30)
    assert LineCatalogue(50.0, 17, (1.5, 3.0)).fundamental == pytest.approx(25.0)
    assert LineCatalogue(50.0, 29, (2.0,)).fundamental == pytest.approx(50.0)


# --- the spectral extent -------------------------------------------------------------------

BAND_2K, BAND_4K9 = ExtentSearch(f_max=2000.0), ExtentSearch(f_max=4900.0)


def test_extent_of_an_impulse_train_does_not_move_with_the_band():
    """Hertz-like pulses of 0.5-0.9 ms at the mesh rate: the extent (about 1.76 kHz) moves
    less than 5 % in every window when the band grows from 2 to 4.9 kHz (measured: 3.6 % at
    most over 100 windows, 0 in the median); not censored."""
    kw = dict(syn.MESH_TRAIN, noise=0.02, pulse=(0.5e-3, 0.9e-3))
    for s in spectra(lambda n, rng: syn.impulse_train(n, rng, **kw), 50, 41):
        narrow, wide = spectral_extent(s, BAND_2K), spectral_extent(s, BAND_4K9)
        assert not (narrow.censored or wide.censored)
        assert abs(wide.frequency / narrow.frequency - 1.0) < 0.05
        assert 1500.0 < wide.frequency < 1950.0


def test_extent_of_lowpass_noise_is_its_ten_db_point():
    """White noise through a 4th-order Butterworth at 1 kHz falls 10 dB below its pass band
    at 1316 Hz: the extent is there (1/3-octave smoothing: 1 % low), whatever the band."""
    expect = syn.lowpass_ten_db(1000.0)
    for s in spectra(lambda n, rng: syn.lowpass_noise(n, 1000.0, rng), 30, 42):
        for search in (BAND_2K, BAND_4K9, ExtentSearch()):
            e = spectral_extent(s, search)
            assert not e.censored
            assert e.frequency == pytest.approx(expect, rel=0.03)


def test_extent_of_a_flat_spectrum_is_only_a_lower_bound():
    """Pulses shorter than the sample step make a flat comb up to Nyquist (the paper
    scenario's force): the extent is the band top, flagged as censored, for every band --
    never a value that moves with the band unannounced."""
    kw = dict(syn.MESH_TRAIN, noise=0.0, pulse=(0.08e-3, 0.12e-3))
    for s in spectra(lambda n, rng: syn.impulse_train(n, rng, **kw), 10, 43):
        for search, top in ((BAND_2K, 2000.0), (BAND_4K9, 4900.0), (ExtentSearch(), 4996.0)):
            e = spectral_extent(s, search)
            assert e.censored and e.frequency == e.band_top == pytest.approx(top)


def test_extent_of_a_step_is_exact():
    """A noise-free PSD of 1 up to 1 kHz and 0.01 above: the 1/3-octave average falls to 0.1
    where 9.1 % of its band lies below 1 kHz; the reference band and the drop are applied
    as stated."""
    f = np.arange(0.0, 5000.1, 4.0)
    spec = Spectrum(f, np.where(f <= 1000.0, 1.0, 0.01), 30.0, 15, 2500, 1e4)
    e = spectral_extent(spec)
    h = 2 ** (1 / 6)
    fb = f[(f >= 100.0) & (f <= f[-2])]
    inside = [np.mean(np.where(fb[(fb >= x / h) & (fb <= x * h)] <= 1000.0, 1.0, 0.01))
              for x in (e.frequency - 4.0, e.frequency + 4.0)]
    assert inside[0] >= 0.1 >= inside[1]
    assert 1000.0 < e.frequency < 1000.0 * h and not e.censored
    assert e.reference_level == 1.0
    flat = Spectrum(f, np.ones_like(f), 30.0, 15, 2500, 1e4)
    assert spectral_extent(flat).censored
    with pytest.raises(ValueError, match="f_max"):
        ExtentSearch(f_max=400.0)
