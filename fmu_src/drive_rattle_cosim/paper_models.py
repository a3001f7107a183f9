"""The paper comparison like for like: the paper's setup -- the pinion kinematic from its
engine orders, a constant resisting torque M_res on the wheel (its eq. 10, ``vehicle.model`` =
1), no driveline -- for each contact model: the default (lead-crowned flanks with the teeth's
compliance), the paper's own as printed (every pair in the zone of action at the shared rigid
approach with eq. 6's r_y, rigid teeth) and the line contact of unmodified flanks (Palmgren's
law, compliant teeth); each at its defaults and over the plausible range of what the paper does
not give -- the dissipation of a lubricated impact, the film, the boundary friction and the
teeth's compliance (``band``) -- so that no single calibrated point stands for a model.  The
same models in the coupled driveline (the soft output shaft to the vehicle inertia, the
Driveline's default) are a separate table: another operating condition, not the paper's.  And
a variant that tests a hypothesis for the paper's 380/190 Hz lines (its engine orders imply
789 rpm, where a 29-tooth pinion meshes at 381 Hz), reported as a hypothesis.

    python -m drive_rattle_cosim.paper_models [--stop-time 11] [--transient 1] [--window 2]
        [--out out/paper_models.md]

Every run is the compiled coupled loop (``system.simulate``: the co-simulation's numbers, bit
for bit), every statistic the mean ± window-to-window scatter after the start transient
(``analysis.windowed_statistics``); a band cell gives the range of the means over the band's
settings, the model's defaults included.
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import dataclass, field, replace
from pathlib import Path

from drive_rattle.library import ModelError
from drive_rattle.parameters import DrivelineParameters, MeshParameters

from .analysis import (
    FLANKS,
    PAPER_FIGURES,
    STRONGEST_ROW,
    LineSearch,
    WindowedStatistics,
    catalogue_for,
    markdown_table,
    strongest_line,
    windowed_statistics,
)
from .band import (
    BODY_HIGH,
    BODY_LOW,
    BOUNDARY_HIGH,
    BOUNDARY_LOW,
    COMPLIANT_TEETH,
    COUPLED_SETUP,
    PAPER_SETUP,
    RIGID_TEETH,
    SQUEEZE_HIGH,
    SQUEEZE_LOW,
)
from .spectral_lines import (
    SubharmonicSearch,
    detect_lines,
    subharmonic_test,
    welch_spectrum,
)
from .system import simulate

#: Recorded mesh outputs (the statistics and the force spectrum).
SIGNALS = ("wheel.phi", "wheel.w", "mesh.W", "mesh.W_peak", "mesh.delta_peak", "mesh.n_contact",
           "mesh.v_impact", "mesh.impacts_drive", "mesh.impacts_coast", "wheel.tau_load")
#: Welch segment [s] of the spectra (4 Hz bins, as the paper-scenario example).
SEGMENT_SECONDS = 0.25
RPM = 2.0 * math.pi / 60.0


@dataclass(frozen=True)
class Setting:
    """A named set of mesh (and driveline) parameter changes; ``teeth_only``: a setting of
    the teeth's compliance, run only where the teeth are compliant."""

    name: str
    meaning: str
    mesh: dict = field(default_factory=dict)
    driveline: dict = field(default_factory=dict)
    teeth_only: bool = False


