"""The paper's creep-rattle scenario (MODEL_NOTES section 3) in the paper's setup: the pinion
kinematic from the paper's engine orders, a constant resisting torque M_res on the wheel (its
eq. 10: the Driveline FMU's ``vehicle.model`` = 1), no coupled driveline.  Co-simulate the
GearMeshRattle and Driveline FMUs, drop the start transient, and compare the statistics of
equal windows after it (mean ± window-to-window scatter, min–max) with the paper's reported
figures; write the paper's Figures 3-5 as PNG files and the comparison as Markdown.  Then the
comparison of the contact models -- the default (crowned flanks, compliant teeth), the paper's
own as printed and the line contact -- each at its defaults and as a band over the dissipation,
film, boundary friction and teeth, in the paper's setup (printed first) and, apart, in the
coupled driveline; and the 789 rpm / 29-tooth hypothesis for the paper's 380/190 Hz lines
(drive_rattle_cosim.paper_models, the model library's compiled loop: the FMUs' numbers).

    python examples/paper_scenario.py [--stop-time 11] [--transient 1] [--window 2]
        [--set GearMeshRattle.contact.damping=50] [--out out/paper_scenario]

The FMUs are built into dist/ first (build_fmu.py) unless --fmu-dir points to built ones.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

from drive_rattle import MAX_PAIR_SLOTS, DrivelineParameters, MeshParameters
from drive_rattle.parameters import specs
from drive_rattle_build import build_fmus
from drive_rattle_build.library import build_in_place
from drive_rattle_cosim.analysis import (
    catalogue_for,
    extent_result_text,
    further_statistics,
    markdown_table,
    number_text,
    onsets_from_counters,
    paper_comparison,
    strongest_line,
    subharmonic_result_text,
    windowed_statistics,
)
from drive_rattle_cosim.harness import CoSimulation
from drive_rattle_cosim.paper_models import (
    CALIBRATION,
    COUPLED,
    PAPER,
    compare,
    comparison_table,
    hypothesis,
    scope_text,
)
from drive_rattle_cosim.paper_models import report as models_report
from drive_rattle_cosim.progress import Phases
from drive_rattle_cosim.spectral_lines import (
    KINDS,
    MIN_SEGMENTS_STABILITY,
    RESONANCE,
    UNEXPLAINED,
    ExtentSearch,
    LineSearch,
    SubharmonicSearch,
    detect_lines,
    spectral_extent,
    subharmonic_test,
    welch_spectrum,
)

ROOT = Path(__file__).resolve().parents[1]
#: The paper's setup in the Driveline FMU's public names: the wheel under a constant M_res.
PAPER_SETUP = {"vehicle.model": 1}
MESH_OUTPUTS = ["wheel.phi", "wheel.w", "mesh.W", "mesh.W_peak", "mesh.delta_peak",
                "mesh.v_impact", "mesh.n_contact", "mesh.impacts_drive", "mesh.impacts_coast",
                *(f"pair[{k}].W" for k in range(MAX_PAIR_SLOTS))]
#: Welch segment [s]: 4 Hz resolution, enough to tell engine orders 13.8 Hz apart at 830 rpm.
SEGMENT_SECONDS = 0.25
KIND_COLOURS = {"mesh": "tab:red", "sideband": "tab:purple", "engine order": "tab:orange",
                UNEXPLAINED: "black"}


def run(stop_time: float = 11.0, transient: float = 1.0, window: float = 2.0,
        step: float = 1e-4, out_dir: str | Path = "out/paper_scenario",
        fmu_dir: str | Path | None = None, parameters: dict | None = None,
        significance: float = 0.01, show_plot: bool = False, progress: bool = False) -> dict:
    """Run the scenario; returns the windowed statistics, the comparison rows, the lines of
    the spectrum after the transient, the written files and the wall time of the run [s].
    With ``progress``, each phase is announced on stderr with its time (and the co-simulation
    shows a progress bar where stderr is a terminal)."""
    phases = Phases("paper scenario", enabled=progress)
    with phases.phase("building the model library"):
        build_in_place()  # a fresh clone has no model library yet, and the parameters need it
    # The paper's setup unless the caller sets the Driveline's load path.
    parameters = {**{f"Driveline.{k}": v for k, v in PAPER_SETUP.items()},
                  **(parameters or {})}
    mesh_params = MeshParameters.from_public(_unit_parameters(parameters, "GearMeshRattle"))
    drive_params = DrivelineParameters.from_public(_unit_parameters(parameters, "Driveline"))
    if not (0 <= transient < stop_time and window > 0 and transient + window <= stop_time):
        raise ValueError(f"stop_time = {stop_time!r} s, transient = {transient!r} s, window = "
                         f"{window!r} s; allowed: 0 <= transient, window > 0 and transient + "
                         "window <= stop_time")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if fmu_dir is None:
        with phases.phase("building the FMUs (dist/)"):
            fmu_dir = build_fmus(ROOT / "dist")["GearMeshRattle"].parent
    fmu_dir = Path(fmu_dir)
    wall = time.perf_counter()
    with phases.phase(f"co-simulating the FMUs, {stop_time:g} s"), \
            CoSimulation(fmu_dir / "GearMeshRattle.fmu", fmu_dir / "Driveline.fmu", parameters,
                         step=step) as sim:
        res = sim.run(stop_time, [f"GearMeshRattle.{n}" for n in MESH_OUTPUTS],
                      progress=progress)
    wall = time.perf_counter() - wall
    with phases.phase("statistics and spectral lines of the windows"):
        res.to_csv(out / "cosim.csv")
        t = np.asarray(res.time)
        s = {name.split(".", 1)[1]: np.asarray(col) for name, col in res.columns.items()}
        onsets = onsets_from_counters(t, s["mesh.impacts_drive"], s["mesh.impacts_coast"],
                                      s["mesh.v_impact"])
        search = LineSearch(significance=significance)
        catalogue = catalogue_for(mesh_params, drive_params)
        ws = windowed_statistics(t, s, *onsets, mesh_params.derived()["normal_mass"], transient,
                                 window, lines=search, catalogue=catalogue,
                                 segment_seconds=SEGMENT_SECONDS)
        # The spectrum of everything the windows cover: more averages, so weaker lines show.
        analysed = slice(ws.slices[0].start + 1, ws.slices[-1].stop)
        full_spec = welch_spectrum(t[analysed], s["mesh.W"][analysed], SEGMENT_SECONDS)
        full = detect_lines(full_spec, search, catalogue)
        full_extent = spectral_extent(full_spec, ExtentSearch())
        full_sub = subharmonic_test(full_spec, catalogue.fundamental, SubharmonicSearch())
        per_window = ws.detections
        rows = paper_comparison(ws)
        table = markdown_table(rows, headers=("quantity", "this run: mean ± scatter (min–max "
                                              "over windows)", "paper"))
        further = markdown_table(further_statistics(ws), headers=("further statistics",
                                                                  "this run"))

        def windows_with(peak) -> str:
            if peak.kind == RESONANCE:
                hits = sum(any(abs(r.frequency - peak.frequency) <= d.resolution
                               for r in d.resonances) for d in per_window)
            else:
                hits = sum(d.near(peak.frequency) is not None for d in per_window)
            return f"{hits} of {len(per_window)}"

        peaks = sorted(full.lines + full.resonances, key=lambda ln: ln.frequency)
        not_measured = "not measured"
        too_few = f"not measured (under {MIN_SEGMENTS_STABILITY} segments)"
        lines = markdown_table(
            [(f"{ln.frequency:.1f}", ln.name or ("—" if ln.kind == RESONANCE else "unexplained"),
              ln.kind, f"{ln.ratio_db:.1f}", number_text(ln.width_ratio, not_measured, spec=".2f"),
              number_text(ln.fluctuation, too_few, spec=".2f"), windows_with(ln))
             for ln in peaks],
            headers=("peak [Hz]", "name", "kind", "above floor [dB]", "width / a tone's",
                     "fluctuation", "found in windows"))
        spec = full.spectrum
        setting = ", ".join(f"`{k}={v}`" for k, v in parameters.items()) or "defaults"
        if drive_params.vehicle_model == 1:
            setting = ("the paper's setup, the pinion kinematic from its engine orders and a "
                       f"constant M_res = {drive_params.drag:.4g} N·m on the wheel; " + setting)
        extent = extent_result_text(full_extent, spec.sample_rate)
        subharmonic = subharmonic_result_text(full_sub)
        report = out / "comparison.md"
        report.write_text(
            f"# Paper scenario: {stop_time:g} s co-simulated (GearMeshRattle + Driveline FMUs, "
            f"fmpy harness, {step:g} s communication step; parameters: {setting})\n\n"
            f"Statistics of {len(ws.windows)} windows of {ws.window:g} s after a start transient "
            f"of {ws.transient:g} s (left out): mean ± window-to-window standard deviation "
            "(min–max over the windows). Rattle is chaotic: compare statistics, not trajectories. "
            "Impact velocities are the normal approach speeds at contact onsets "
            "(`mesh.v_impact`), per flank as percentiles and RMS, with the impact energy rate "
            "Σ ½ m_n v² per second; a periodic impact pattern puts its onsets in a few clusters, "
            "so no single percentile is \"the\" impact speed, and the paper does not say which "
            "statistic its figure is. The paper's figures come from its own, unpublished gear "
            "data (docs/model.md). Spectral figures: Welch spectra of the total normal force "
            f"({SEGMENT_SECONDS:g} s Hann segments, {spec.resolution:g} Hz resolution, up to "
            f"Nyquist); a line where the PSD exceeds its noise floor at {significance:.0%} "
            "family-wise significance and the peak is neither wider than the window makes a tone "
            "nor fluctuating between segments like noise (else: a resonance); the spectral "
            "extent where the 1/3-octave PSD falls 10 dB below its 100–500 Hz mean; the "
            "sub-harmonic flag from the power at odd multiples of half the forcing frequency "
            f"f0 = {catalogue.fundamental:.2f} Hz against the noise floor (docs/analysis.md)."
            "\n\n"
            + table + "\n" + further
            + f"\nWall time of the co-simulation: {wall:.1f} s ({wall / stop_time:.2f} s per "
            "simulated second).\n\n"
            f"## Lines of the spectrum after the transient ({spec.segments} segments, "
            f"{spec.dof:.0f} degrees of freedom, {len(full.lines)} lines and "
            f"{len(full.resonances)} resonances found in "
            f"{full.search.f_min:g}–{full.search.f_max:g} Hz)\n\n"
            f"Over all windows together: spectral extent {extent}; sub-harmonic {subharmonic}."
            "\n\n"
            f"Names: mesh = z_p n/60 = {catalogue.mesh_frequency:.1f} Hz, Ek = engine order k "
            f"(k × {catalogue.shaft_frequency:.2f} Hz); a name means the line lies within one "
            "bin of that frequency. \"width / a tone's\": the peak's −3 dB width over the width "
            "the window gives a pure tone at the same offset from the bin centre (a resonance "
            "above 1.5); \"fluctuation\": variance / mean² of the peak bin's power over the "
            "segments (about (2r − 1)/r² for a line r times its floor, about 1 for noise). "
            "\"found in windows\": windows whose own spectrum has a peak of that kind there.\n\n"
            + lines)
    # The two contact models side by side, each with its band, and the hypothesis test (the
    # compiled loop; with the parameters given, on top of each model's own).
    span = {"stop_time": stop_time, "transient": transient, "window": window, "step": step}
    # The contact models side by side, each with its band, in the paper's setup and apart in
    # the coupled driveline, and the hypothesis test (the compiled loop; with the parameters
    # given, on top of each model's own).
    own = {k: v for k, v in parameters.items()
           if k.removeprefix("Driveline.") not in PAPER_SETUP}
    models = _with_parameters(own) if own else None
    with phases.phase("the contact models and their bands, the paper's setup (compiled loop)"):
        results = compare(**span, **({"models": models} if models else {}), setup=PAPER)
    with phases.phase("the contact models and their bands, the coupled driveline"):
        coupled = compare(**span, **({"models": models} if models else {}), setup=COUPLED)
    with phases.phase("the 789 rpm / 29-tooth hypothesis"):
        h = hypothesis(**span) if not own else None
    models_text = models_report(results, h, coupled)
    models_file = out / "models.md"
    models_file.write_text("# The paper comparison: the contact models, each as a band, in "
                           "the paper's setup and in the coupled driveline\n\n"
                           + models_text, encoding="utf-8")
    with phases.phase("figures"):
        figures, fig5_names = _figures(t, s, ws, full, catalogue, out, show_plot)
    files = [report, models_file, out / "cosim.csv", *figures]
    phases.done()
    return {"statistics": ws, "rows": rows, "lines": full, "files": files, "table": table,
            "models": results, "models_table": comparison_table(results),
            "coupled": coupled, "coupled_table": comparison_table(coupled),
            "scope": scope_text(results), "coupled_scope": scope_text(coupled),
            "fig5_names": fig5_names, "wall_seconds": wall}


def _with_parameters(parameters: dict):
    """The two models with the user's parameters on top (public names, by unit)."""
    from dataclasses import replace

    from drive_rattle_cosim.paper_models import MODELS

    attrs = {}
    for unit, cls in (("GearMeshRattle", MeshParameters), ("Driveline", DrivelineParameters)):
        by_name = {spec.name: attr for attr, spec in specs(cls)}
        attrs[unit] = {by_name[k]: v for k, v in _unit_parameters(parameters, unit).items()}
    return tuple(replace(m, mesh={**attrs["GearMeshRattle"], **m.mesh},
                         driveline={**attrs["Driveline"], **m.driveline}) for m in MODELS)


