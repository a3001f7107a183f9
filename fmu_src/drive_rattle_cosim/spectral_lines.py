"""Spectral lines found against the spectrum's own noise floor, at a stated significance, told
apart from noise resonances and named after the gear mesh and the engine orders; the spectral
extent of a spectrum and a test for sub-harmonics.  Needs numpy and scipy (not the FMUs).

The method (docs/analysis.md gives the reasoning and the measured error rates):

1. **Welch estimate** (Hann window, 50 % overlap, mean removed per segment).  Its equivalent
   degrees of freedom are computed from the window actually used (Welch 1967; Percival &
   Walden 1993, eq. 292b): ``nu = 2K / (1 + 2 sum_{m=1}^{K-1} (1 - m/K) rho_m^2)`` with
   ``rho_m`` the overlap correlation of the window with itself shifted by m segments; for Hann
   at 50 % this is ``36 K^2 / (19 K - 1)``.  Where there is no line, ``psd / S ~ chi2_nu / nu``.
2. **Noise floor** of each bin: the median of its neighbours within ``floor_half_width`` bins,
   leaving out the bin and ``floor_gap`` bins each side (a line's Hann main lobe), divided by
   the median of ``chi2_nu / nu`` (the median of a chi-squared is below its mean).  Bins of
   lines already found are left out and the floor recomputed until the set of lines is stable,
   so that a dense comb of lines does not lift its own floor.
3. **Test**: a bin holds a line when ``psd / floor`` exceeds the ``1 - alpha/N`` quantile of
   ``F(nu, nu_floor)`` -- the ratio of the bin's chi-squared to the floor's, whose own scatter
   is that of a sample median of the neighbours (``nu_floor`` below) -- with ``N`` the bins
   searched (Bonferroni: the family-wise false-alarm probability per spectrum is at most
   ``alpha``).  A line is a local maximum over the threshold; a second maximum on the skirt of
   a stronger line must also stand the threshold above the valley between them.
4. **Line or resonance**: a peak over the threshold whose -3 dB width exceeds
   ``max_width_ratio`` times the width the window gives a tone at the same offset from the bin
   centre, or whose power fluctuates between the Welch segments more than a line's could (at
   ``stability_alpha``) and as much as narrow-band noise's, is a resonance, not a line.
5. **Names**: a line within one bin spacing of the mesh frequency ``z_p n/60`` or its
   harmonics, of a mesh +- engine-order sideband, or of an engine order ``k n/60`` or its
   harmonics gets that name (in this priority); any other line is reported as unexplained.

``spectral_extent``: where the 1/3-octave-smoothed PSD falls 10 dB below its mean in
100-500 Hz, searched up to Nyquist, censored when it never does.  ``subharmonic_test``: power
at the odd multiples of half a fundamental against the noise floor and against the comb at its
multiples.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from fractions import Fraction
from functools import lru_cache

import numpy as np
from scipy import signal, stats

#: Window of the Welch estimate.  Its sidelobes fall at 18 dB/octave, so a strong line does not
#: leak into the floor far from itself.
WINDOW = "hann"
#: Kinds of named lines, in the order a name is chosen when several fit.
KINDS = ("mesh", "sideband", "engine order")
UNEXPLAINED = "unexplained"
#: Kind of a peak over the threshold that is not a line: wider than the window makes a tone,
#: or fluctuating from segment to segment like narrow-band noise.
RESONANCE = "resonance"
#: Fewest kept neighbours on each side of a bin for it to have a floor.
MIN_SIDE = 4


@dataclass
class Spectrum:
    """One-sided power spectral density (Welch) and what its statistics need."""

    frequency: np.ndarray  # Hz
    psd: np.ndarray  # signal unit^2 / Hz
    dof: float = math.nan  # equivalent degrees of freedom of each bin (chi-squared)
    segments: int = 0  # Welch segments averaged
    segment_length: int = 0  # samples per segment
    sample_rate: float = math.nan  # Hz
    #: 1 + 2 sum_l r_l^2 with r_l the correlation of the DFT of white noise l bins apart under
    #: the window: the number of bins that count as one independent bin in a sample median.
    bin_correlation: float = 1.0
    #: Equivalent noise bandwidth of the window in bins (1.5 for Hann).
    enbw_bins: float = 1.0
    #: The periodogram of each Welch segment (segments x bins; ``psd`` is their mean), for the
    #: stability test of a peak; None when not kept (the test is then skipped).
    segment_psd: np.ndarray | None = None
    segment_step: int = 0  # samples between the starts of consecutive segments

    @property
    def resolution(self) -> float:
        """Bin spacing [Hz]: lines closer than this are not told apart."""
        return float(self.frequency[1] - self.frequency[0])


def welch_dof(window: np.ndarray, step: int, segments: int) -> float:
    """Equivalent degrees of freedom of a Welch average of ``segments`` segments shifted by
    ``step`` samples under ``window`` (Percival & Walden 1993, eq. 292b)."""
    w = np.asarray(window, dtype=float)
    n, energy = len(w), float(np.sum(w * w))
    total = 0.0
    for m in range(1, segments):
        shift = m * step
        if shift >= n:
            break
        rho = float(np.sum(w[: n - shift] * w[shift:])) / energy
        total += (1.0 - m / segments) * rho * rho
    return 2.0 * segments / (1.0 + 2.0 * total)


#: Fewest samples of a signal whose Welch spectrum is taken (one segment of 16).
MIN_SAMPLES = 16


def welch_spectrum(time, values, segment_seconds: float = 0.25) -> Spectrum:
    """Welch PSD of a uniformly sampled signal: Hann window, 50 % overlap, the mean removed
    per segment, with its equivalent degrees of freedom and the periodogram of each
    segment."""
    x = np.asarray(values, dtype=float)
    if np.shape(time) != x.shape or x.ndim != 1:
        raise ValueError(f"welch_spectrum: time and values must be 1-D of equal length >= 16; "
                         f"got shapes {np.shape(time)} and {x.shape}")
    return welch_spectra(time, x[None, :], segment_seconds)[0]


def welch_spectra(time, rows, segment_seconds: float = 0.25) -> list[Spectrum]:
    """``welch_spectrum`` of each row of ``rows`` (signals sampled at the same ``time``
    points), computed in one batch."""
    t = np.asarray(time, dtype=float)
    x = np.asarray(rows, dtype=float)
    if x.ndim != 2 or t.ndim != 1 or t.shape[0] != x.shape[1] or len(t) < MIN_SAMPLES:
        raise ValueError(f"welch_spectrum: time and values must be 1-D of equal length >= 16; "
                         f"got shapes {t.shape} and {x.shape[1:]}")
    if not segment_seconds > 0:
        raise ValueError(f"welch_spectrum: segment_seconds = {segment_seconds!r}; allowed: > 0")
    fs = 1.0 / float(np.median(np.diff(t)))
    nper = min(t.size, max(MIN_SAMPLES, round(segment_seconds * fs)))
    step = nper - nper // 2
    segments = 1 + (t.size - nper) // step
    window = signal.get_window(WINDOW, nper)
    # The periodogram of every segment (density scaling, as scipy.signal.welch, whose
    # estimate is their mean).
    f, _t, seg = signal.spectrogram(x, fs=fs, window=window, nperseg=nper,
                                    noverlap=nper // 2, detrend="constant",
                                    scaling="density", mode="psd")
    seg = np.moveaxis(seg, -1, 1)  # rows x segments x bins
    w2 = window * window
    coeff = np.abs(np.fft.rfft(w2))[:8] / np.sum(w2)  # |sum w^2 e^(-2 pi i l n / N)| / sum w^2
    common = dict(dof=welch_dof(window, step, segments), segments=segments,
                  segment_length=nper, sample_rate=fs,
                  bin_correlation=float(1.0 + 2.0 * np.sum(coeff[1:] ** 2)),
                  enbw_bins=float(nper * np.sum(w2) / np.sum(window) ** 2), segment_step=step)
    return [Spectrum(frequency=f, psd=np.mean(sp, axis=0), segment_psd=sp, **common)
            for sp in seg]


@dataclass(frozen=True)
class LineSearch:
    """Settings of the line search."""

    f_min: float = 20.0  # Hz, searched band
    f_max: float = 2000.0  # Hz
    #: Family-wise false-alarm probability: the chance that a spectrum without any line
    #: shows one or more anywhere in the band.
    significance: float = 0.01
    floor_half_width: int = 24  # bins each side of a bin that set its floor
    floor_gap: int = 2  # bins each side of a bin left out of its own floor (Hann main lobe)
    max_rounds: int = 6  # floor recomputations without the lines found
    #: Width test: a peak whose -3 dB width (where the PSD falls to half the peak bin's,
    #: interpolated between bins) exceeds this multiple of the -3 dB width the window gives a
    #: pure tone at the same offset from the bin centre is a resonance, not a line.
    #: None: no width test.
    max_width_ratio: float | None = 1.5
    #: Stability test: the probability that it calls a true line (a sinusoid in Gaussian
    #: noise) a resonance.  A peak whose power fluctuates between the Welch segments more
    #: than a line of its level does at this probability, and as much as narrow-band noise,
    #: is a resonance.  None: no stability test.
    stability_alpha: float | None = 0.001

    def __post_init__(self):
        if not (0 <= self.f_min < self.f_max and math.isfinite(self.f_max)):
            raise ValueError(f"LineSearch: band {self.f_min!r}..{self.f_max!r} Hz is invalid; "
                             "allowed: 0 <= f_min < f_max, finite")
        if not 0 < self.significance < 1:
            raise ValueError(f"LineSearch: significance = {self.significance!r}; allowed: "
                             "0 < significance < 1")
        if not (self.floor_gap >= 0 and self.floor_half_width >= self.floor_gap + 4):
            raise ValueError(f"LineSearch: floor_half_width = {self.floor_half_width!r}, "
                             f"floor_gap = {self.floor_gap!r}; allowed: floor_gap >= 0 and "
                             "floor_half_width >= floor_gap + 4")
        if self.max_width_ratio is not None and not self.max_width_ratio >= 1.0:
            raise ValueError(f"LineSearch: max_width_ratio = {self.max_width_ratio!r}; "
                             "allowed: >= 1 or None")
        if self.stability_alpha is not None and not 0 < self.stability_alpha < 0.5:
            raise ValueError(f"LineSearch: stability_alpha = {self.stability_alpha!r}; "
                             "allowed: 0 < stability_alpha < 0.5 or None")


@dataclass(frozen=True)
class LineCatalogue:
    """The lines a gear mesh driven by engine orders is expected to show.

    ``shaft_frequency`` is the pinion (input-shaft) rotation frequency n/60 [Hz]; engine order
    k sits at k n/60, the mesh at z_p n/60."""

    shaft_frequency: float  # Hz
    z_pinion: int
    orders: tuple[float, ...]  # excitation orders, e.g. (2, 4, 6)

    def __post_init__(self):
        if not (self.shaft_frequency > 0 and self.z_pinion >= 1):
            raise ValueError(f"LineCatalogue: shaft_frequency = {self.shaft_frequency!r} Hz, "
                             f"z_pinion = {self.z_pinion!r}; allowed: > 0 and >= 1")
        if any(not (k > 0 and math.isfinite(k)) for k in self.orders):
            raise ValueError(f"LineCatalogue: orders = {self.orders!r}; allowed: positive")

    @property
    def mesh_frequency(self) -> float:
        return self.z_pinion * self.shaft_frequency

    @property
    def fundamental(self) -> float:
        """Frequency of the forcing's period [Hz]: the largest frequency of which the mesh and
        every excited order are whole multiples (the greatest common divisor of z_p and the
        orders, times n/60).  A response periodic with the forcing has lines only at its
        multiples; z_p = 20 and orders 2, 4, 6 give order 2 (27.7 Hz at 830 rpm)."""
        g = Fraction(self.z_pinion)
        for k in self.orders:
            q = Fraction(k).limit_denominator(64)
            g = Fraction(math.gcd(g.numerator * q.denominator, q.numerator * g.denominator),
                         g.denominator * q.denominator)
        return float(g) * self.shaft_frequency

    def candidates(self, f_max: float) -> list[tuple[float, str, str]]:
        """``(frequency [Hz], name, kind)`` of every expected line up to ``f_max``, in the
        order a name is chosen: mesh harmonics, sidebands, engine orders."""
        fe, fm = self.shaft_frequency, self.mesh_frequency
        out = []
        for j in range(1, int(f_max / fm) + 2):
            mesh = "mesh" if j == 1 else f"{j}×mesh"
            out.append((j * fm, mesh, "mesh"))
        for j in range(1, int(f_max / fm) + 2):
            mesh = "mesh" if j == 1 else f"{j}×mesh"
            for k in self.orders:
                out += [(j * fm - k * fe, f"{mesh}−E{k:g}", "sideband"),
                        (j * fm + k * fe, f"{mesh}+E{k:g}", "sideband")]
        orders = sorted({round(h * k, 9) for k in self.orders
                         for h in range(1, int(f_max / (k * fe)) + 2)})
        out += [(m * fe, f"E{m:g}", "engine order") for m in orders]
        return [c for c in out if 0 < c[0] <= f_max * 1.05]

    def name(self, frequency: float, tolerance: float) -> tuple[str, str]:
        """``(name, kind)`` of the expected line within ``tolerance`` of ``frequency`` (the
        nearest of the first kind that has one), or ``("", "unexplained")``."""
        candidates = self.candidates(frequency + tolerance)
        for kind in KINDS:
            near = [(abs(f - frequency), name) for f, name, k in candidates if k == kind
                    and abs(f - frequency) <= tolerance]
            if near:
                return min(near)[1], kind
        return "", UNEXPLAINED


@dataclass
class SpectralLine:
    """One detected line."""

    frequency: float  # Hz, peak bin refined by a parabola through the log PSD
    psd: float  # at the peak bin
    floor: float  # noise floor at the peak bin
    threshold: float  # the ratio psd/floor a line must exceed at that bin
    name: str = ""  # "" when unexplained
    kind: str = UNEXPLAINED
    #: -3 dB width of the peak over the width the window gives a tone at the same offset
    #: from the bin centre (1 for a noise-free tone; nan when not measured).
    width_ratio: float = math.nan
    #: Variance over mean^2 of the peak bin's power across the Welch segments (about
    #: (2r - 1) / r^2 for a line r times its noise floor; about 1 for narrow-band noise).
    fluctuation: float = math.nan

    @property
    def ratio(self) -> float:
        return self.psd / self.floor

    @property
    def ratio_db(self) -> float:
        return 10.0 * math.log10(self.ratio)


@dataclass
class LineDetection:
    """Result of a line search on one spectrum."""

    spectrum: Spectrum
    search: LineSearch
    floor: np.ndarray  # noise floor per bin [unit^2/Hz]
    threshold: np.ndarray  # ratio psd/floor a line must exceed, per bin (nan: not searched)
    bins_searched: int
    lines: list[SpectralLine] = field(default_factory=list)
    #: Peaks over the threshold that the width or the stability test showed to be resonances
    #: (kind "resonance"): not lines, and left out of every figure that counts lines.
    resonances: list[SpectralLine] = field(default_factory=list)

    @property
    def resolution(self) -> float:
        return self.spectrum.resolution

    def in_band(self, f_min: float, f_max: float) -> list[SpectralLine]:
        return [ln for ln in self.lines if f_min <= ln.frequency <= f_max]

    def strongest(self, f_min: float, f_max: float) -> SpectralLine | None:
        """The line with the highest PSD in ``[f_min, f_max]``, or None."""
        lines = self.in_band(f_min, f_max)
        return max(lines, key=lambda ln: ln.psd) if lines else None

    def near(self, frequency: float, tolerance: float | None = None) -> SpectralLine | None:
        """The strongest line within ``tolerance`` (default: the resolution) of
        ``frequency``, or None."""
        tol = self.resolution if tolerance is None else tolerance
        return self.strongest(frequency - tol, frequency + tol)


@lru_cache(maxsize=64)
def median_of_chi2(dof: float) -> float:
    """Median of chi2_dof / dof: the running median's bias against the mean PSD."""
    return float(stats.chi2.median(dof) / dof)