#: Where the wheel is run: the paper's setup first (the comparison), the coupled driveline
#: apart (another operating condition).
SETUPS = (
    Setting("the paper's setup", "the pinion kinematic from the paper's engine orders "
            "(orders 2/4/6 at 830 rpm), a constant resisting torque M_res = vehicle.drag = "
            "0.5 M* on the wheel (eq. 10; vehicle.model = 1), no driveline",
            driveline=PAPER_SETUP),
    Setting("coupled driveline", "the pinion as in the paper's setup, the wheel loaded "
            "through the soft output shaft (shaft.k, shaft.c) by the reflected vehicle inertia "
            "under the same drag (vehicle.model = 0, the Driveline's default): not the "
            "paper's setup", driveline=COUPLED_SETUP),
)
PAPER, COUPLED = SETUPS
#: The contact models compared with the paper.
MODELS = (
    Setting("default model", "lead-crowned flanks: each pair at its own crown offset "
            "(contact.geometry = 0), the teeth's compliance in series (tooth.compliance = 1)"),
    Setting("paper's contact model", "every pair in the zone of action an equivalent ellipsoid "
            "at the shared rigid approach, eq. 6's r_y (contact.geometry = 1), rigid teeth as "
            "printed (tooth.compliance = 0)",
            {"contact_geometry": 1, "tooth_compliance": 0}),
    Setting("line contact", "unmodified flanks: every pair in the zone loaded along its "
            "engaged contact line, Palmgren's law (contact.geometry = 2), the teeth's "
            "compliance in series (tooth.compliance = 1)", {"contact_geometry": 2}),
)
#: The band of each model: the plausible range of the lubricated impact's dissipation (the
#: squeeze-film law's low and high ends, docs/model.md section 3.3), of the film and friction
#: (the EHL film with piezoviscous shear, section 4; the boundary friction coefficient
#: 0.05-0.15) and of the teeth (rigid or compliant, section 3.7; the gear bodies at the ends
#: of their fitted range), each changed alone from the model's defaults.  A setting that
#: changes nothing of a model (its teeth as they are; the bodies of rigid teeth) is left out.
BAND = (
    Setting("dissipation low", "squeeze film: St_c 5, e_dry 0.99, phi 0.01", SQUEEZE_LOW),
    Setting("dissipation high", "squeeze film: St_c 20, e_dry 0.9, phi 0.1", SQUEEZE_HIGH),
    Setting("EHL film, Barus", "lubricant.film = 1, friction.viscous_law = 1, "
            "friction.shear_speed = 1", {"film": 1, "viscous_law": 1, "shear_speed": 1}),
    Setting("boundary mu 0.05", "boundary friction coefficient 0.05 (friction.tau_s halved)",
            BOUNDARY_LOW),
    Setting("boundary mu 0.15", "boundary friction coefficient 0.15 (friction.tau_s x 1.5)",
            BOUNDARY_HIGH),
    Setting("rigid teeth", "tooth.compliance = 0", RIGID_TEETH),
    Setting("compliant teeth", "tooth.compliance = 1", COMPLIANT_TEETH),
    Setting("bodies 1.4", "gear bodies' root/bore radius 1.4 (both gears)", BODY_LOW,
            teeth_only=True),
    Setting("bodies 7", "gear bodies' root/bore radius 7 (both gears)", BODY_HIGH,
            teeth_only=True),
)
#: The hypothesis for the paper's lines: its engine orders (26/53/79 Hz) imply 789 rpm; a
#: 29-tooth pinion (with a 57-tooth wheel, ratio 1.97, module 1.5 mm: a similar centre
#: distance, 72.9 mm) then meshes at 381.4 Hz, its half at 190.7 Hz.
HYPOTHESIS = Setting(
    "789 rpm, 29/57 teeth", "engine speed 789 rpm (the paper's orders), pinion 29 and wheel 57 "
    "teeth, module 1.5 mm",
    {"z_pinion": 29, "z_wheel": 57, "m_n": 1.5e-3}, {"w_mean": 789.0 * RPM, **PAPER_SETUP})

#: The statistic of the strongest line's row: one line followed through the windows
#: (analysis.strongest_line), never a mean of each window's strongest line's frequency.
STRONGEST = "strongest line"
#: (quantity, statistic, display scale) of the comparison; the paper's figure from
#: analysis.PAPER_FIGURES where it gives one.
QUANTITIES = (
    ("mean wheel speed [rad/s]", "mean_wheel_speed", 1.0),
    ("max deflection [µm]", "max_penetration", 1e6),
    ("impacts per second, drive flank [1/s]", "impacts_per_second_drive", 1.0),
    ("impacts per second, coast flank [1/s]", "impacts_per_second_coast", 1.0),
    *((f"impact speed at onsets, {flank} flank: {label} [mm/s]", f"impact_speed_{q}_{flank}",
       1e3) for flank, _sign in FLANKS
      for label, q in (("10th percentile", "p10"), ("median", "p50"),
                       ("90th percentile", "p90"), ("RMS", "rms"))),
    *((f"impact energy rate, {flank} flank: Σ ½ m_n v² per second [mW]",
       f"impact_energy_rate_{flank}", 1e3) for flank, _sign in FLANKS),
    ("pairs loaded while in contact [1]", "mean_loaded_pairs", 1.0),
    (STRONGEST_ROW, STRONGEST, 1.0),
)