def _unit_parameters(parameters: dict, unit: str) -> dict:
    return {k.split(".", 1)[1]: v for k, v in parameters.items() if k.startswith(unit + ".")}


def _figures(t, s, ws, full, catalogue, out: Path, show_plot: bool
             ) -> tuple[list[Path], list[str]]:
    """Figures 3-5 as PNG files, and the line names Fig. 5 writes."""
    import matplotlib

    if not show_plot:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig5, names = _fig5(plt, full, strongest_line(ws), catalogue, out)
    files = [_fig3(plt, t, s, ws, catalogue, out), _fig4(plt, t, s, ws, catalogue, out), fig5]
    if show_plot:
        plt.show()
    plt.close("all")
    return files, names


#: Resolution of the saved figures [dots per inch]; the figures are drawn at it, so that a
#: pixel column of an axes is one column of the PNG.
DPI = 120
#: Forcing periods shown at full resolution in Fig. 3's lower panel.
ZOOM_PERIODS = 3


def envelope(t, y, columns: int):
    """The record ``y(t)`` as ``columns`` equal spans of time, each with the smallest and the
    largest sample in it: ``(centre, low, high)`` of every span holding a sample.  Drawn as a
    band, one span per pixel column, it shows every sample's value and nothing else -- a line
    through 110,000 samples on 1000 pixel columns shows only the samples it happens to join
    (aliasing: a 27.7 Hz forcing turns into slow false strokes)."""
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    if columns < 1 or t.size < 1:
        raise ValueError(f"envelope: columns = {columns!r}, {t.size} samples; allowed: "
                         "columns >= 1 and one sample or more")
    edges = np.linspace(t[0], t[-1], columns + 1)
    column = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, columns - 1)
    first = np.flatnonzero(np.diff(column, prepend=-1))  # first sample of each column used
    centre = 0.5 * (edges[column[first]] + edges[column[first] + 1])
    return centre, np.minimum.reduceat(y, first), np.maximum.reduceat(y, first)