@lru_cache(maxsize=64)
def _density_at_median(dof: float) -> float:
    """Density of chi2_dof / dof at its median."""
    return float(stats.chi2.pdf(median_of_chi2(dof) * dof, dof) * dof)


def floor_dof(dof: float, neighbours: np.ndarray, bin_correlation: float) -> np.ndarray:
    """Degrees of freedom of a floor taken as the median of ``neighbours`` bins of
    chi2_dof/dof each: a sample median of n independent values has the variance
    1 / (4 n f(m)^2) (f the density at the median m); correlated neighbouring bins count as
    n / bin_correlation independent ones; a chi-squared with the same relative variance has
    2 / relvar degrees of freedom."""
    m = median_of_chi2(dof)
    density = _density_at_median(dof)
    n_independent = np.maximum(np.asarray(neighbours, dtype=float), 1.0) / bin_correlation
    relvar = 1.0 / (4.0 * n_independent * density * density * m * m)
    return 2.0 / relvar


def _side_medians(psd: np.ndarray, excluded: np.ndarray, half: int, gap: int):
    """Per bin: the median of the kept neighbours below it (bins k-half .. k-gap-1) and above
    it (k+gap+1 .. k+half), and how many each holds."""
    x = np.where(excluded, np.nan, psd)
    padded = np.concatenate([np.full(half, np.nan), x, np.full(half, np.nan)])
    windows = np.lib.stride_tricks.sliding_window_view(padded, 2 * half + 1)
    out = []
    for side in (windows[:, : half - gap], windows[:, half + gap + 1:]):
        out += [*_nanmedian_rows(side)]
    return out