@dataclass
class Run:
    """One setting's run: its parameters and windowed statistics."""

    setting: Setting
    mesh: MeshParameters
    driveline: DrivelineParameters
    statistics: WindowedStatistics
    record: object  # system.Record


def run(setting: Setting, base: Setting | None = None, stop_time: float = 11.0,
        transient: float = 1.0, window: float = 2.0, step: float = 1e-4,
        setup: Setting = PAPER) -> Run:
    """The scenario in ``setup`` with ``base``'s changes, then ``setting``'s, in the compiled
    loop."""
    mesh = MeshParameters(**_mesh_changes(setting, base))
    drive = DrivelineParameters(**{**setup.driveline, **(base.driveline if base else {}),
                                   **setting.driveline})
    rec = simulate(mesh, drive, stop_time=stop_time, step=step, signals=list(SIGNALS))
    ws = windowed_statistics(rec.time, rec.signals, rec.onset_times, rec.onset_speeds,
                             rec.onset_flanks, mesh.derived()["normal_mass"], transient, window,
                             lines=LineSearch(), catalogue=catalogue_for(mesh, drive),
                             segment_seconds=SEGMENT_SECONDS)
    return Run(setting, mesh, drive, ws, rec)


def _mesh_changes(setting: Setting, base: Setting | None) -> dict:
    return {**(base.mesh if base else {}), **setting.mesh}


def applies(setting: Setting, model: Setting) -> bool:
    """Whether a band setting applies to ``model``: not when it leaves the mesh parameters as
    they are, nor a setting of the teeth's compliance on rigid teeth, nor an option the
    model's law refuses (the EHL film with the line contact)."""
    try:
        changed = MeshParameters(**_mesh_changes(setting, model))
    except (ValueError, ModelError):
        return False
    if setting.teeth_only and changed.tooth_compliance == 0:
        return False
    return changed != MeshParameters(**model.mesh) or bool(setting.driveline)


@dataclass
class ModelBand:
    """A model at its defaults and over its band, in one setup."""

    model: Setting
    central: Run
    band: list[Run]
    setup: Setting = PAPER

    def load_range(self) -> tuple[float, float]:
        """The smallest and largest window mean of the wheel's load torque [N·m] at the
        model's defaults (constant in the paper's setup; in the coupled driveline the slow
        vehicle mode modulates it)."""
        ws = self.central.statistics
        tau = self.central.record.signals["wheel.tau_load"]
        means = [sum(tau[s].tolist()) / len(tau[s]) for s in ws.slices]  # in time order
        return min(means), max(means)

    def cell(self, statistic: str, scale: float) -> str:
        """``mean ± scatter [lo–hi over the band]`` of a statistic (where it has no value in
        any window, why, in words)."""
        if statistic == STRONGEST:
            return self.strongest_cell()
        c = self.central.statistics.scatter(statistic)
        if c.n == 0:
            return self.central.statistics.text(statistic)
        means = [r.statistics.scatter(statistic) for r in (self.central, *self.band)]
        means = [m.mean for m in means if m.n > 0]
        text = f"{_g(c.mean * scale)}"
        if c.n > 1:  # a scatter at the rounding level of the mean is none
            text += (f" ± {_g(c.std * scale, 2)}" if c.std > 1e-9 * abs(c.mean) else " ± 0")
        return text + f" [{_g(min(means) * scale)}–{_g(max(means) * scale)}]"


    def strongest_cell(self) -> str:
        """The model's strongest line at its defaults (frequency, name, in how many windows)
        and, in brackets, the strongest lines over the band (its defaults included)."""
        lines = [strongest_line(r.statistics) for r in (self.central, *self.band)]
        names = list(dict.fromkeys(f"{ln.frequency:.0f} Hz ({ln.name})" for ln in lines
                                   if ln is not None))
        central = lines[0]
        text = central.text() if central is not None else "no line found in any window"
        return text + (f" [over the band: {', '.join(names)}]" if names else "")


def _g(x: float, digits: int = 4) -> str:
    return f"{x:.{digits}g}"


def compare(stop_time: float = 11.0, transient: float = 1.0, window: float = 2.0,
            step: float = 1e-4, models=MODELS, band=BAND, setup: Setting = PAPER
            ) -> list[ModelBand]:
    """Every model at its defaults and over the band (the settings that apply to it), in
    ``setup``."""
    kw = {"stop_time": stop_time, "transient": transient, "window": window, "step": step,
          "setup": setup}
    return [ModelBand(m, run(replace(m, name=m.name), None, **kw),
                      [run(b, m, **kw) for b in band if applies(b, m)], setup)
            for m in models]