def zoom_span(t, start: float, period: float, periods: int = ZOOM_PERIODS) -> slice:
    """The samples of ``periods`` forcing periods of ``period`` [s] from ``start`` [s] (cut
    at the record's end): the span Fig. 3 draws at full resolution."""
    t = np.asarray(t, dtype=float)
    if not (period > 0 and periods >= 1 and t[0] <= start <= t[-1]):
        raise ValueError(f"zoom_span: start = {start!r} s, period = {period!r} s, periods = "
                         f"{periods!r}; allowed: a start within the record's "
                         f"{t[0]:g}–{t[-1]:g} s, period > 0, periods >= 1")
    h = (t[-1] - t[0]) / (t.size - 1)
    lo = int(np.searchsorted(t, start - 1e-6 * h))
    hi = int(np.searchsorted(t, start + periods * period + 1e-6 * h, side="right"))
    return slice(lo, hi)


def onset_samples(counter) -> np.ndarray:
    """Indices of the samples where a cumulative onset counter grew (the step ending there
    holds one or more onsets)."""
    c = np.asarray(counter)
    return np.flatnonzero(np.diff(c, prepend=c[:1]) > 0)


#: The ways a pair's force rises from 0 in a step, by the mesh's onset counters in it.
PAIR_ONSET_KINDS = ("drive", "coast", "both", "under load")


