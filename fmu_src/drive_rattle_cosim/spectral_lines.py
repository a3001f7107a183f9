"""Spectral lines found against the spectrum's own noise floor, at a stated significance, and
named after the gear mesh and the engine orders.  Needs numpy and scipy (not the FMUs).

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
4. **Names**: a line within one bin spacing of the mesh frequency ``z_p n/60`` or its
   harmonics, of a mesh +- engine-order sideband, or of an engine order ``k n/60`` or its
   harmonics gets that name (in this priority); any other line is reported as unexplained.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import signal, stats

#: Window of the Welch estimate.  Its sidelobes fall at 18 dB/octave, so a strong line does not
#: leak into the floor far from itself.
WINDOW = "hann"
#: Kinds of named lines, in the order a name is chosen when several fit.
KINDS = ("mesh", "sideband", "engine order")
UNEXPLAINED = "unexplained"
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


def welch_spectrum(time, values, segment_seconds: float = 0.25) -> Spectrum:
    """Welch PSD of a uniformly sampled signal: Hann window, 50 % overlap, the mean removed
    per segment, with its equivalent degrees of freedom."""
    t = np.asarray(time, dtype=float)
    x = np.asarray(values, dtype=float)
    if t.shape != x.shape or t.ndim != 1 or len(t) < 16:
        raise ValueError(f"welch_spectrum: time and values must be 1-D of equal length >= 16; "
                         f"got shapes {t.shape} and {x.shape}")
    if not segment_seconds > 0:
        raise ValueError(f"welch_spectrum: segment_seconds = {segment_seconds!r}; allowed: > 0")
    fs = 1.0 / float(np.median(np.diff(t)))
    nper = min(len(x), max(16, round(segment_seconds * fs)))
    step = nper - nper // 2
    segments = 1 + (len(x) - nper) // step
    window = signal.get_window(WINDOW, nper)
    f, p = signal.welch(x, fs=fs, window=window, nperseg=nper, noverlap=nper // 2,
                        detrend="constant")
    w2 = window * window
    coeff = np.abs(np.fft.rfft(w2))[:8] / np.sum(w2)  # |sum w^2 e^(-2 pi i l n / N)| / sum w^2
    return Spectrum(
        frequency=f, psd=p, dof=welch_dof(window, step, segments), segments=segments,
        segment_length=nper, sample_rate=fs,
        bin_correlation=float(1.0 + 2.0 * np.sum(coeff[1:] ** 2)),
        enbw_bins=float(nper * np.sum(w2) / np.sum(window) ** 2))


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
        for kind in KINDS:
            near = [(abs(f - frequency), name) for f, name, k in
                    self.candidates(frequency + tolerance) if k == kind
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


def median_of_chi2(dof: float) -> float:
    """Median of chi2_dof / dof: the running median's bias against the mean PSD."""
    return float(stats.chi2.median(dof) / dof)


def floor_dof(dof: float, neighbours: np.ndarray, bin_correlation: float) -> np.ndarray:
    """Degrees of freedom of a floor taken as the median of ``neighbours`` bins of
    chi2_dof/dof each: a sample median of n independent values has the variance
    1 / (4 n f(m)^2) (f the density at the median m); correlated neighbouring bins count as
    n / bin_correlation independent ones; a chi-squared with the same relative variance has
    2 / relvar degrees of freedom."""
    m = median_of_chi2(dof)
    density = float(stats.chi2.pdf(m * dof, dof) * dof)
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
        new_threshold[ok] = stats.f.isf(alpha_bin, spec.dof, nu_f[ok])
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
        name, kind = (catalogue.name(fk, spec.resolution) if catalogue is not None
                      else ("", UNEXPLAINED))
        detection.lines.append(SpectralLine(fk, float(p[k]), float(floor[k]),
                                            float(threshold[k]), name, kind))
    return detection


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