def _nanmedian_rows(a: np.ndarray):
    """``(median of the finite values of each row, their count)``; nan for a row without
    any.  The same as ``np.nanmedian(a, axis=1)``, several times faster (nan sorts last)."""
    s = np.sort(a, axis=1)
    count = np.sum(np.isfinite(s), axis=1)
    rows = np.arange(len(s))
    lo = s[rows, np.maximum(count - 1, 0) // 2]
    hi = s[rows, np.maximum(count, 1) // 2 - (count == 0)]
    return np.where(count > 0, 0.5 * (lo + hi), np.nan), count


def noise_floor(spec: Spectrum, excluded: np.ndarray, half: int, gap: int):
    """``(floor, floor_dof)`` per bin.

    The floor is the geometric mean of the medians of the kept neighbours below and above
    the bin, divided by the median of chi2_nu/nu: exact for a PSD linear in log scale across
    the window (one median over both sides is biased there: on coloured noise it gave twice
    the nominal false alarms), and above the truth where the log PSD is convex (1/f^2 near
    DC: conservative).  ``dof`` is that of a chi-squared with the floor's relative variance.
    A bin with fewer than ``MIN_SIDE`` kept neighbours on a side (the band's ends next to DC
    and Nyquist, between masked lines) gets nan: it is not searched."""
    lo, n_lo, hi, n_hi = _side_medians(spec.psd, excluded, half, gap)
    usable = (n_lo >= MIN_SIDE) & (n_hi >= MIN_SIDE) & (lo > 0) & (hi > 0)
    with np.errstate(invalid="ignore", divide="ignore"):
        floor = np.sqrt(lo * hi) / median_of_chi2(spec.dof)
        # log floor = (log lo + log hi) / 2: relvar = (relvar_lo + relvar_hi) / 4, and a
        # chi-squared with relative variance r has 2 / r degrees of freedom.
        dof = 4.0 / (1.0 / floor_dof(spec.dof, n_lo, spec.bin_correlation)
                     + 1.0 / floor_dof(spec.dof, n_hi, spec.bin_correlation))
    return np.where(usable, floor, np.nan), np.where(usable, dof, np.nan)


def detect_lines(spec: Spectrum, search: LineSearch | None = None,
                 catalogue: LineCatalogue | None = None) -> LineDetection:
    """The lines of ``spec`` in the search band at the family-wise significance of ``search``
    (module docstring), named from ``catalogue`` if given."""
    search = search or LineSearch()
    if not (math.isfinite(spec.dof) and spec.dof > 0):
        raise ValueError("detect_lines: the spectrum has no degrees of freedom; make it with "
                         "welch_spectrum")
    f, p = spec.frequency, spec.psd
    n = len(f)
    band = (f >= search.f_min) & (f <= search.f_max)
    band[[0, n - 1]] = False  # DC and Nyquist bins have half the degrees of freedom
    searched = int(np.sum(band))
    alpha_bin = search.significance / max(searched, 1)
    # DC, Nyquist and bins without power never enter a floor.
    base_excluded = np.zeros(n, dtype=bool)
    base_excluded[[0, n - 1]] = True
    base_excluded |= ~(p > 0)
    excluded = base_excluded.copy()
    lines: list[int] = []
    floor = threshold = np.full(n, np.nan)
    for _ in range(max(1, search.max_rounds)):
        new_floor, nu_f = noise_floor(spec, excluded, search.floor_half_width,
                                      search.floor_gap)
        new_threshold = np.full(n, np.nan)
        ok = band & np.isfinite(new_floor)
        # The floor's degrees of freedom take few distinct values (they depend only on how
        # many neighbours each side keeps): one quantile per value.
        nus, which = np.unique(nu_f[ok], return_inverse=True)
        new_threshold[ok] = stats.f.isf(alpha_bin, spec.dof, nus)[which]
        # A bin whose neighbours are all masked now (inside the skirt of strong lines) keeps
        # the floor it had: leaving lines out only lowers floors.
        keep = ~ok & np.isfinite(floor)
        floor = np.where(keep, floor, new_floor)
        threshold = np.where(keep, threshold, new_threshold)
        ok = np.isfinite(threshold)
        over = ok & (p > threshold * floor)
        found = _peaks(p, over, threshold)
        if found == lines:
            break
        lines = found
        excluded = base_excluded.copy()
        for k in lines:  # leave each line's bins over the threshold (and its lobe) out
            lo, hi = k, k
            while lo - 1 >= 0 and over[lo - 1]:
                lo -= 1
            while hi + 1 < n and over[hi + 1]:
                hi += 1
            excluded[max(0, lo - search.floor_gap): hi + search.floor_gap + 1] = True
    detection = LineDetection(spec, search, floor, threshold, searched)
    for k in lines:
        fk = _refined_frequency(f, p, k)
        peak = SpectralLine(fk, float(p[k]), float(floor[k]), float(threshold[k]))
        resonance = _classify(spec, search, k, fk, peak)
        if resonance:
            peak.kind = RESONANCE
            detection.resonances.append(peak)
            continue
        if catalogue is not None:
            peak.name, peak.kind = catalogue.name(fk, spec.resolution)
        detection.lines.append(peak)
    return detection


def _classify(spec: Spectrum, search: LineSearch, k: int, fk: float,
              peak: SpectralLine) -> bool:
    """Measure the peak at bin ``k`` (its width ratio and fluctuation, stored in ``peak``)
    and tell whether it is a resonance rather than a line."""
    resonance = False
    if search.max_width_ratio is not None and spec.segment_length >= 16:
        offset = min(0.5, abs(fk - spec.frequency[k]) / spec.resolution)
        offsets, widths = tone_widths(WINDOW, spec.segment_length)
        peak.width_ratio = (half_power_width(spec.psd, k, search.floor_half_width)
                            / float(np.interp(offset, offsets, widths)))
        resonance = peak.width_ratio > search.max_width_ratio
    seg = spec.segment_psd
    if seg is not None and seg.shape[0] >= MIN_SEGMENTS_STABILITY:
        x = seg[:, k]
        peak.fluctuation = float(np.var(x, ddof=1) / np.mean(x) ** 2)
        if search.stability_alpha is not None and not resonance:
            # The noise under a line: the floor, or the PSD 5-8 bins either side where that
            # is higher (a line on a resonance hump fluctuates with the hump).
            near = [j for j in (*range(k - 8, k - 4), *range(k + 5, k + 9))
                    if 0 < j < len(spec.psd) - 1]
            under = max(peak.floor, float(np.median(spec.psd[near]))) if near else peak.floor
            line_limit, noise_limit = stability_limits(
                seg.shape[0], _overlap_correlations(spec), search.stability_alpha,
                peak.psd / under)
            resonance = peak.fluctuation > max(line_limit, noise_limit)
    return resonance


#: Fewest Welch segments for the stability test (the sample variance of fewer says little).
MIN_SEGMENTS_STABILITY = 8


def half_power_width(p: np.ndarray, k: int, limit: int) -> float:
    """Width in bins of the peak at bin ``k``: between the points where ``p`` falls to half
    of ``p[k]`` (linear interpolation between bins), walking at most ``limit`` bins each way
    (a peak that does not fall that far gets the width walked)."""
    level = 0.5 * p[k]
    n = len(p)
    lo = k
    while lo > 0 and k - lo < limit and p[lo - 1] > level:
        lo -= 1
    left = (lo - (p[lo] - level) / (p[lo] - p[lo - 1]) if lo > 0 and p[lo - 1] <= level
            else float(lo))
    hi = k
    while hi < n - 1 and hi - k < limit and p[hi + 1] > level:
        hi += 1
    right = (hi + (p[hi] - level) / (p[hi] - p[hi + 1]) if hi < n - 1 and p[hi + 1] <= level
             else float(hi))
    return float(right - left)


@lru_cache(maxsize=16)
def tone_widths(window: str, length: int, pad: int = 32, grid: int = 51):
    """``(offsets, widths)``: the ``half_power_width`` [bins] of a noise-free tone's
    periodogram under ``window`` of ``length`` samples, the tone ``offset`` bins (0..0.5)
    from the centre of its peak bin (1.33 bins on a bin centre, 2.04 half-way for Hann)."""
    w = signal.get_window(window, length)
    kernel = np.abs(np.fft.fft(w, length * pad)) ** 2
    kernel /= kernel[0]
    span = np.arange(-8, 9)
    offsets = np.linspace(0.0, 0.5, grid)
    widths = np.array([half_power_width(
        kernel[np.round((span - d) * pad).astype(int) % (length * pad)], 8, 8)
        for d in offsets])
    return offsets, widths


def _overlap_correlations(spec: Spectrum) -> tuple[float, ...]:
    """Correlation of the DFT of white noise between segments 1, 2, ... apart (the window
    against itself shifted by multiples of the step), rounded for caching."""
    if spec.segment_step <= 0 or spec.segment_length < 16:
        return ()
    w = signal.get_window(WINDOW, spec.segment_length)
    energy = float(np.sum(w * w))
    out = []
    for m in range(1, spec.segments):
        shift = m * spec.segment_step
        if shift >= len(w):
            break
        out.append(round(float(np.sum(w[: len(w) - shift] * w[shift:])) / energy, 4))
    return tuple(out)


#: Ratios psd/floor at which the stability limits are tabulated (interpolated in log).
_STABILITY_RATIOS = np.geomspace(1.0, 1e4, 33)


def stability_limits(segments: int, correlations: tuple[float, ...], alpha: float,
                     ratio: float) -> tuple[float, float]:
    """``(line limit, noise limit)`` of the fluctuation (variance / mean^2 over segments) of
    a peak ``ratio`` times its noise floor: a line exceeds the first with probability
    ``alpha``; narrow-band noise falls below the second with probability ``alpha``."""
    line, noise = _stability_table(segments, correlations, alpha)
    r = min(max(ratio, 1.0), _STABILITY_RATIOS[-1])
    return float(np.interp(math.log(r), np.log(_STABILITY_RATIOS), line)), noise


@lru_cache(maxsize=16)
def _stability_table(segments: int, correlations: tuple[float, ...], alpha: float,
                     draws: int = 20000):
    """Quantiles of the fluctuation by simulation (fixed seed, so the limits are the same in
    every run): the segments' DFT values at the peak are a line's constant amplitude plus
    complex Gaussian noise correlated between overlapping segments as the window makes it;
    the line's power over the noise's is ``ratio - 1`` for each tabulated ratio."""
    rng = np.random.default_rng(20261125)
    lags = np.zeros(segments)
    lags[0] = 1.0
    lags[1: 1 + len(correlations)] = correlations[: segments - 1]
    cov = np.array([[lags[abs(i - j)] for j in range(segments)] for i in range(segments)])
    chol = np.linalg.cholesky(cov + 1e-12 * np.eye(segments))
    z = (rng.standard_normal((draws, segments)) + 1j * rng.standard_normal((draws, segments)))
    noise = (z @ chol.T) / math.sqrt(2.0)  # unit power, correlated like the segments
    line = []
    for r in _STABILITY_RATIOS:
        x = np.abs(math.sqrt(r - 1.0) + noise) ** 2
        t = np.var(x, axis=1, ddof=1) / np.mean(x, axis=1) ** 2
        line.append(float(np.quantile(t, 1.0 - alpha)))
        if r == 1.0:
            noise_limit = float(np.quantile(t, alpha))
    return np.array(line), noise_limit


def _peaks(p: np.ndarray, over: np.ndarray, threshold: np.ndarray) -> list[int]:
    """Bins of the lines: local maxima over the threshold whose prominence (the peak over the
    higher of the valleys that separate it from stronger peaks) also exceeds the threshold."""
    if not np.any(over):
        return []
    logp = np.log(np.where(p > 0, p, np.min(p[p > 0])))
    idx, props = signal.find_peaks(logp, prominence=0.0)
    keep = over[idx] & (props["prominences"] > np.log(np.where(over[idx], threshold[idx], 1.0)))
    return sorted(int(k) for k in idx[keep])


def _refined_frequency(f: np.ndarray, p: np.ndarray, k: int) -> float:
    """Peak frequency from a parabola through the log PSD at bins k-1, k, k+1."""
    if k <= 0 or k >= len(p) - 1 or min(p[k - 1], p[k], p[k + 1]) <= 0:
        return float(f[k])
    a, b, c = np.log(p[k - 1]), np.log(p[k]), np.log(p[k + 1])
    denom = a - 2 * b + c
    shift = 0.5 * (a - c) / denom if denom < 0 else 0.0
    return float(f[k] + float(np.clip(shift, -0.5, 0.5)) * (f[1] - f[0]))


# --------------------------------------------------------------------------------------
# Spectral extent: how far up the spectrum reaches, with the band open to Nyquist


@dataclass(frozen=True)
class ExtentSearch:
    """Settings of the spectral extent."""

    #: Band [Hz] whose mean PSD is the reference level.
    reference_band: tuple[float, float] = (100.0, 500.0)
    drop_db: float = 10.0  # the extent is where the smoothed PSD is this far below it
    #: Width of the running band the PSD is averaged over, in octaves, centred (on a log
    #: scale) on each bin: 1/3 octave spans 0.891 f .. 1.122 f (23 % of f).
    smoothing_octaves: float = 1.0 / 3.0
    #: Top of the analysed band [Hz]; None: the last bin below Nyquist.
    f_max: float | None = None

    def __post_init__(self):
        lo, hi = self.reference_band
        if not (0 < lo < hi and math.isfinite(hi)):
            raise ValueError(f"ExtentSearch: reference_band = {self.reference_band!r}; "
                             "allowed: 0 < lo < hi, finite")
        if not (self.drop_db > 0 and self.smoothing_octaves > 0):
            raise ValueError(f"ExtentSearch: drop_db = {self.drop_db!r}, smoothing_octaves = "
                             f"{self.smoothing_octaves!r}; allowed: > 0")
        if self.f_max is not None and not self.f_max > hi:
            raise ValueError(f"ExtentSearch: f_max = {self.f_max!r} Hz; allowed: above the "
                             f"reference band's top {hi!r} Hz, or None")


@dataclass
class SpectralExtent:
    """The frequency up to which the smoothed PSD stays within ``drop_db`` of its level in
    the reference band."""

    frequency: float  # Hz; the band top when censored; nan when undefined
    #: True when the smoothed PSD is still within ``drop_db`` of the reference at the top of
    #: the band: the extent is at least ``band_top`` (a lower bound, not a value).
    censored: bool
    band_top: float  # Hz, the highest bin analysed
    reference_level: float  # mean PSD in the reference band [unit^2/Hz]
    frequencies: np.ndarray  # Hz, the bins analysed (reference band's bottom .. band top)
    smoothed: np.ndarray  # the smoothed PSD at those bins


def spectral_extent(spec: Spectrum, search: ExtentSearch | None = None) -> SpectralExtent:
    """The highest frequency at which the PSD, averaged over a running band of
    ``smoothing_octaves`` (only bins inside the analysed band, from the bottom of the
    reference band to ``f_max``), is still at least the mean PSD of the reference band less
    ``drop_db``; linear interpolation in dB to the crossing with the next bin.  A flat
    spectrum has no extent below the band top: the result is then censored."""
    search = search or ExtentSearch()
    f, p = spec.frequency, spec.psd
    lo, hi = search.reference_band
    nyquist_below = f[-2] if len(f) > 2 else f[-1]
    top = nyquist_below if search.f_max is None else min(search.f_max, nyquist_below)
    eps = 1e-6 * spec.resolution  # bins computed from a rounded sample rate
    ref_bins = (f >= lo - eps) & (f <= hi + eps)
    band = (f >= lo - eps) & (f <= top + eps)
    fb, pb = f[band], p[band]
    reference = float(np.mean(p[ref_bins])) if np.any(ref_bins) else math.nan
    if not (reference > 0 and fb.size >= 2):
        return SpectralExtent(math.nan, False, float(top), reference, fb,
                              np.full(fb.size, np.nan))
    half = 2.0 ** (0.5 * search.smoothing_octaves)
    cum = np.concatenate([[0.0], np.cumsum(pb)])
    a = np.searchsorted(fb, fb / half, side="left")
    b = np.searchsorted(fb, fb * half, side="right")
    smoothed = (cum[b] - cum[a]) / (b - a)
    level = reference * 10.0 ** (-search.drop_db / 10.0)
    above = np.nonzero(smoothed >= level)[0]
    if above.size == 0:
        return SpectralExtent(math.nan, False, float(fb[-1]), reference, fb, smoothed)
    k = int(above[-1])
    if k == fb.size - 1:
        return SpectralExtent(float(fb[-1]), True, float(fb[-1]), reference, fb, smoothed)
    d0, d1 = (10.0 * np.log10(max(smoothed[j], 1e-300) / level) for j in (k, k + 1))
    frac = d0 / (d0 - d1) if d0 > d1 else 0.0
    return SpectralExtent(float(fb[k] + frac * (fb[k + 1] - fb[k])), False, float(fb[-1]),
                          reference, fb, smoothed)


# --------------------------------------------------------------------------------------
# Sub-harmonics: power at odd multiples of half a fundamental against the comb


@dataclass(frozen=True)
class SubharmonicSearch:
    """Settings of the sub-harmonic test."""

    f_min: float = 100.0  # Hz, band of the positions k f0 and (k + 1/2) f0
    f_max: float = 1500.0
    #: A position's narrow band holds the bins whose centres lie within this many bins of
    #: it (two or three bins: the top of a line's Hann main lobe).
    half_width: float = 1.0
    #: Probability that the flag is raised where there is no sub-harmonic (noise only).
    significance: float = 0.01
    #: Least power of the sub-harmonic comb (summed over its positions, less the floor)
    #: against the comb at k f0, for the flag: -20 dB is above the Hann leakage of the comb
    #: into the half positions (-32 dB at 2.5 bins).
    min_ratio_db: float = -20.0
    floor_half_width: int = 24  # bins each side that set the floor, as for lines

    def __post_init__(self):
        if not (0 <= self.f_min < self.f_max and math.isfinite(self.f_max)):
            raise ValueError(f"SubharmonicSearch: band {self.f_min!r}..{self.f_max!r} Hz is "
                             "invalid; allowed: 0 <= f_min < f_max, finite")
        if not (0 < self.significance < 1 and self.half_width >= 0.5
                and self.floor_half_width >= 8):
            raise ValueError(f"SubharmonicSearch: significance = {self.significance!r}, "
                             f"half_width = {self.half_width!r}, floor_half_width = "
                             f"{self.floor_half_width!r}; allowed: 0 < significance < 1, "
                             "half_width >= 0.5, floor_half_width >= 8")


@dataclass
class Subharmonic:
    """Result of the sub-harmonic test on one spectrum."""

    fundamental: float  # Hz, f0
    positions: int  # half positions (k + 1/2) f0 with a floor, in the band
    #: Mean over the half positions of (PSD summed over the position's bins) / (floor summed
    #: over them): about 1 without a sub-harmonic.
    statistic: float
    threshold: float  # the statistic's 1 - significance quantile without a sub-harmonic
    half_excess: float  # power of the half positions above their floor [unit^2]
    comb_excess: float  # power of the positions k f0 above their floor [unit^2]
    flag: bool

    @property
    def ratio_db(self) -> float:
        """Sub-harmonic comb over the comb at k f0 [dB] (nan when either has no power above
        the floor)."""
        if self.half_excess > 0 and self.comb_excess > 0:
            return 10.0 * math.log10(self.half_excess / self.comb_excess)
        return math.nan


def subharmonic_test(spec: Spectrum, fundamental: float,
                     search: SubharmonicSearch | None = None) -> Subharmonic:
    """Is there power at the odd multiples of half the fundamental f0, (k + 1/2) f0, beyond
    the noise floor?  A response with the period 1/f0 has lines only at k f0; one with twice
    that period (a period doubling) also at (k + 1/2) f0.

    Each position's narrow band is summed, PSD and floor; the floor is a running median as
    for lines (``noise_floor``) with the bins of every multiple of f0/2 left out.  The
    statistic is the mean over the half positions of band power / band floor; without a
    sub-harmonic it follows F(nu_psd, nu_floor) with nu_psd from the Welch degrees of
    freedom of each band (its bins correlated as the window makes them) and nu_floor from
    the floors' scatter (correlated where their neighbourhoods overlap).  The flag is raised
    when the statistic exceeds the 1 - significance quantile and the sub-harmonic comb's
    power above the floor is at least ``min_ratio_db`` of the comb's at k f0 (or the comb
    has none)."""
    search = search or SubharmonicSearch()
    f, p = spec.frequency, spec.psd
    df = spec.resolution
    nan = Subharmonic(float(fundamental), 0, math.nan, math.nan, math.nan, math.nan, False)
    if not (fundamental > 0 and math.isfinite(fundamental) and math.isfinite(spec.dof)):
        return nan
    half_f = 0.5 * fundamental
    tol = search.half_width * df
    # distance of every bin from the nearest multiple of f0/2
    nearest = np.round(f / half_f)
    excluded = (np.abs(f - nearest * half_f) <= tol) & (nearest > 0)
    excluded[[0, len(f) - 1]] = True
    excluded |= ~(p > 0)
    floor, floor_dof_ = noise_floor(spec, excluded, search.floor_half_width, 0)

    halves = _position_bins(f, floor, half_f, fundamental, search.f_min, search.f_max, tol)
    combs = _position_bins(f, floor, fundamental, fundamental, search.f_min, search.f_max, tol)
    if halves is None:
        return nan
    idx, mask = halves
    k = idx.shape[0]
    r = _bin_power_correlations(spec)
    n = mask.sum(axis=1)
    # variance of a band's mean power over its mean, for each band's bin count (contiguous)
    own_var = np.array([math.inf] + [_mean_variance(np.arange(m), r)
                                     for m in range(1, mask.shape[1] + 1)])
    floor_sum = np.sum(np.where(mask, floor[idx], 0.0), axis=1)
    ratios = np.sum(np.where(mask, p[idx], 0.0), axis=1) / floor_sum
    # Each band sum is a chi-squared of nu / own_var degrees of freedom (its bins count as
    # 1 / own_var independent ones); the mean of k of them has k^2 / sum(1 / dof).
    dof_psd = k * k * spec.dof / float(np.sum(own_var[n]))
    seg = spec.segment_psd
    gap = (~excluded & np.isfinite(floor) & (f >= search.f_min - tol)
           & (f <= search.f_max + tol))
    if seg is not None and seg.shape[0] >= MIN_SEGMENTS_STABILITY and np.sum(gap) >= 8:
        # An impulsive force's spectral estimates scatter more than Gaussian noise's, and
        # together over the band (one strong impact lifts every bin of its segment).  That
        # common part is measured on the floor's own bins: over the segments, the variance of
        # their mean power (over the floor) less what independent bins would give.  The
        # statistic's variance is then the common part plus the half bands' own, over the
        # segments (overlap-corrected); never below the Gaussian value.
        segments = seg.shape[0]
        g = np.mean(seg[:, gap] / floor[gap], axis=1)
        common = max(0.0, float(np.var(g, ddof=1)) - _mean_variance(np.nonzero(gap)[0], r))
        own = float(np.sum(own_var[n])) / k**2
        rho2 = np.asarray(_overlap_correlations(spec)[: segments - 1]) ** 2
        lags = np.arange(1, rho2.size + 1)
        inflation = 1.0 + 2.0 * float(np.sum((1.0 - lags / segments) * rho2))
        var = (common + own) / segments * inflation
        dof_psd = min(dof_psd, 2.0 / var)
    width = 2 * search.floor_half_width + 1
    floor_rv = np.sum(np.where(mask, 2.0 / floor_dof_[idx], 0.0), axis=1) / n
    c = np.sum(np.where(mask, idx, 0), axis=1) / n
    overlap = np.clip(1.0 - np.abs(c[:, None] - c[None, :]) / width, 0.0, None)
    rv = np.sqrt(np.outer(floor_rv, floor_rv))
    dof_floor = 2.0 / (float(np.sum(overlap * rv)) / (k * k))
    statistic = float(np.mean(ratios))
    threshold = float(stats.f.isf(search.significance, dof_psd, dof_floor))

    def excess(bins):
        if bins is None:
            return 0.0
        i, m = bins
        return float(np.sum(np.where(m, p[i] - floor[i], 0.0)) * df)

    half_excess, comb_excess = excess(halves), excess(combs)
    result = Subharmonic(float(fundamental), k, statistic, threshold, half_excess,
                         comb_excess, False)
    strong_enough = (comb_excess <= 0 or half_excess
                     >= comb_excess * 10.0 ** (search.min_ratio_db / 10.0))
    result.flag = bool(statistic > threshold and strong_enough)
    return result


def _position_bins(f: np.ndarray, floor: np.ndarray, first: float, step: float,
                   f_min: float, f_max: float, tol: float):
    """``(bins, mask)`` of the positions first, first + step, ... in [f_min, f_max]: per
    position (row) the bins whose centres lie within ``tol`` of it (``mask``; ``bins``
    clipped to the spectrum), only positions with a bin and a floor at every bin; None when
    there is none."""
    df = f[1] - f[0]
    centres = first + step * np.arange(max(0, math.ceil((f_min - tol - first) / step)),
                                       math.floor((f_max + tol - first) / step) + 1)
    if centres.size == 0:
        return None
    w = math.ceil(tol / df) + 1
    bins = np.round(centres / df).astype(int)[:, None] + np.arange(-w, w + 1)[None, :]
    inside = (bins >= 0) & (bins < len(f))
    bins = np.clip(bins, 0, len(f) - 1)
    mask = inside & (np.abs(f[bins] - centres[:, None]) <= tol)
    ok = mask.any(axis=1) & ~np.any(mask & ~np.isfinite(floor[bins]), axis=1)
    if not np.any(ok):
        return None
    return bins[ok], mask[ok]


def _mean_variance(bins: np.ndarray, r: np.ndarray) -> float:
    """Variance of the mean of one segment's periodogram over ``bins`` (each bin of unit
    variance over its mean, bins j apart correlated r[j]) for Gaussian noise."""
    d = np.abs(np.subtract.outer(bins, bins))
    return float(np.sum(np.where(d < len(r), r[np.minimum(d, len(r) - 1)], 0.0))) / bins.size**2


def _bin_power_correlations(spec: Spectrum) -> np.ndarray:
    """Correlation of the power of white noise in bins 0, 1, 2, ... apart under the window
    (Hann: 1, 4/9, 1/36, 0, ...)."""
    if spec.segment_length < 16:
        return np.array([1.0])
    w2 = signal.get_window(WINDOW, spec.segment_length) ** 2
    return (np.abs(np.fft.rfft(w2))[:8] / np.sum(w2)) ** 2