def pair_onsets(force, drive_counter, coast_counter) -> dict[str, int]:
    """The contact onsets of one tooth pair -- the samples where its normal force goes from 0
    to above 0 -- by the mesh's onset counters in the same step: an impact on the drive or
    the coast flank (that flank's counter grew), ``both`` (both grew: flank not told), or
    ``under load`` (neither grew: the pair took up load on a flank already in contact, as
    a pair entering the zone of action does)."""
    w = np.asarray(force, dtype=float)
    rises = np.flatnonzero((w[1:] > 0) & (w[:-1] <= 0)) + 1
    drive = np.diff(np.asarray(drive_counter), prepend=drive_counter[0])[rises] > 0
    coast = np.diff(np.asarray(coast_counter), prepend=coast_counter[0])[rises] > 0
    return {"drive": int(np.sum(drive & ~coast)), "coast": int(np.sum(coast & ~drive)),
            "both": int(np.sum(drive & coast)), "under load": int(np.sum(~drive & ~coast))}


def pair_onsets_text(counts: dict[str, int]) -> str:
    """``pair_onsets`` in words, for Fig. 4's title."""
    total = sum(counts.values())
    if total == 0:
        return "no contact onset of this pair in this span (its force never rises from 0)"
    words = {"drive": ("impact on the drive flank", "impacts on the drive flank"),
             "coast": ("impact on the coast flank", "impacts on the coast flank"),
             "both": ("in a step with onsets on both flanks",
                      "in steps with onsets on both flanks"),
             "under load": ("taking up load on a flank in contact",
                            "taking up load on a flank in contact")}
    parts = [f"{counts[k]} {words[k][counts[k] > 1]}" for k in PAIR_ONSET_KINDS if counts[k]]
    return (f"{total} contact onset{'s' if total > 1 else ''} of this pair in this span "
            "(its force rising from 0):\n" + ", ".join(parts))


