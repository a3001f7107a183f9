"""The paper's creep-rattle scenario (MODEL_NOTES section 3): co-simulate the GearMeshRattle and
Driveline FMUs, drop the start transient, and compare the statistics of equal windows after it
(mean ± window-to-window scatter, min–max) with the paper's reported figures; write the paper's
Figures 3-5 as PNG files and the comparison as Markdown.  Then the comparison of the two
contact models -- the default (crowned flanks) and the paper's own -- each at its defaults and
as a band over the dissipation and film parameters, and the 789 rpm / 29-tooth hypothesis for
the paper's 380/190 Hz lines (drive_rattle_cosim.paper_models, the model library's compiled
loop: the FMUs' numbers); it prints that comparison.

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
    further_statistics,
    markdown_table,
    onsets_from_counters,
    paper_comparison,
    windowed_statistics,
)
from drive_rattle_cosim.harness import CoSimulation
from drive_rattle_cosim.paper_models import compare, comparison_table, hypothesis
from drive_rattle_cosim.paper_models import report as models_report
from drive_rattle_cosim.progress import Phases
from drive_rattle_cosim.spectral_lines import (
    KINDS,
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
    parameters = dict(parameters or {})
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
        per_window = [detect_lines(welch_spectrum(t[sl][1:], s["mesh.W"][sl][1:], SEGMENT_SECONDS),
                                   search, catalogue) for sl in ws.slices]
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
        lines = markdown_table(
            [(f"{ln.frequency:.1f}", ln.name or ("—" if ln.kind == RESONANCE else "unexplained"),
              ln.kind, f"{ln.ratio_db:.1f}", f"{ln.width_ratio:.2f}", f"{ln.fluctuation:.2f}",
              windows_with(ln)) for ln in peaks],
            headers=("peak [Hz]", "name", "kind", "above floor [dB]", "width / a tone's",
                     "fluctuation", "found in windows"))
        spec = full.spectrum
        setting = ", ".join(f"`{k}={v}`" for k, v in parameters.items()) or "defaults"
        if full_extent.censored:
            extent = (f"≥ {full_extent.frequency:.0f} Hz: the 1/3-octave PSD stays within 10 dB of "
                      "its 100–500 Hz mean up to the band top next to Nyquist "
                      f"({spec.sample_rate / 2:g} Hz)")
        else:
            extent = f"{full_extent.frequency:.0f} Hz"
        subharmonic = (f"{'flagged' if full_sub.flag else 'not flagged'} (f0 = "
                       f"{full_sub.fundamental:.2f} Hz, {full_sub.positions} positions, statistic "
                       f"{full_sub.statistic:.3g} against the threshold {full_sub.threshold:.3g}; "
                       f"sub-harmonic comb over the comb {full_sub.ratio_db:.1f} dB)")
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
    with phases.phase("the two contact models and their bands (compiled loop)"):
        if parameters:
            models = _with_parameters(parameters)
            results = compare(**span, models=models)
        else:
            results = compare(**span)
        models_text = models_report(results, hypothesis(**span) if not parameters else None)
    models_file = out / "models.md"
    models_file.write_text("# The paper comparison: two contact models, each as a band\n\n"
                           + models_text, encoding="utf-8")
    with phases.phase("figures"):
        figures = _figures(t, s, ws, full, catalogue, out, show_plot)
    files = [report, models_file, out / "cosim.csv", *figures]
    phases.done()
    return {"statistics": ws, "rows": rows, "lines": full, "files": files, "table": table,
            "models": results, "models_table": comparison_table(results),
            "wall_seconds": wall}


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


def _figures(t, s, ws, full, catalogue, out: Path, show_plot: bool) -> list[Path]:
    import matplotlib

    if not show_plot:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    files = [_fig3(plt, t, s, ws, out), _fig4(plt, t, s, ws, catalogue, out),
             _fig5(plt, full, catalogue, out)]
    if show_plot:
        plt.show()
    plt.close("all")
    return files


def _fig3(plt, t, s, ws, out: Path) -> Path:
    fig, ax = plt.subplots(figsize=(9, 4))
    ax.plot(t, s["wheel.w"], lw=0.5, color="tab:blue", label="wheel speed")
    ax.axvspan(t[0], t[0] + ws.transient, color="0.85", zorder=0,
               label=f"start transient ({ws.transient:g} s, left out)")
    for start in ws.starts[1:]:
        ax.axvline(start, color="0.6", lw=0.6, ls=":")
    mean = ws.scatter("mean_wheel_speed")
    ax.hlines(mean.mean, ws.starts[0], ws.starts[-1] + ws.window, color="k", ls="--", lw=0.9,
              label=f"mean after the transient: {mean.text(digits=4)} rad/s")
    ax.set(xlabel="time [s]", ylabel="wheel speed [rad/s]",
           title=f"Wheel speed (paper Fig. 3); dotted: the {len(ws.windows)} windows "
                 f"of {ws.window:g} s")
    ax.legend(loc="lower right", fontsize=8)
    return _save(fig, out / "fig3_wheel_speed.png")


def _fig4(plt, t, s, ws, catalogue, out: Path) -> Path:
    """One tooth pair's normal force over three passages through the zone of action, around
    its largest force after the transient."""
    analysed = slice(ws.slices[0].start, ws.slices[-1].stop)
    ta = t[analysed]
    slot = max(range(MAX_PAIR_SLOTS), key=lambda k: np.max(s[f"pair[{k}].W"][analysed]))
    force = s[f"pair[{slot}].W"][analysed]
    period = MAX_PAIR_SLOTS / catalogue.mesh_frequency  # the slot's next pair enters then
    centre = ta[int(np.argmax(force))]
    lo = max(ta[0], centre - 1.5 * period)
    hi = min(ta[-1], lo + 3 * period)
    span = (ta >= lo) & (ta <= hi)
    drive = np.ptp(s["mesh.impacts_drive"][analysed][span])
    coast = np.ptp(s["mesh.impacts_coast"][analysed][span])
    if drive + coast == 0:
        flank = "no contact onset in this span (the flanks stay in contact)"
    elif coast == 0:
        flank = f"drive flank: all {drive} contact onsets in this span"
    elif drive == 0:
        flank = f"coast flank: all {coast} contact onsets in this span"
    else:
        flank = f"both flanks: {drive} onsets on the drive, {coast} on the coast flank"
    fig, ax = plt.subplots(figsize=(9, 4.2))
    ax.plot(ta[span] * 1e3, s["mesh.W"][analysed][span], lw=0.6, color="0.7",
            label="total normal force of all pairs (mesh.W)")
    ax.plot(ta[span] * 1e3, force[span], lw=1.0, color="tab:blue",
            label=f"normal force of the pair in slot {slot} (pair[{slot}].W)")
    ax.set(xlabel="time [ms]", ylabel="normal force [N]")
    ax.set_title(f"Normal force of one tooth pair (slot {slot}) as it passes through the zone "
                 f"of action (paper Fig. 4)\n{flank}; a new pair takes this slot every "
                 f"{period * 1e3:.1f} ms", fontsize=10)
    ax.legend(loc="upper right", fontsize=8)
    return _save(fig, out / "fig4_pair_force.png")


def _fig5(plt, full, catalogue, out: Path) -> Path:
    """The spectrum after the transient with its noise floor, the detection threshold, and
    every detected line marked and named; names staggered in a strip above the plot."""
    spec = full.spectrum
    f_max = min(full.search.f_max, spec.frequency[-1])
    fig, (strip, ax) = plt.subplots(2, 1, figsize=(12, 6.5), sharex=True, layout="constrained",
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
        strip.axvline(ln.frequency, color=KIND_COLOURS[ln.kind], lw=0.4, alpha=0.5)
    for kind in (*KINDS, UNEXPLAINED):  # legend entries for the marker colours
        ax.plot([], [], "v", color=KIND_COLOURS[kind], label=f"detected line: {kind}")
    _staggered_names(fig, strip, full.lines, f_max)
    ax.set(xlim=(0, f_max), xlabel="frequency [Hz]", ylabel="PSD [N²/Hz]")
    ax.legend(loc="lower center", fontsize=7, ncol=2)
    strip.set_title(
        f"Normal-force spectrum after the transient (paper Fig. 5): Welch, {spec.segments} "
        f"Hann segments, {spec.resolution:g} Hz bins; mesh {catalogue.mesh_frequency:.1f} Hz, "
        f"engine order 1 = {catalogue.shaft_frequency:.2f} Hz", fontsize=10)
    return _save(fig, out / "fig5_force_spectrum.png")


def _staggered_names(fig, strip, lines, f_max: float, tiers: int = 4) -> None:
    """Names of the lines as vertical text in ``strip``, each in the lowest tier where it
    keeps a text height from its neighbours (the tier counter wraps if all are taken)."""
    strip.set(ylim=(0, tiers), yticks=[])
    for side in ("left", "right", "top"):
        strip.spines[side].set_visible(False)
    fig.canvas.draw()
    width_px = strip.get_window_extent().width
    text_px = 9.0  # height of 6.5 pt text at 120 dpi, plus a gap
    min_df = text_px / width_px * f_max
    last = [-math.inf] * tiers
    for n, ln in enumerate(sorted(lines, key=lambda x: x.frequency)):
        free = [k for k in range(tiers) if ln.frequency - last[k] >= min_df]
        tier = free[0] if free else n % tiers
        last[tier] = ln.frequency
        name = ln.name or f"{ln.frequency:.0f} Hz ?"
        strip.text(ln.frequency, tier + 0.05, name, rotation=90, fontsize=6.5,
                   ha="center", va="bottom", color=KIND_COLOURS[ln.kind], clip_on=True)


def _save(fig, path: Path) -> Path:
    if fig.get_layout_engine() is None:
        fig.tight_layout()
    fig.savefig(path, dpi=120)
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
    print("The paper comparison: the default model and the paper's contact model, each at its "
          "defaults (mean ± window scatter) and [over its band]:\n")
    print(result["models_table"])
    print(f"FMU co-simulation wall time {result['wall_seconds']:.1f} s")
    for f in result["files"]:
        print("wrote", f)
    return 0


if __name__ == "__main__":
    sys.exit(main())