def comparison_rows(results: list[ModelBand]) -> list[tuple]:
    """Rows ``(quantity, one cell per model, the paper's figure)``."""
    rows = []
    for quantity, statistic, scale in QUANTITIES:
        paper = PAPER_FIGURES.get(quantity, "—")
        rows.append((quantity, *(r.cell(statistic, scale) for r in results), paper))
    return rows


def comparison_table(results: list[ModelBand]) -> str:
    return markdown_table(comparison_rows(results),
                          headers=("quantity", *(r.model.name for r in results), "paper"))


@dataclass
class Hypothesis:
    """The 789 rpm / 29-tooth variant's force spectrum against the paper's lines."""

    run: Run
    mesh_frequency: float  # Hz
    lines: list  # the lines detected over all windows (spectral_lines.Line)
    resolution: float  # Hz
    subharmonic: object  # spectral_lines.subharmonic_test over all windows
    reference: Hypothesis | None = None  # the default pair, analysed alike

    def near(self, frequency: float):
        """The detected line within one bin of ``frequency``, or None."""
        hits = [ln for ln in self.lines if abs(ln.frequency - frequency) <= self.resolution]
        return max(hits, key=lambda ln: ln.ratio_db) if hits else None


def hypothesis(stop_time: float = 11.0, transient: float = 1.0, window: float = 2.0,
               step: float = 1e-4, setting: Setting = HYPOTHESIS,
               reference: Setting | None = MODELS[0]) -> Hypothesis:
    """The variant run, and the lines of its force spectrum over everything after the
    transient; the same for ``reference`` (the default pair) beside it."""
    r = run(setting, None, stop_time, transient, window, step)
    ws = r.statistics
    analysed = slice(ws.slices[0].start + 1, ws.slices[-1].stop)
    t = r.record.time[analysed]
    spectrum = welch_spectrum(t, r.record.signals["mesh.W"][analysed], SEGMENT_SECONDS)
    catalogue = catalogue_for(r.mesh, r.driveline)
    found = detect_lines(spectrum, LineSearch(), catalogue)
    sub = subharmonic_test(spectrum, catalogue.fundamental, SubharmonicSearch())
    ref = (hypothesis(stop_time, transient, window, step, reference, None)
           if reference is not None else None)
    return Hypothesis(r, catalogue.mesh_frequency, found.lines, spectrum.resolution, sub, ref)


def _line_text(h: Hypothesis, frequency: float) -> str:
    ln = h.near(frequency)
    if ln is None:
        return f"no line within one bin ({h.resolution:g} Hz)"
    return (f"a line at {ln.frequency:.1f} Hz, {ln.ratio_db:.1f} dB above the floor"
            + (f" ({ln.name})" if ln.name else ""))


def hypothesis_text(h: Hypothesis) -> str:
    f_mesh = h.mesh_frequency
    parts = [f"Variant: {h.run.setting.meaning} (the default model otherwise). Its mesh "
             f"frequency is {f_mesh:.1f} Hz, half of it {f_mesh / 2:.1f} Hz; the paper's "
             "lines are 380 and 190 Hz. Lines of the normal-force spectrum over all windows "
             "after the transient:", ""]
    for label, f in (("mesh", f_mesh), ("half mesh", f_mesh / 2), ("380 Hz", 380.0),
                     ("190 Hz", 190.0)):
        parts.append(f"* {label} ({f:.1f} Hz): {_line_text(h, f)}")
    parts.append(f"* sub-harmonic of the forcing (f0 = {h.subharmonic.fundamental:.2f} Hz): "
                 f"{'flagged' if h.subharmonic.flag else 'not flagged'}")
    ref = h.reference
    if ref is not None:
        parts.append(f"* for comparison, the default pair (mesh {ref.mesh_frequency:.1f} Hz): "
                     f"mesh {_line_text(ref, ref.mesh_frequency)}; half mesh "
                     f"{_line_text(ref, ref.mesh_frequency / 2)}; sub-harmonic "
                     f"{'flagged' if ref.subharmonic.flag else 'not flagged'}")
    parts += ["", "This tests a hypothesis; it is not a reproduction: the paper gives neither "
              "its tooth counts nor its inertias, and the variant changes only the speed and "
              "the teeth of the default pair."]
    return "\n".join(parts)