def _fig3(plt, t, s, ws, catalogue, out: Path) -> Path:
    """The wheel speed: the whole run as a min/max band per pixel column, and a few forcing
    periods after the transient at full resolution, with the impacts marked."""
    fig, (whole, zoom) = plt.subplots(2, 1, figsize=(9, 7), dpi=DPI, layout="constrained",
                                      gridspec_kw={"height_ratios": [1, 1.25]})
    w = s["wheel.w"]
    whole.set(xlim=(t[0], t[-1]), xlabel="time [s]", ylabel="wheel speed [rad/s]",
              title=f"Wheel speed (paper Fig. 3), the whole run; dotted: the "
                    f"{len(ws.windows)} windows of {ws.window:g} s")
    fig.canvas.draw()  # the layout, hence the axes' width in pixels
    columns = max(1, int(whole.get_window_extent().width))
    centre, low, high = envelope(t, w, columns)
    whole.fill_between(centre, low, high, step="mid", lw=0, color="tab:blue",
                       label=f"wheel speed: min–max of the {len(t) / columns:.0f} samples in "
                             "each pixel column")
    whole.axvspan(t[0], t[0] + ws.transient, color="0.85", zorder=0,
                  label=f"start transient ({ws.transient:g} s, left out)")
    for start in ws.starts[1:]:
        whole.axvline(start, color="0.6", lw=0.6, ls=":")
    mean = ws.scatter("mean_wheel_speed")
    whole.hlines(mean.mean, ws.starts[0], ws.starts[-1] + ws.window, color="k", ls="--",
                 lw=0.9, label=f"mean after the transient: {mean.text(digits=4)} rad/s")
    period = 1.0 / catalogue.fundamental
    span = zoom_span(t, ws.starts[0], period)
    whole.axvspan(t[span][0], t[span][-1], color="tab:orange", alpha=0.5, lw=0,
                  label="the span of the panel below")
    _headroom(whole, low.min(), high.max(), above=0.45)
    whole.legend(loc="upper center", fontsize=7, ncol=2)

    tz = t[span]
    zoom.plot(tz * 1e3, w[span], lw=0.8, color="tab:blue", label="wheel speed, every sample")
    counts = []
    for counter, marker, colour, flank in (("mesh.impacts_drive", "v", "tab:red", "drive"),
                                           ("mesh.impacts_coast", "^", "tab:green", "coast")):
        k = onset_samples(s[counter][span])
        k = k[k > 0]  # an onset in the step ending at the span's first sample lies before it
        counts.append(len(k))
        zoom.plot(tz[k] * 1e3, w[span][k], marker, ms=5, color=colour, ls="none",
                  label=f"{flank}-flank onsets ({len(k)}): an impact in the step ending there")
    zoom.set(xlim=(tz[0] * 1e3, tz[-1] * 1e3), xlabel="time [ms]",
             ylabel="wheel speed [rad/s]")
    zoom.set_title(f"{ZOOM_PERIODS} forcing periods after the transient ({ZOOM_PERIODS} × "
                   f"{period * 1e3:.1f} ms, f0 = {catalogue.fundamental:.2f} Hz), all "
                   f"{len(tz)} samples: {counts[0]} drive and {counts[1]} coast onsets",
                   fontsize=10)
    _headroom(zoom, np.min(w[span]), np.max(w[span]), below=0.3)
    zoom.legend(loc="lower center", fontsize=7, ncol=3)
    return _save(fig, out / "fig3_wheel_speed.png")


def _headroom(ax, low: float, high: float, above: float = 0.0, below: float = 0.0) -> None:
    """Y limits around ``low``–``high`` with ``above`` / ``below`` of the range left free for
    a legend, which then hides no data."""
    r = (high - low) or 1.0
    ax.set_ylim(low - (0.04 + below) * r, high + (0.04 + above) * r)


def _fig4(plt, t, s, ws, catalogue, out: Path) -> Path:
    """One tooth pair's normal force over three passages through the zone of action, around
    its largest force after the transient; the title counts that pair's onsets."""
    analysed = slice(ws.slices[0].start, ws.slices[-1].stop)
    ta = t[analysed]
    slot = max(range(MAX_PAIR_SLOTS), key=lambda k: np.max(s[f"pair[{k}].W"][analysed]))
    force = s[f"pair[{slot}].W"][analysed]
    period = MAX_PAIR_SLOTS / catalogue.mesh_frequency  # the slot's next pair enters then
    centre = ta[int(np.argmax(force))]
    lo = max(ta[0], centre - 1.5 * period)
    hi = min(ta[-1], lo + 3 * period)
    span = (ta >= lo) & (ta <= hi)
    counts = pair_onsets(force[span], s["mesh.impacts_drive"][analysed][span],
                         s["mesh.impacts_coast"][analysed][span])
    fig, ax = plt.subplots(figsize=(10, 4.6), dpi=DPI, layout="constrained")
    ax.plot(ta[span] * 1e3, s["mesh.W"][analysed][span], lw=0.6, color="0.7",
            label="total normal force of all pairs (mesh.W)")
    ax.plot(ta[span] * 1e3, force[span], lw=1.0, color="tab:blue",
            label=f"normal force of the pair in slot {slot} (pair[{slot}].W)")
    ax.set(xlabel="time [ms]", ylabel="normal force [N]")
    ax.set_title(f"Normal force of one tooth pair (slot {slot}) through the zone of action "
                 f"(paper Fig. 4); a new pair takes this slot every {period * 1e3:.1f} ms\n"
                 f"{pair_onsets_text(counts)}", fontsize=9)
    ax.legend(loc="upper right", fontsize=8)
    return _save(fig, out / "fig4_pair_force.png")