#: What no table of this module shows and every reader must be told.
CALIBRATION = ("The paper's figures come from its own, unpublished gear data, and it does not "
               "say which statistic of which flank its \"4 mm/s\" is. Defaults chosen where "
               "the paper's magnitudes fall are a calibration, not evidence that the model "
               "matches the paper: read the band, not the central value.")


def scope_text(results: list[ModelBand]) -> str:
    """What a table's cells cover: the windows (and what they do not see: the coupled
    driveline's slow load modulation) and the band's settings, model by model."""
    ws = results[0].central.statistics
    setup = results[0].setup
    span = len(ws.windows) * ws.window
    text = (f"{setup.name.capitalize()}: {setup.meaning}. Each cell: the model at its "
            f"defaults, mean ± standard deviation over {len(ws.windows)} windows of "
            f"{ws.window:g} s after a {ws.transient:g} s start transient (one run from one "
            "start: the ± covers the rattle's variation from window to window, not other "
            "starts, and not the parameters), then in brackets the range of the window means "
            "over the band: the model's defaults and each band setting that changes it, one "
            "at a time.")
    if setup.driveline.get("vehicle_model", 0) == 0:
        d = DrivelineParameters(**setup.driveline).derived()
        period = 1.0 / d["vehicle_mode_frequency"]
        loads = ", ".join(f"{r.model.name} {r.load_range()[0] * 1e3:.4g}–"
                          f"{r.load_range()[1] * 1e3:.4g}" for r in results)
        text += (f" In the coupled driveline the vehicle mode ({d['vehicle_mode_frequency']:.4g}"
                 f" Hz: a period of {period:.3g} s, decay time {d['vehicle_mode_decay_time']:.4g}"
                 f" s) modulates the wheel's load slowly; the window means of the load at the "
                 f"defaults span [mN·m]: {loads}. The {span:g} s analysed are "
                 f"{span / period:.2g} of one period, so the ± does not cover that modulation: "
                 "a longer run or another start gives other values beyond it.")
    return text + "\n"


def band_text(results: list[ModelBand]) -> str:
    """The band's settings and the models each applies to."""
    lines = []
    for b in BAND:
        used = [r.model.name for r in results if any(x.setting.name == b.name for x in r.band)]
        lines.append(f"* {b.name} ({b.meaning}): "
                     + (", ".join(used) if used else "changes none of the models"))
    return ("Band settings, each changed alone from a model's defaults, and the models it "
            "applies to (not: a setting that changes nothing of a model, or an option its "
            "law refuses):\n\n" + "\n".join(lines))


def report(results: list[ModelBand], h: Hypothesis | None,
           coupled: list[ModelBand] | None = None) -> str:
    """The comparison in the paper's setup, the same models in the coupled driveline apart,
    and the hypothesis, as Markdown."""
    text = ("Impact speeds are normal approach speeds at contact onsets. " + CALIBRATION
            + "\n\n" + "\n".join(f"* {m.model.name}: {m.model.meaning}" for m in results)
            + "\n\n" + band_text(results) + "\n\n")
    text += (f"## {results[0].setup.name.capitalize()}: the comparison with the paper\n\n"
             + scope_text(results) + "\n" + comparison_table(results))
    if coupled:
        text += (f"\n## {coupled[0].setup.name.capitalize()}: not the paper's setup\n\n"
                 + scope_text(coupled) + "\n" + comparison_table(coupled))
    if h is not None:
        text += "\n## A hypothesis for the paper's 380 / 190 Hz lines\n\n" + hypothesis_text(h)
    return text + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m drive_rattle_cosim.paper_models",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("--stop-time", type=float, default=11.0)
    ap.add_argument("--transient", type=float, default=1.0)
    ap.add_argument("--window", type=float, default=2.0)
    ap.add_argument("--step", type=float, default=1e-4)
    ap.add_argument("--out", type=Path, help="also write the report to this file")
    args = ap.parse_args(argv)
    kw = {"stop_time": args.stop_time, "transient": args.transient, "window": args.window,
          "step": args.step}
    text = report(compare(**kw), hypothesis(**kw), compare(**kw, setup=COUPLED))
    print(text)
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text, encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