#: Lines named in Fig. 5 (the strongest); every line is marked, and listed in comparison.md.
NAMED_LINES = 10


def named_lines(lines, count: int = NAMED_LINES) -> list:
    """The ``count`` detected lines with the highest PSD, in order of frequency: the lines
    Fig. 5 names (the others are marked and listed in comparison.md's line table)."""
    return sorted(sorted(lines, key=lambda ln: -ln.psd)[:count], key=lambda ln: ln.frequency)


def _fig5(plt, full, strongest, catalogue, out: Path) -> tuple[Path, list[str]]:
    """The spectrum after the transient with its noise floor, the detection threshold, every
    detected line marked, the strongest named in a strip above the plot, and the strongest
    line over the windows (the comparison's) starred."""
    spec = full.spectrum
    f_max = min(full.search.f_max, spec.frequency[-1])
    fig, (strip, ax) = plt.subplots(2, 1, figsize=(12, 6.5), dpi=DPI, sharex=True,
                                    layout="constrained",
                                    gridspec_kw={"height_ratios": [1, 3.2]})
    shown = spec.frequency <= f_max
    ax.semilogy(spec.frequency[shown], spec.psd[shown], lw=0.7, color="tab:blue",
                label="PSD of the total normal force")
    ax.semilogy(spec.frequency[shown], full.floor[shown], lw=0.8, color="0.45",
                label="noise floor (running median)")
    ax.semilogy(spec.frequency[shown], (full.floor * full.threshold)[shown], lw=0.8,
                color="0.45", ls="--",
                label=f"line threshold ({full.search.significance:.0%} family-wise)")
    for ln in full.lines:
        ax.plot(ln.frequency, ln.psd * 1.6, "v", ms=4, color=KIND_COLOURS[ln.kind])
    named = named_lines(full.lines)
    for ln in named:
        strip.axvline(ln.frequency, color=KIND_COLOURS[ln.kind], lw=0.6, alpha=0.7)
    for kind in (*KINDS, UNEXPLAINED):  # legend entries for the marker colours
        ax.plot([], [], "v", color=KIND_COLOURS[kind], label=f"detected line: {kind}")
    if strongest is not None:
        near = np.abs(spec.frequency - strongest.frequency) <= spec.resolution
        ax.plot(strongest.frequency, float(np.max(spec.psd[near])) * 4.0, "*", ms=10,
                color="gold", mec="k", mew=0.5,
                label=f"the strongest line 100–1500 Hz over the windows (comparison.md): "
                      f"{strongest.frequency:.1f} Hz, {strongest.name}, found in "
                      f"{strongest.found_in} of {strongest.windows} windows")
    ax.set(xlim=(0, f_max), xlabel="frequency [Hz]", ylabel="PSD [N²/Hz]")
    fig.legend(loc="outside lower center", fontsize=7, ncol=3)
    names = _staggered_names(fig, strip, named, f_max)
    unnamed = len(full.lines) - len(named)
    strip.set_title(
        f"Normal-force spectrum after the transient (paper Fig. 5): Welch, {spec.segments} "
        f"Hann segments, {spec.resolution:g} Hz bins; mesh {catalogue.mesh_frequency:.1f} Hz, "
        f"engine order 1 = {catalogue.shaft_frequency:.2f} Hz\n{len(full.lines)} detected "
        f"lines marked ▼, the {len(named)} strongest named"
        + (f"; the other {unnamed} and the {len(full.resonances)} resonances (not drawn) are "
           "listed in comparison.md" if unnamed or full.resonances else ""), fontsize=10)
    return _save(fig, out / "fig5_force_spectrum.png"), names


#: Size of the line names in Fig. 5 [pt].
FONT_PT = 8.0


def _staggered_names(fig, strip, lines, f_max: float, tiers: int = 2) -> list[str]:
    """Names of the lines as vertical text in ``strip``, each in the lowest tier where it
    keeps a text height from its neighbours (the tier counter wraps if all are taken); the
    names written, in order of frequency."""
    strip.set(ylim=(0, tiers), yticks=[])
    for side in ("left", "right", "top"):
        strip.spines[side].set_visible(False)
    fig.canvas.draw()
    width_px = strip.get_window_extent().width
    text_px = FONT_PT / 72 * DPI + 2  # the height of a name's text, plus a gap
    min_df = text_px / width_px * f_max
    last = [-math.inf] * tiers
    names = []
    for n, ln in enumerate(sorted(lines, key=lambda x: x.frequency)):
        free = [k for k in range(tiers) if ln.frequency - last[k] >= min_df]
        tier = free[0] if free else n % tiers
        last[tier] = ln.frequency
        name = ln.name or f"{ln.frequency:.0f} Hz ?"
        strip.text(ln.frequency, tier + 0.05, name, rotation=90, fontsize=FONT_PT,
                   ha="center", va="bottom", color=KIND_COLOURS[ln.kind], clip_on=True)
        names.append(name)
    return names


def _save(fig, path: Path) -> Path:
    if fig.get_layout_engine() is None:
        fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    return path


def _parse_set(items: list[str]) -> dict:
    params = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or "." not in key:
            raise SystemExit(f"--set {item!r}: expected UNIT.NAME=VALUE")
        low = value.lower()
        if low in ("true", "false"):
            params[key] = low == "true"
        else:
            try:
                params[key] = float(value)
            except ValueError:
                params[key] = value
    return params


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--stop-time", type=float, default=11.0, help="simulated time [s]")
    ap.add_argument("--transient", type=float, default=1.0,
                    help="start transient left out of the statistics [s]")
    ap.add_argument("--window", type=float, default=2.0,
                    help="window of the statistics [s]; the scatter is over the windows")
    ap.add_argument("--step", type=float, default=1e-4, help="communication step [s]")
    ap.add_argument("--set", action="append", default=[], metavar="UNIT.NAME=VALUE",
                    help="parameter value (SI), e.g. GearMeshRattle.contact.damping=50")
    ap.add_argument("--significance", type=float, default=0.01,
                    help="family-wise false-alarm probability of the line search")
    ap.add_argument("--out", default="out/paper_scenario", help="output folder")
    ap.add_argument("--fmu-dir", default=None, help="folder with built FMUs (default: build)")
    ap.add_argument("--show", action="store_true", help="show the figures")
    args = ap.parse_args(argv)
    result = run(args.stop_time, args.transient, args.window, args.step, args.out,
                 args.fmu_dir, _parse_set(args.set), args.significance, args.show,
                 progress=True)
    print("The paper comparison, in the paper's setup (the pinion kinematic from its engine "
          "orders, a constant M_res on the wheel, no coupled driveline): each contact model at "
          "its defaults (mean ± window scatter) and [over its band].\n")
    print(result["scope"])
    print(result["models_table"])
    print(CALIBRATION + "\n")
    print("Not the paper's setup -- the same models in the coupled driveline (the soft output "
          "shaft to the vehicle inertia):\n")
    print(result["coupled_scope"])
    print(result["coupled_table"])
    print(f"The band's settings and the hypothesis for the paper's lines: {result['files'][1]}")
    print(f"FMU co-simulation wall time {result['wall_seconds']:.1f} s")
    for f in result["files"]:
        print("wrote", f)
    return 0


if __name__ == "__main__":
    sys.exit(main())
