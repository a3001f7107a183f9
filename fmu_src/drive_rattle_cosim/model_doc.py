"""The numbers of docs/model.md (and of docs/analysis.md's runs), computed: every ``<!-- BEGIN
name -->...<!-- END name -->`` block of docs/model.md is the output of ``BLOCKS[name]``, of
docs/analysis.md of ``ANALYSIS_BLOCKS[name]``, written by ``python -m
drive_rattle_cosim.model_doc --update`` (``update``; ``--only NAME`` rewrites one block and
keeps the others) and held against a fresh computation by
tests/cosim/test_model_doc.py (``stale``).  After a change of the default physics,
run that command and review the diff: the findings written around the tables are generated
from the same runs, so a sentence that no longer holds changes with its numbers.

The runs are the model library's compiled loop (the FMUs' numbers bit for bit), deterministic:
the same text on every machine with the same library.  One block is not run on update: section
6.2's grid of the compliant teeth with 24 phases (minutes of runs) is rendered from the data
committed in docs/data/multistability_grid.json, which ``--measure-grid`` measures again (or
``--grid-from`` reduces from the JSON of the study's command); the slow
tests/analysis/test_multistability.py measures two of its points again against it.
"""

from __future__ import annotations

import argparse
import itertools
import re
import sys
from collections.abc import Callable
from functools import lru_cache
from pathlib import Path

from . import band, contact_laws, mesh_stiffness, paper_models, squeeze_impacts
from .analysis import PAPER_FIGURES

DOC = Path(__file__).resolve().parents[2] / "docs" / "model.md"
ANALYSIS_DOC = DOC.with_name("analysis.md")
#: The scenario's horizon of every run of the document [s]: an 11 s run, the first second
#: left out, five windows of 2 s (the README's main command).
HORIZON = {"stop_time": 11.0, "transient": 1.0, "window": 2.0}


def _h(horizon: dict | None) -> tuple:
    return tuple(sorted((horizon or HORIZON).items()))


@lru_cache(maxsize=4)
def _contact_runs(horizon: tuple) -> dict:
    return contact_laws.results(**dict(horizon))


@lru_cache(maxsize=4)
def _paper_runs(horizon: tuple):
    kw = dict(horizon)
    return (paper_models.compare(**kw), paper_models.compare(**kw, setup=paper_models.COUPLED),
            paper_models.hypothesis(**kw))


@lru_cache(maxsize=4)
def _band_runs(horizon: tuple) -> list:
    return band.band(**dict(horizon))


def _g(x: float, digits: int = 3) -> str:
    return f"{x:.{digits}g}"


def _pct(new: float, old: float) -> str:
    return f"{(new / old - 1) * 100:+.1f} %"


def _in(x: float, lo: float, hi: float) -> str:
    return "inside" if lo <= x <= hi else "outside"


# --- section 2: the reference pair ----------------------------------------------------

def _derived() -> dict:
    from drive_rattle import MeshParameters

    return MeshParameters().derived()


def reference_pair() -> str:
    """The default (reference) pair's centre distance and contact ratios (the library's)."""
    d = _derived()
    return (f"a = {d['centre_distance'] * 1e3:.5g} mm, ε_α = {d['eps_alpha']:.4g}, "
            f"ε_β = {d['eps_beta']:.4g}, ε_γ = {d['eps_gamma']:.4g}")


def crown_radius() -> str:
    """The default crowning's r_y of the reference pair."""
    return f"{_derived()['r_y']:.3g} m for the reference pair"


def eq6_radius() -> str:
    """Eq. 6's r_y at the reference pair's pitch point, and its pitch radii."""
    d = _derived()
    return (f"r_y = **{d['r_y_eq6_pitch'] * 1e3:.4g} mm** at the pitch point (the pitch radii "
            f"{d['r_pinion'] * 1e3:.4g} and {d['r_wheel'] * 1e3:.4g} mm)")


def half_lines() -> str:
    """Half the reference pair's longest contact line, b / (2 cos beta_b)."""
    import math

    from drive_rattle import MeshParameters

    half = MeshParameters().b / (2 * math.cos(_derived()["beta_b"]))
    return f"b/(2 cos β_b) = {half * 1e3:.3g} mm"


def line_lengths() -> str:
    """The mean total contact-line length b eps_alpha / cos(beta_b) of the reference pair and
    the range of the engaged lines' sum over a base pitch (the library's line contact)."""
    import ctypes
    import math

    from drive_rattle import DRIVE, MeshParameters
    from drive_rattle.library import MESH
    from drive_rattle.units import Unit

    p = MeshParameters(contact_geometry=2)
    d = p.derived()
    totals = []
    unit = Unit(MESH, p, initialize=False)
    try:
        out, n = (ctypes.c_double * (10 * 16))(), ctypes.c_size_t()
        for k in range(LAW_SAMPLES):
            phi_p = k * 2.0 * math.pi / p.z_pinion / LAW_SAMPLES
            unit.call("rm_probe_pair_laws", int(DRIVE), phi_p, out, 16, ctypes.byref(n))
            totals.append(sum(out[10 * i + 2] for i in range(n.value)))
    finally:
        unit.close()
    mean = p.b * d["eps_alpha"] / math.cos(d["beta_b"])
    return (f"{mean * 1e3:.4g} mm for the reference pair, the sum of the engaged lines "
            f"{min(totals) * 1e3:.3g}–{max(totals) * 1e3:.3g} mm over a base pitch "
            f"({LAW_SAMPLES} angles; the mean tested)")


#: Pinion angles over a base pitch at which the pairs' laws are sampled.
LAW_SAMPLES = 200


@lru_cache(maxsize=4)
def _pair_laws(geometry: int) -> list[tuple[float, float, float, float]]:
    """(r_x, r_y, K of the exact law, K of eq. 2) of every pair in the zone on the drive flank
    at LAW_SAMPLES pinion angles over a base pitch, for ``contact.geometry`` ``geometry``
    (``rm_probe_pair_laws``: slot, s, length, r_x, r_y, K, ...)."""
    import ctypes
    import math

    from drive_rattle import DRIVE, MeshParameters
    from drive_rattle.library import MESH
    from drive_rattle.units import Unit

    found = {}
    for law in (0, 1):
        p = MeshParameters(contact_geometry=geometry, hertz_law=law)
        unit = Unit(MESH, p, initialize=False)
        try:
            out, n = (ctypes.c_double * (10 * 16))(), ctypes.c_size_t()
            for k in range(LAW_SAMPLES):
                phi_p = k * 2.0 * math.pi / p.z_pinion / LAW_SAMPLES
                unit.call("rm_probe_pair_laws", int(DRIVE), phi_p, out, 16, ctypes.byref(n))
                for i in range(n.value):
                    row = out[10 * i: 10 * i + 10]
                    found.setdefault((k, int(row[0])), []).append(row[3:6])
        finally:
            unit.close()
    return [(a[0], a[1], a[2], b[2]) for a, b in found.values()]


def crowned_laws() -> str:
    """The crowned default's r_y/r_x over a base pitch and how much softer eq. 2 is there."""
    rows = _pair_laws(0)
    rho = [ry / rx for rx, ry, _, _ in rows]
    soft = [exact / sphere for _, _, exact, sphere in rows]
    return (f"{min(soft):.2g}–{max(soft):.2g} times softer than the exact law (ρ = r_y/r_x = "
            f"{min(rho):.0f}–{max(rho):.0f} over a base pitch)")


def eq6_laws() -> str:
    """Eq. 6's r_y over the path of contact, r_y/r_x, and the exact law against eq. 2."""
    rows = _pair_laws(1)
    ry = [r for _, r, _, _ in rows]
    rho = [r / x for x, r, _, _ in rows]
    stiff = [(exact / sphere - 1.0) * 100 for _, _, exact, sphere in rows]
    return (f"{min(ry) * 1e3:.3g}–{max(ry) * 1e3:.3g} mm along the path of contact, r_y/r_x = "
            f"{min(rho):.2g}–{max(rho):.3g}; there the exact elliptical law "
            f"(`contact.hertz_law` = 0) is {min(stiff):.0f}–{max(stiff):.0f} % stiffer than "
            "eq. 2 (= 1)")


# --- section 3.3: the dissipation laws' constants ----------------------------------------

#: The mesh damping ratios of section 3.3 and the speed [m/s] and substep [s] of their single
#: impacts (a rigid spur pair: the Hertz law, whose restitution is then speed-independent).
ZETAS = (0.03, 0.05, 0.1)
ZETA_IMPACT = {"v": 4e-3, "h_max": 5e-7}
#: The speeds [m/s] at which the Hunt-Crossley restitution of the defaults' factor is given.
HUNT_CROSSLEY_SPEEDS = (1e-3, 20e-3, 100e-3)
#: The pinion angles over a base pitch at which the flooded critical speed is taken.
PITCH_SAMPLES = 201


_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def _sci(x: float, digits: int = 3) -> str:
    mantissa, exponent = f"{x:.{digits - 1}e}".split("e")
    return f"{mantissa}·10{str(int(exponent)).translate(_SUPERSCRIPT)}"


def dissipation_constants() -> str:
    """The squeeze-film law's area, critical speeds and film damping at the defaults, the
    Hunt-Crossley factor of the defaults' restitution, and the mesh damping ratio's
    restitutions: the model library's probes and single impacts (section 3.3)."""
    import math

    from drive_rattle import MeshParameters

    p = MeshParameters()
    pitch = 2.0 * math.pi / p.z_pinion
    angles = [k * pitch / (PITCH_SAMPLES - 1) for k in range(PITCH_SAMPLES)]
    (v_c,) = squeeze_impacts.critical_speeds({})
    (low,) = squeeze_impacts.critical_speeds(band.SQUEEZE_LOW)
    (high,) = squeeze_impacts.critical_speeds(band.SQUEEZE_HIGH)
    flooded = squeeze_impacts.critical_speeds({"squeeze_fraction": 1.0}, angles)
    d, hc = squeeze_impacts.hunt_crossley(p.restitution, p.restitution_speed,
                                          HUNT_CROSSLEY_SPEEDS)
    ratio = [squeeze_impacts.measured_restitution(
        ZETA_IMPACT["v"], dissipation=4, damping_ratio=z, beta=0.0, tooth_compliance=0,
        h_max=ZETA_IMPACT["h_max"]) for z in ZETAS]

    def band_case(c):
        return f"St_c {c['stokes_critical']:g}, φ {c['squeeze_fraction']:g}"

    return (
        "\n* squeeze-film area of the default flank at φp = 0: A = "
        f"{_sci(squeeze_impacts.squeeze_area())} m²;\n"
        f"* critical speed at φp = 0: v_c = {v_c * 1e3:.3g} mm/s at the defaults (St_c "
        f"{p.stokes_critical:g}, φ {p.squeeze_fraction:g}); over section 6.4's band from "
        f"{low * 1e3:.2g} mm/s ({band_case(band.SQUEEZE_LOW)}) to {high * 1e3:.2g} mm/s "
        f"({band_case(band.SQUEEZE_HIGH)}); flooded (φ = 1) {flooded[0] * 1e3:.3g} mm/s, "
        f"{min(flooded) * 1e3:.3g}–{max(flooded) * 1e3:.3g} mm/s over a base pitch of the "
        f"pinion's angle ({PITCH_SAMPLES} angles);\n"
        "* film damping of a sticking contact on the pair at the pitch point: "
        f"{squeeze_impacts.pitch_point_damper():.3g} N·s/m;\n"
        f"* Hunt–Crossley from e = {p.restitution:g} at {p.restitution_speed * 1e3:g} mm/s "
        f"(`contact.restitution`, `contact.restitution_speed`): d = {d:.3g} s/m, whose "
        "restitution is " + ", ".join(f"{e:.2g} at {v * 1e3:g} mm/s"
                                       for v, e in zip(HUNT_CROSSLEY_SPEEDS, hc, strict=True))
        + ";\n"
        "* mesh damping ratio, one impact of a rigid spur pair on the pinion at rest at "
        f"{ZETA_IMPACT['v'] * 1e3:g} mm/s (`solver.h_max` = {ZETA_IMPACT['h_max'] * 1e6:g} "
        "µs): e = " + ", ".join(f"{e:.3f}" for e in ratio) + " for ζ = "
        + ", ".join(f"{z:g}" for z in ZETAS) + ".\n\n"
        "(`model_doc.dissipation_constants`: the model library's `rm_probe_squeeze`, "
        "`rm_probe_loads`, `rm_probe_damping_factor` and `rm_probe_restitution`, and single "
        "impacts stepped through it.)\n")


# --- section 3.6: the contact options -----------------------------------------------------

def contact_options(horizon: dict | None = None) -> str:
    runs = _contact_runs(_h(horizon))
    return "\n" + contact_laws.report(progress=False, runs=runs) + "\n"


def contact_findings(horizon: dict | None = None) -> str:
    runs = _contact_runs(_h(horizon))
    sc = {n: {f: ws.scatter(f) for _, f, _ in contact_laws.ROWS} for n, ws in runs.items()}
    crowned, paper, line = ("default (crowned, exact law)", "paper, exact law",
                            "line (Palmgren)")

    def pairs(name):
        return sc[name]["mean_loaded_pairs"].mean

    def three_to_four(name):
        return "within" if 3.0 <= pairs(name) <= 4.0 else "outside"

    yes = [label for label, f, _ in contact_laws.ROWS
           if contact_laws.sensitive([runs[n].scatter(f) for n in runs])]
    no = [label for label, f, _ in contact_laws.ROWS if label not in yes]
    delta = {n: sc[n]["max_penetration"].mean * 1e6 for n in runs}
    # Johnson's roughness parameter of the peak approaches (section 3.5): sigma / delta_max
    from drive_rattle import MeshParameters

    sigma = MeshParameters().sigma * 1e6
    ratios = [sigma / d for d in delta.values()]
    onsets = {n: sc[n]["impacts_per_second_drive"].mean for n in runs}
    return (
        "\n* **Pairs in contact**: the paper's ellipsoids load "
        f"{_g(pairs(paper))} pairs on average ({three_to_four(paper)} the paper's 3–4) and the "
        f"line contact {_g(pairs(line))} ({three_to_four(line)} 3–4): wherever every pair in "
        "the zone of action carries load, the transverse and overlap contact ratios "
        f"(ε_γ ≈ 3) set the count; the crowned default loads {_g(pairs(crowned))}. The "
        "paper's \"3–4 teeth pairs in simultaneous impact\" is a property of its contact "
        "geometry, not of rattle.\n"
        f"* **Sensitive to the contact law** (the spread of the means over the cases beyond "
        f"three window scatters): {'; '.join(yes) or 'none'}. **Not sensitive**: "
        f"{'; '.join(no) or 'none'}.\n"
        "* Peak approach δmax " + ", ".join(f"{n} {_g(delta[n])} µm" for n in runs)
        + "; drive-flank onsets per second " + ", ".join(f"{n} {_g(onsets[n])}" for n in runs)
        + f". Johnson's roughness parameter of the peak approaches, σ/δmax (σ = {sigma:g} µm), "
        f"is {_g(min(ratios), 2)}–{_g(max(ratios), 2)}: "
        + ("above" if min(ratios) > 0.05 else "not everywhere above")
        + " the 0.05 below which a smooth-surface law holds (section 3.5).\n")


# --- section 4: where the mixed regime is reached ----------------------------------------

#: The surface roughnesses [m] and the films of section 4's table: (heading, mesh parameters).
SIGMAS = (0.4e-6, 0.2e-6, 0.1e-6, 0.05e-6, 0.02e-6)
FILMS = (("eq. 11 film, isoviscous", {}),
         ("eq. 11 film, Barus", {"viscous_law": 1, "shear_speed": 1}),
         ("EHL film, Barus", {"viscous_law": 1, "shear_speed": 1, "film": 1}))


@lru_cache(maxsize=4)
def _film_runs(horizon: tuple) -> dict:
    return {(sigma, name): band.run_case(band.BandCase(name, name, {"sigma": sigma, **mesh}),
                                         **dict(horizon))
            for sigma in SIGMAS for name, mesh in FILMS}


def mixed_regime(horizon: dict | None = None) -> str:
    """The fraction of the in-contact samples whose most loaded pair has psi < 1 in the
    paper's setup (today's defaults) over the roughness and the film."""
    h = horizon or HORIZON
    runs = _film_runs(_h(horizon))
    rows = ["| σ [µm] | " + " | ".join(name for name, _ in FILMS) + " |",
            "|---|" + "---|" * len(FILMS)]
    for sigma in SIGMAS:
        cells = [band.cell(runs[sigma, name].values["psi"], 100.0, 3) for name, _ in FILMS]
        rows.append(f"| {sigma * 1e6:g} | " + " | ".join(f"{c} %" for c in cells) + " |")
    return ("\n" + "\n".join(rows) + "\n\n"
            f"(The paper's setup at the defaults but σ and the film, one {h['stop_time']:g} s "
            f"run each from the smooth start, mean ± scatter over its {h['window']:g} s windows "
            f"after {h['transient']:g} s, in % of the samples with a pair in contact; "
            "`band.run_case` with those parameters.)\n")


# --- sections 6.3: the paper comparison ---------------------------------------------------

def paper_comparison(horizon: dict | None = None) -> str:
    paper, coupled, h = _paper_runs(_h(horizon))
    return "\n" + paper_models.report(paper, h, coupled)


def _band_range(mb, statistic: str) -> tuple[float, float]:
    means = [r.statistics.scatter(statistic) for r in (mb.central, *mb.band)]
    means = [m.mean for m in means if m.n]
    return min(means), max(means)


def paper_findings(horizon: dict | None = None) -> str:
    paper, coupled, _ = _paper_runs(_h(horizon))
    out = []
    speed = paper[0].central.statistics.scatter("mean_wheel_speed").mean
    out.append(f"* **Mean wheel speed** {_g(speed, 4)} rad/s against the paper's "
               f"{PAPER_FIGURES['mean wheel speed [rad/s]']}: the kinematic ratio of the "
               "830 rpm pinion, not a test of the contact.")
    for mb in paper:
        pairs = mb.central.statistics.scatter("mean_loaded_pairs").mean
        d = mb.central.statistics.scatter("max_penetration").mean * 1e6
        v = mb.central.statistics.scatter("impact_speed_p50_drive").mean * 1e3
        dlo, dhi = (x * 1e6 for x in _band_range(mb, "max_penetration"))
        vlo, vhi = (x * 1e3 for x in _band_range(mb, "impact_speed_p50_drive"))
        coast = mb.central.statistics.scatter("impacts_per_second_coast").mean
        out.append(
            f"* **{mb.model.name.capitalize()}** in the paper's setup: {_g(pairs)} pairs loaded "
            f"while in contact; δmax {_g(d)} µm at its defaults, {_g(dlo)}–{_g(dhi)} µm over "
            f"its band (1 µm {_in(1.0, dlo, dhi)} it); median drive onset speed {_g(v)} mm/s, "
            f"{_g(vlo)}–{_g(vhi)} mm/s over the band (4 mm/s {_in(4.0, vlo, vhi)} it); "
            f"{_g(coast)} coast onsets per second.")
    d0, c0 = paper[0].central.statistics, coupled[0].central.statistics
    lo, hi = coupled[0].load_range()
    out.append(
        "* **The load path matters**: the default model in the coupled driveline gives a "
        f"median drive onset speed of {_g(c0.scatter('impact_speed_p50_drive').mean * 1e3)} "
        f"mm/s, δmax {_g(c0.scatter('max_penetration').mean * 1e6)} µm and "
        f"{_g(c0.scatter('impacts_per_second_coast').mean)} coast onsets/s, against "
        f"{_g(d0.scatter('impact_speed_p50_drive').mean * 1e3)} mm/s, "
        f"{_g(d0.scatter('max_penetration').mean * 1e6)} µm and "
        f"{_g(d0.scatter('impacts_per_second_coast').mean)}/s under the paper's constant "
        f"M_res; its load's window means span {_g(lo * 1e3, 4)}–{_g(hi * 1e3, 4)} mN·m over the "
        "run, which the window scatter does not cover.")
    return "\n" + "\n".join(out) + "\n"


# --- section 6.4: the band ----------------------------------------------------------------

def band_table(horizon: dict | None = None) -> str:
    h = horizon or HORIZON
    rows = _band_runs(_h(horizon))
    ws_note = (f"The paper's setup, one {h['stop_time']:g} s run per case from the smooth start "
               f"(`python -m drive_rattle_cosim.band`); each cell the mean ± standard deviation "
               f"over the windows of {h['window']:g} s after the {h['transient']:g} s start "
               "transient: the ± covers the variation between windows of that run, not "
               "other starts; the cases are the band.\n\n")
    return "\n" + ws_note + band.markdown(rows, timings=False) + "\n"


#: (label, statistic, scale, unit) of the band's findings.
EFFECTS = (("drive onsets", "impacts_per_second_drive", 1.0, "/s"),
           ("coast onsets", "impacts_per_second_coast", 1.0, "/s"),
           ("median drive onset speed", "impact_speed_p50_drive", 1e3, " mm/s"),
           ("δmax", "max_penetration", 1e6, " µm"),
           ("rattle index", "impact_energy_rate", 1e3, " mW"))


def _effect(rows: dict, name: str, reference: str = "default") -> str:
    parts = []
    for label, stat, scale, unit in EFFECTS:
        new, old = rows[name].values[stat], rows[reference].values[stat]
        if not (new.n and old.n):
            continue
        beyond = abs(new.mean - old.mean) > 2.0 * max(old.std, new.std)
        parts.append(f"{label} {_g(old.mean * scale)} → {_g(new.mean * scale)}{unit} "
                     f"({_pct(new.mean, old.mean)}, {'beyond' if beyond else 'within'} twice "
                     f"the window scatter ± {_g(max(old.std, new.std) * scale, 2)})")
    return "; ".join(parts)


def _largest(rows: dict, names, reference: str = "default") -> str:
    """The largest relative change of the findings' statistics over the cases ``names``
    against ``reference``, and how many of the changes exceed twice the window scatter."""
    changes, beyond, total = [], 0, 0
    for name in names:
        for _label, stat, _scale, _unit in EFFECTS:
            new, old = rows[name].values[stat], rows[reference].values[stat]
            if new.n and old.n:
                changes.append(abs(new.mean / old.mean - 1) * 100)
                beyond += abs(new.mean - old.mean) > 2.0 * max(old.std, new.std)
                total += 1
    return (f"at most {max(changes):.0f} % (in {beyond} of {total} statistic–case pairs beyond "
            "twice the window scatter)")


def band_findings(horizon: dict | None = None) -> str:
    rows = {r.case.name: r for r in _band_runs(_h(horizon))}

    def span(stat, names, scale):
        values = [rows[n].values[stat].mean * scale for n in names if rows[n].values[stat].n]
        return f"{_g(min(values))}–{_g(max(values))}"

    dissipation = [n for n in rows if n.startswith(("squeeze", "e ", "zeta")) or n == "default"]
    out = [
        "* **Friction, measured** (against the defaults, boundary coefficient 0.1): it moves "
        "the statistics below by "
        f"{_largest(rows, ('friction off', 'boundary mu 0.05', 'boundary mu 0.15'))}. Friction "
        f"off: {_effect(rows, 'friction off')}. Boundary coefficient 0.05: "
        f"{_effect(rows, 'boundary mu 0.05')}. 0.15: {_effect(rows, 'boundary mu 0.15')}.",
        "* **The teeth's compliance** moves them by "
        f"{_largest(rows, ('rigid teeth', 'bodies 1.4', 'bodies 7'))}. Rigid teeth: "
        f"{_effect(rows, 'rigid teeth')}. Gear "
        f"bodies 1.4: {_effect(rows, 'bodies 1.4')}; 7: {_effect(rows, 'bodies 7')}.",
        "* **The dissipation** (the squeeze-film law over its range, Hunt–Crossley e = "
        "0.7–0.9, damping ratios 0.03–0.1): drive onsets "
        f"{span('impacts_per_second_drive', dissipation, 1.0)}/s, coast onsets "
        f"{span('impacts_per_second_coast', dissipation, 1.0)}/s, median drive onset speed "
        f"{span('impact_speed_p50_drive', dissipation, 1e3)} mm/s, δmax "
        f"{span('max_penetration', dissipation, 1e6)} µm, rattle index "
        f"{span('impact_energy_rate', dissipation, 1e3)} mW.",
        "* **The film**: with the EHL film "
        f"{_g(rows['Barus + EHL film'].values['psi'].mean * 100)} % of the in-contact samples "
        f"are mixed (ψ < 1), against {_g(rows['default'].values['psi'].mean * 100)} % with "
        f"eq. 11's film; its effect: {_effect(rows, 'Barus + EHL film')}.",
    ]
    return "\n" + "\n".join(out) + "\n"


# --- section 6.1: the paper's setup over the load -----------------------------------------

#: The loads of section 6.1's table [M*] and its backlash [m].
LOADS = (0.3, 0.4, 0.5, 0.6, 0.8, 1.0)
LOAD_BACKLASH = 1e-4


@lru_cache(maxsize=1)
def _load_study():
    from . import multistability

    return multistability.study(LOADS, [LOAD_BACKLASH], workers=2)


def separation_loads() -> str:
    """The multistability study's attractors over the load at the default backlash (the
    command of section 6.1, one backlash), a row per attractor, and what they show."""
    points = _load_study()
    rows = ["| load | verdict | starts | drive / coast onsets [1/s] | drive onset speed p10 / "
            "p50 / p90 [mm/s] | impact energy rate [mW] | δmax [µm] | pairs loaded |",
            "|---|---|---|---|---|---|---|---|"]
    for p in points:
        for a in p.attractors:
            m = a.mean
            rows.append(
                f"| {p.load_fraction:g} M* ({p.load:.4g} N·m) | {p.verdict} | "
                f"{len(a.starts)} of {len(p.runs)} | {m['drive_rate']:.3g} / "
                f"{m['coast_rate']:.3g} | {m['drive_p10'] * 1e3:.2g} / "
                f"{m['drive_p50'] * 1e3:.3g} / {m['drive_p90'] * 1e3:.3g} | "
                f"{m['energy_rate'] * 1e3:.3g} | {m['delta_max'] * 1e6:.3g} | "
                f"{m['pairs']:.3g} |")
        if p.unsettled:
            rows.append(f"| {p.load_fraction:g} M* | unsettled: {', '.join(p.unsettled)} "
                        "| | | | | | |")
    both = [p.load_fraction for p in points
            if all(a.mean["coast_rate"] > 0 for a in p.attractors)]
    drive_only = [p.load_fraction for p in points
                  if all(a.mean["coast_rate"] == 0 for a in p.attractors)]
    top = points[-1]
    p90 = max(a.mean["drive_p90"] for a in top.attractors) * 1e3
    multi = [f"{p.load_fraction:g} M*" for p in points if p.verdict == "multistable"]
    text = ("\n" + "\n".join(rows) + "\n\n"
            f"(`python -m drive_rattle_cosim.multistability --loads "
            f"{','.join(f'{x:g}' for x in LOADS)} --backlash {LOAD_BACKLASH:g}`.) Impacts on "
            f"both flanks (creep rattle) at {', '.join(f'{x:g}' for x in both) or 'no load'} "
            f"M*; on the drive flank only at "
            f"{', '.join(f'{x:g}' for x in drive_only) or 'no load'} M*; at "
            f"{top.load_fraction:g} M* the drive onsets' 90th percentile is {p90:.2g} mm/s. "
            + (f"Several attractors at {', '.join(multi)} (section 6.2)." if multi
               else "Every point single-valued from these starts.") + "\n")
    return text


# --- section 6.2: the compliant teeth's two states -----------------------------------------

#: The operating point of section 6.2's two states: load [M*], backlash [m], and the starts.
TWO_STATES = (0.4, 1e-4, ("smooth", "kick+1"))


@lru_cache(maxsize=1)
def two_states_point():
    """The multistability study at 0.4 M* and 0.1 mm from the smooth start and the kick of
    +1 rad/s (today's default physics; tests/analysis/test_multistability.py's point)."""
    from drive_rattle import MeshParameters

    from . import multistability as ms

    load, backlash, starts = TWO_STATES
    return ms.study_point(load, backlash, MeshParameters(),
                          starts=[ms.STARTS_BY_KEY[k] for k in starts], workers=2)


def two_states() -> str:
    """Each attractor of ``two_states_point``: its onsets per second and per forcing period,
    median drive onset speed, δmax and pairs, each with its window scatter."""
    from drive_rattle import DrivelineParameters, MeshParameters

    from . import multistability as ms

    point = two_states_point()
    period = ms.forcing_period(MeshParameters(), DrivelineParameters())

    def c(a, name, scale=1.0, digits=3):
        # a periodic orbit's windows differ by rounding only: no scatter, said as 0
        sd = a.scatter[name] if a.scatter[name] > 1e-9 * abs(a.mean[name]) else 0.0
        return f"{a.mean[name] * scale:.{digits}g} ± {sd * scale:.2g}"

    rows = ["| start | drive / coast onsets [1/s] | per forcing period | median drive onset "
            "[mm/s] | δmax [µm] | pairs loaded | windows |",
            "|---|---|---|---|---|---|---|"]
    for a in point.attractors:
        rows.append(
            f"| {', '.join(a.starts)} | {c(a, 'drive_rate')} / {c(a, 'coast_rate')} | "
            f"{a.mean['drive_rate'] * period:.3g} / {a.mean['coast_rate'] * period:.3g} | "
            f"{c(a, 'drive_p50', 1e3)} | {c(a, 'delta_max', 1e6)} | {c(a, 'pairs')} | "
            f"{a.windows} |")
    if point.unsettled:
        rows.append(f"| unsettled: {', '.join(point.unsettled)} | | | | | | |")
    load, backlash, _ = TWO_STATES
    return ("\n" + "\n".join(rows) + "\n\n"
            f"({load:g} M*, backlash {backlash * 1e3:g} mm, verdict {point.verdict}; "
            f"`multistability.study_point({load:g}, {backlash:g}, MeshParameters(), "
            "starts=[smooth, kick+1], workers=2)`, each start until its windows are "
            "stationary; mean ± scatter over the windows; the forcing period "
            f"{period * 1e3:.4g} ms.)\n")


# --- section 6.2: the compliant teeth's grid, a committed measurement --------------------

#: The grid of section 6.2 (the multistability study's default grid with 24 phases): too long
#: for a test (about ten minutes on two threads), so measured once into GRID_DATA by
#: ``python -m drive_rattle_cosim.model_doc --measure-grid`` (or reduced from that
#: command's JSON with ``--grid-from``) and rendered from there; the slow
#: tests/analysis/test_multistability.py re-measures two of its points against it.
GRID = {"loads": (0.3, 0.4, 0.5, 0.6, 0.8, 1.0), "backlash": (1e-4, 2e-4), "min_time": 20.0,
        "max_time": 60.0, "phases": 24}
GRID_COMMAND = ("python -m drive_rattle_cosim.multistability --loads "
                + ",".join(f"{x:g}" for x in GRID["loads"]) + " --backlash "
                + ",".join(f"{x:g}" for x in GRID["backlash"])
                + f" --min-time {GRID['min_time']:g} --max-time {GRID['max_time']:g} "
                f"--workers 2 --phases {GRID['phases']}")
GRID_DATA = DOC.parent / "data" / "multistability_grid.json"


def grid_starts() -> list:
    """The grid's starts: the seven named ones and the phase starts of GRID."""
    from . import multistability as ms

    return ms.with_phase_starts(list(ms.STARTS), GRID["phases"])


def grid_summary(points: list[dict], measured: str, commit: str) -> dict:
    """The data of GRID_DATA from the points of the study's JSON (``multistability.to_json``):
    per point its verdict, each attractor's starts, windows, mean and window-to-window
    scatter of every statistic, and the starts that did not settle; the runs' count and the
    sum of their times."""
    runs = [r for p in points for r in p["runs"]]
    return {
        "command": GRID_COMMAND, "measured": measured, "commit": commit,
        "runs": len(runs), "run_seconds": round(sum(r["wall"] for r in runs), 1),
        "points": [{
            "load_fraction": p["load_fraction"], "load": p["load"], "backlash": p["backlash"],
            "verdict": p["verdict"],
            "attractors": [{k: a[k] for k in ("starts", "windows", "mean", "scatter")}
                           for a in p["attractors"]],
            "unsettled": [{"start": r["start"], "seconds": r["seconds"]}
                          for r in p["runs"] if not r["settled"]]}
            for p in points]}


def _commit() -> str:
    import subprocess

    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=DOC.parent,
                              capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def write_grid(points: list[dict], path: Path = GRID_DATA) -> Path:
    """GRID_DATA from the study's JSON points, dated today, with the sources' commit."""
    import datetime
    import json

    wanted = [(f, b) for b in GRID["backlash"] for f in GRID["loads"]]
    found = [(p["load_fraction"], p["backlash"]) for p in points]
    starts = sorted(s.name for s in grid_starts())
    if found != wanted or any(sorted(r["start"] for r in p["runs"]) != starts
                              for p in points):
        raise ValueError(f"the study's points are {found} with their starts; allowed: those "
                         f"of `{GRID_COMMAND}` ({wanted}, {len(starts)} starts each)")
    data = grid_summary(points, datetime.date.today().isoformat(), _commit())
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    return path


def measure_grid(path: Path = GRID_DATA, workers: int = 2) -> Path:
    """Run GRID (the study of GRID_COMMAND) and write its data to ``path``."""
    from . import multistability as ms

    results = ms.study(GRID["loads"], GRID["backlash"], starts=grid_starts(), workers=workers,
                       min_time=GRID["min_time"], max_time=GRID["max_time"])
    return write_grid(ms.to_json(results), path)


def grid_data(path: Path = GRID_DATA) -> dict:
    import json

    return json.loads(path.read_text(encoding="utf-8"))


def compliant_grid(data: dict | None = None) -> str:
    """The committed grid (GRID_DATA) as a table, one row per attractor, and what it shows."""
    from drive_rattle import DrivelineParameters, MeshParameters

    from . import multistability as ms

    data = data or grid_data()
    period = ms.forcing_period(MeshParameters(), DrivelineParameters())

    def c(a, name, scale=1.0, digits=3):
        m, sd = a["mean"][name], a["scatter"][name]
        sd = sd if sd is not None and sd > 1e-9 * abs(m) else 0.0
        return f"{m * scale:.{digits}g} ± {sd * scale:.2g}"

    rows = ["| load | backlash [mm] | verdict | starts | drive / coast onsets [1/s] | median "
            "drive onset [mm/s] | δmax [µm] | pairs loaded |", "|---|---|---|---|---|---|---|---|"]
    points = data["points"]
    n_starts = max(sum(len(a["starts"]) for a in p["attractors"]) + len(p["unsettled"])
                   for p in points)
    for p in points:
        head = f"| {p['load_fraction']:g} M* | {p['backlash'] * 1e3:g} | {p['verdict']} |"
        for a in p["attractors"]:
            k = len(a["starts"])
            starts = (f"all {k}" if k == n_starts else f"{k}: " + ", ".join(a["starts"])
                      if k <= 6 else f"{k}: {a['starts'][0]} and {k - 1} others")
            rows.append(f"{head} {starts} | {c(a, 'drive_rate')} / {c(a, 'coast_rate')} | "
                        f"{c(a, 'drive_p50', 1e3)} | {c(a, 'delta_max', 1e6)} | "
                        f"{c(a, 'pairs')} |")
        for u in p["unsettled"]:
            rows.append(f"{head} unsettled: {u['start']} after {u['seconds']:.3g} s "
                        "| | | | |")
    single = [p for p in points if p["verdict"] == "single-valued"]
    multi = [f"{p['load_fraction']:g} M* at {p['backlash'] * 1e3:g} mm" for p in points
             if p["verdict"] == "multistable"]
    # an orbit of one onset per flank and forcing period (the rigid teeth's, below)
    one_each = [f"{p['load_fraction']:g} M* at {p['backlash'] * 1e3:g} mm" for p in points
                for a in p["attractors"]
                if all(abs(a["mean"][f] * period - 1.0) < 1e-3
                       for f in ("drive_rate", "coast_rate"))]
    return ("\n" + "\n".join(rows) + "\n\n"
            f"(`{data['command']}`: {n_starts} starts per point, {data['runs']} runs of "
            f"{GRID['min_time']:g}–{GRID['max_time']:g} s, measured on {data['measured']} at "
            f"commit {data['commit']}, the runs' times summing to {data['run_seconds']:.0f} s; "
            "each attractor's mean ± scatter over the windows of its first start; "
            f"`{GRID_DATA.relative_to(DOC.parents[1])}`, rendered by "
            "`model_doc.compliant_grid`.) "
            f"{len(single)} of the {len(points)} points single-valued"
            + (f"; multistable: {', '.join(multi)}" if multi else "")
            + ". An orbit of one onset per flank and forcing period (the rigid teeth's, "
            "below) is reached "
            + (f"at {', '.join(one_each)}" if one_each else "from no start at any point")
            + ".\n")


# --- section 6.2: the rigid teeth's orbit and the former default's two states -------------

#: The rigid teeth's orbit's point of section 6.2: load [M*], backlash [m], phase starts.
RIGID_ORBIT = (0.4, 2e-4, 24)


@lru_cache(maxsize=1)
def rigid_orbit_point():
    """The multistability study at 0.4 M* and 0.2 mm with rigid teeth (the default physics
    otherwise) from the smooth start and the phase starts of ``--phases 24``
    (tests/analysis/test_multistability.py's ``test_phase_starts_find_the_orbit_the_seven_
    starts_miss``, shared within a session)."""
    from drive_rattle import MeshParameters

    from . import multistability as ms

    load, backlash, phases = RIGID_ORBIT
    return ms.study_point(load, backlash, MeshParameters(tooth_compliance=0),
                          starts=[ms.STARTS_BY_KEY["smooth"], *ms.phase_starts(phases)],
                          workers=2)


def _is_orbit(a, period: float) -> bool:
    """One onset per flank and forcing period."""
    return all(abs(a.mean[f] * period - 1.0) < 1e-3 for f in ("drive_rate", "coast_rate"))


def rigid_orbit() -> str:
    """The attractors of ``rigid_orbit_point`` with their statistics, and which starts reach
    the orbit of one onset per flank and forcing period."""
    from drive_rattle import DrivelineParameters, MeshParameters

    from . import multistability as ms

    point = rigid_orbit_point()
    period = ms.forcing_period(MeshParameters(), DrivelineParameters())

    def c(a, name, scale=1.0, digits=3):
        sd = a.scatter[name] if a.scatter[name] > 1e-9 * abs(a.mean[name]) else 0.0
        return f"{a.mean[name] * scale:.{digits}g} ± {sd * scale:.2g}"

    rows = ["| starts | drive / coast onsets [1/s] | per forcing period | median onset drive / "
            "coast [mm/s] | δmax [µm] | pairs loaded | windows |",
            "|---|---|---|---|---|---|---|"]
    for a in point.attractors:
        k = len(a.starts)
        starts = ", ".join(a.starts) if k <= 6 else f"{k}: {a.starts[0]} and {k - 1} others"
        rows.append(
            f"| {starts} | {c(a, 'drive_rate')} / {c(a, 'coast_rate')} | "
            f"{a.mean['drive_rate'] * period:.3g} / {a.mean['coast_rate'] * period:.3g} | "
            f"{c(a, 'drive_p50', 1e3)} / {c(a, 'coast_p50', 1e3)} | "
            f"{c(a, 'delta_max', 1e6)} | {c(a, 'pairs')} | {a.windows} |")
    if point.unsettled:
        rows.append(f"| unsettled: {', '.join(point.unsettled)} | | | | | | |")
    load, backlash, phases = RIGID_ORBIT
    orbit = [s for a in point.attractors if _is_orbit(a, period) for s in a.starts]
    n_phase = len(point.runs) - 1
    reach = (f"the orbit of one onset per flank and forcing period is reached from "
             f"{len(orbit)} of the {n_phase} phase starts ({', '.join(orbit)})"
             if orbit else "no start reaches an orbit of one onset per flank and period")
    return ("\n" + "\n".join(rows) + "\n\n"
            f"({load:g} M*, backlash {backlash * 1e3:g} mm, rigid teeth, verdict "
            f"{point.verdict}; `python -m drive_rattle_cosim.multistability --loads {load:g} "
            f"--backlash {backlash:g} --starts smooth --phases {phases} --set "
            "GearMeshRattle.tooth.compliance=0`, `model_doc.rigid_orbit_point`; mean ± scatter "
            f"over the windows of each attractor's first start.) {reach[0].upper()}{reach[1:]}"
            + ("; the smooth start reaches the chaotic rattle" if "smooth" not in orbit
               else "") + ".\n")


#: The physics the former default's two states were measured with (Hunt-Crossley
#: dissipation from e = 0.8 at 4 mm/s, 10 um crowning, the exact Hertz law, friction form 0
#: on the entrainment speed, rigid teeth), pinned: the study's --set items.
HUNT_CROSSLEY_PINNED = (
    "GearMeshRattle.contact.dissipation=1", "GearMeshRattle.contact.restitution=0.8",
    "GearMeshRattle.contact.restitution_speed=0.004", "GearMeshRattle.contact.crowning=1e-5",
    "GearMeshRattle.contact.hertz_law=0", "GearMeshRattle.friction.enabled=true",
    "GearMeshRattle.friction.form=0", "GearMeshRattle.friction.shear_speed=0",
    "GearMeshRattle.gear.backlash=1e-4", "GearMeshRattle.tooth.compliance=0")
#: Its two commands: (loads, starts; None: the seven named starts).
HUNT_CROSSLEY_RUNS = (("0.4", "smooth,kick-1"), ("0.8", None))


def hunt_crossley_arguments(loads: str, starts: str, out: Path) -> list[str]:
    """The study command's arguments on the pinned physics at the default backlash."""
    args = ["--loads", loads, "--backlash", "1e-4", "--starts", starts, "--min-time", "20",
            "--max-time", "60", "--workers", "2", "--out", str(out)]
    for item in HUNT_CROSSLEY_PINNED:
        args += ["--set", item]
    return args


@lru_cache(maxsize=1)
def hunt_crossley_points() -> tuple:
    """The study command at 0.4 M* (smooth, kick -1) and 0.8 M* (the seven starts) on the
    pinned physics: per command (its JSON points, its markdown report)
    (tests/analysis/test_multistability.py's
    ``test_the_command_finds_the_second_attractor_at_0_4_and_one_at_0_8``, shared within a
    session)."""
    import contextlib
    import io
    import json
    import tempfile

    from . import multistability as ms

    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for k, (loads, starts) in enumerate(HUNT_CROSSLEY_RUNS):
            path = Path(tmp) / f"run{k}.md"
            with contextlib.redirect_stdout(io.StringIO()):
                status = ms.main(hunt_crossley_arguments(
                    loads, starts or ",".join(ms.STARTS_BY_KEY), path))
            if status:
                raise RuntimeError(f"the study command ended with status {status}")
            out.append((json.loads(path.with_suffix(".json").read_text(encoding="utf-8")),
                        path.read_text(encoding="utf-8")))
    return tuple(out)


def hunt_crossley_states() -> str:
    """What the pinned former default's two commands find, attractor by attractor."""
    parts = []
    for points, _ in hunt_crossley_points():
        for p in points:
            found = []
            for a in p["attractors"]:
                m = a["mean"]
                runs = sorted({f"{x:.3g}" for x in a["durations"].values()}, key=float)
                found.append(
                    f"{', '.join(a['starts'])}: {m['drive_rate']:.4g} / {m['coast_rate']:.3g} "
                    f"drive / coast onsets per second, δmax {m['delta_max'] * 1e6:.4g} µm "
                    f"(runs of {' or '.join(runs)} s, the longest transient "
                    f"{max(a['transients'].values()):.2g} s)")
            parts.append(f"{p['load_fraction']:g} M*, {p['backlash'] * 1e3:g} mm: "
                         f"{p['verdict']} -- " + "; ".join(found))
    return ("\n" + "\n".join(f"    * {x}" for x in parts) + "\n\n"
            "    (`python -m drive_rattle_cosim.multistability --loads L --backlash 1e-4 "
            "--starts S --min-time 20 --max-time 60 --workers 2 --set ...` with the settings "
            "`model_doc.HUNT_CROSSLEY_PINNED`, `model_doc.hunt_crossley_points`.)\n")


# --- section 6.1: the separation load ---------------------------------------------------

def separation_load() -> str:
    """The default orders, the pinion's deepest deceleration, M* and the default drag over it
    (``multistability.deepest_deceleration``, ``separation_load``)."""
    from drive_rattle import DrivelineParameters, MeshParameters

    from . import multistability as ms

    mesh, drive = MeshParameters(), DrivelineParameters()
    orders = [k for k in range(1, 5) if getattr(drive, f"amplitude_{k}")]
    a = ms.deepest_deceleration(drive)
    m_star = ms.separation_load(mesh, drive)
    return ("With the default engine orders ("
            + "/".join(f"{getattr(drive, f'order_{k}'):g}" for k in orders) + " at "
            + "/".join(f"{getattr(drive, f'amplitude_{k}'):g}" for k in orders)
            + f" rad/s²) the pinion's deepest deceleration is {a:.4g} rad/s² (tested), so a "
            f"load below\n\n    M* = I_w (z_p/z_w) · {a:.4g} rad/s² = {m_star:.4g} N·m\n\n"
            "lets the fluctuation separate the teeth quasi-statically (MODEL_NOTES §3). The "
            f"default drag is **{drive.drag / m_star:.3g} M* = {drive.drag:.4g} N·m**")


# --- section 6: the coupled system's memory ---------------------------------------------

def vehicle_mode() -> str:
    """The default driveline's vehicle mode: frequency, damping ratio and decay time
    (``DrivelineParameters().derived()``, the library's)."""
    from drive_rattle import DrivelineParameters

    d = DrivelineParameters().derived()
    return (f"f = √(k/J_v)/2π = {d['vehicle_mode_frequency']:.3g} Hz with damping ratio "
            f"ζ = (c + c_v)/(2√(k J_v)) = {d['vehicle_mode_damping_ratio'] * 100:.2g} %, so a "
            "disturbance of the vehicle's steady state decays as exp(−t/τ) with **τ = 1/(ζ ω) "
            f"= {d['vehicle_mode_decay_time']:.4g} s**")


def start_offset() -> str:
    """The wheel's mean line ahead of its coupled start angle, rho sum A_k/W_k^2 cos p_k (the
    engine orders' mean angle offset at the defaults), and the shaft torque it adds."""
    import math

    from drive_rattle import DrivelineParameters, MeshParameters

    mesh, drive = MeshParameters(), DrivelineParameters()
    ratio = mesh.z_pinion / mesh.z_wheel
    offset = ratio * sum(
        getattr(drive, f"amplitude_{k}") / (getattr(drive, f"order_{k}") * drive.w_mean) ** 2
        * math.cos(getattr(drive, f"phase_{k}")) for k in range(1, 5)
        if getattr(drive, f"amplitude_{k}"))
    torque = drive.k_shaft * offset
    return (f"ρ Σ A_k/W_k² cos p_k = {offset * 1e3:.2g} mrad ahead of its start angle (the "
            "orders' mean angle offset, ρ = z_p/z_w), so the shaft's mean torque after the "
            f"start is the drag plus k × {offset * 1e3:.2g} mrad = {torque * 1e3:+.3g} mN·m "
            f"({torque / drive.drag * 100:+.2g} %)")


#: The coupled default's long run [s] (about four periods of the vehicle mode).
MEMORY_SECONDS = 120.0


def coupled_memory(seconds: float = MEMORY_SECONDS) -> str:
    """The coupled default's load and drive onset rate in 1 s windows over ``seconds``."""
    import numpy as np

    from drive_rattle import DrivelineParameters, MeshParameters

    from .system import simulate

    drive = DrivelineParameters()
    rec = simulate(MeshParameters(), drive, stop_time=seconds, step=1e-4,
                   signals=["wheel.tau_load", "vehicle.w"])
    t = np.asarray(rec.time)
    tau = np.asarray(rec.signals["wheel.tau_load"])
    vw = np.asarray(rec.signals["vehicle.w"])
    n = round(seconds)
    edges = np.searchsorted(t, np.arange(n + 1), side="left")
    means = [float(np.mean(tau[edges[k]:edges[k + 1]])) for k in range(n)]
    onsets = np.asarray(rec.onset_times)[np.asarray(rec.onset_flanks) == 1]
    rates = np.histogram(onsets, bins=np.arange(n + 1))[0]
    half = n // 2
    late = max(means[half:]) - min(means[half:])
    early = max(means[:half]) - min(means[:half])
    vdev = float(np.max(np.abs(vw - np.mean(vw))))
    period = 1.0 / drive.derived()["vehicle_mode_frequency"]
    return (f"Measured over {seconds:g} s of the coupled default (1 s means): `wheel.tau_load` "
            f"{min(means):.4g}–{max(means):.4g} N·m around the drag {drive.drag:.4g} N·m "
            f"(the vehicle mode's period {period:.3g} s), a swing of {late * 1e3:.3g} mN·m in "
            f"the second half against {early * 1e3:.3g} in the first; the drive onsets per "
            f"second of 1 s windows range from {rates.min()} to {rates.max()} "
            f"(`vehicle.w` within ± {vdev:.2g} rad/s of its mean)")


#: The kicked coupled start's run [s] and the shortest quiet interval it reports [s].
KICK_SECONDS = 30.0
QUIET = 2.0


def kicked_coupled(seconds: float = KICK_SECONDS) -> str:
    """The coupled default started with the wheel 1 rad/s faster than the rigid speed (the
    multistability study's kick +1, its shaft in steady state behind it): the load's range
    and the intervals longer than QUIET without an onset, over ``seconds``."""
    import numpy as np

    from drive_rattle import DrivelineParameters, MeshParameters

    from . import multistability as ms
    from .system import simulate

    mesh, drive = ms.start_parameters(MeshParameters(), DrivelineParameters(),
                                      ms.STARTS_BY_KEY["kick+1"])
    rec = simulate(mesh, drive, stop_time=seconds, step=1e-4, signals=["wheel.tau_load"])
    tau = np.asarray(rec.signals["wheel.tau_load"])
    edges = np.concatenate([[0.0], np.asarray(rec.onset_times), [seconds]])
    quiet = [(a, b) for a, b in itertools.pairwise(edges) if b - a > QUIET]
    spans = (("with no onset " + " and ".join(f"from {a:.3g} to {b:.3g} s" for a, b in quiet))
             if quiet else f"with no interval of more than {QUIET:g} s without an onset")
    low, high = (f"{x:+.2f}".replace("-", "−") for x in (tau.min(), tau.max()))
    return (f"measured over {seconds:g} s: the load swings between {low} and {high} N·m "
            f"({abs(tau.min()) / drive.drag:.3g} and "
            f"{tau.max() / drive.drag:.3g} times the drag), {spans} "
            f"(`model_doc.kicked_coupled`, the compiled loop at 1e-4 s)")


#: name -> function giving the block's text.
BLOCKS: dict[str, Callable[[], str]] = {
    "mixed regime": mixed_regime,
    "reference pair": reference_pair,
    "crown radius": crown_radius,
    "eq6 radius": eq6_radius,
    "eq6 laws": eq6_laws,
    "line lengths": line_lengths,
    "half lines": half_lines,
    "crowned laws": crowned_laws,
    "single impacts": lambda: "\n" + squeeze_impacts.table() + "\n",
    "dissipation constants": dissipation_constants,
    "mesh stiffness": lambda: "\n" + mesh_stiffness.report() + "\n",
    "contact options": contact_options,
    "contact findings": contact_findings,
    "paper comparison": paper_comparison,
    "paper findings": paper_findings,
    "band": band_table,
    "band findings": band_findings,
    "coupled memory": coupled_memory,
    "separation load": separation_load,
    "vehicle mode": vehicle_mode,
    "start offset": start_offset,
    "separation loads": separation_loads,
    "two states": two_states,
    "compliant grid": compliant_grid,
    "rigid orbit": rigid_orbit,
    "hunt-crossley states": hunt_crossley_states,
    "kicked coupled": kicked_coupled,
}


# --- docs/analysis.md section 5: what the default run shows -------------------------------

def default_run(horizon: dict | None = None) -> str:
    """The comparison table and the further statistics of the default model in the paper's
    setup, as examples/paper_scenario.py writes them from the FMUs (the compiled loop's
    numbers are theirs, bit for bit)."""
    from .analysis import further_statistics, markdown_table
    from .analysis import paper_comparison as comparison

    paper, _, _ = _paper_runs(_h(horizon))
    ws = paper[0].central.statistics
    return ("\n" + markdown_table(comparison(ws), headers=(
        "quantity", "this run: mean ± scatter (min–max over windows)", "paper")) + "\n"
        + markdown_table(further_statistics(ws), headers=("further statistics", "this run"))
        + "\n")


#: name -> function giving the block's text, in docs/analysis.md.
ANALYSIS_BLOCKS: dict[str, Callable[[], str]] = {"default run": default_run}
#: Each document and its blocks.
DOCUMENTS = {"model.md": BLOCKS, "analysis.md": ANALYSIS_BLOCKS}
_BLOCK = re.compile(r"<!-- BEGIN (?P<name>[^>]+?) -->(?P<body>.*?)<!-- END (?P=name) -->", re.S)


def blocks_in(text: str) -> dict[str, str]:
    return {m["name"]: m["body"] for m in _BLOCK.finditer(text)}


def compute(names, blocks=None) -> dict[str, str]:
    blocks = BLOCKS if blocks is None else blocks
    return {name: blocks[name]() for name in dict.fromkeys(names)}


def update(text: str, computed: dict[str, str] | None = None, blocks=None) -> str:
    """``text`` with every block's body replaced by its computed text; ValueError when a
    block of ``blocks`` (default ``BLOCKS``, docs/model.md's) is missing or the text has a
    block ``blocks`` lacks."""
    blocks = BLOCKS if blocks is None else blocks
    found = blocks_in(text)
    missing = sorted(set(blocks) - set(found))
    unknown = sorted(set(found) - set(blocks))
    if missing or unknown:
        raise ValueError(f"the document's blocks: missing {', '.join(missing) or 'none'}, "
                         f"unknown {', '.join(unknown) or 'none'}; allowed: exactly "
                         f"{', '.join(blocks)}")
    computed = computed if computed is not None else compute(found, blocks)
    return _BLOCK.sub(lambda m: f"<!-- BEGIN {m['name']} -->{computed[m['name']]}"
                                f"<!-- END {m['name']} -->", text)


def stale(text: str, names=None, blocks=None) -> list[str]:
    """The names of the blocks of ``text`` (or of ``names`` only) whose body differs from a
    fresh computation (``blocks``: default ``BLOCKS``, docs/model.md's)."""
    blocks = BLOCKS if blocks is None else blocks
    bodies = blocks_in(text)
    names = list(bodies) if names is None else list(names)
    return [n for n in names if bodies[n] != blocks[n]()]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m drive_rattle_cosim.model_doc",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("--update", action="store_true",
                    help="rewrite the documents' blocks (else: name the stale ones)")
    ap.add_argument("--only", action="append", metavar="NAME",
                    help="with --update: rewrite only this block (repeatable; the others kept)")
    ap.add_argument("--doc", type=Path, action="append",
                    help="a document (docs/model.md or docs/analysis.md; default both)")
    ap.add_argument("--measure-grid", action="store_true",
                    help=f"run section 6.2's grid (about ten minutes) into {GRID_DATA.name}")
    ap.add_argument("--grid-from", type=Path, metavar="JSON",
                    help=f"write {GRID_DATA.name} from the JSON of `{GRID_COMMAND} --out X`")
    args = ap.parse_args(argv)
    if args.measure_grid or args.grid_from:
        import json

        try:
            path = (write_grid(json.loads(args.grid_from.read_text(encoding="utf-8")))
                    if args.grid_from else measure_grid())
        except (OSError, ValueError) as err:
            print(f"model_doc: {err}", file=sys.stderr)
            return 1
        print(f"wrote {path}")
        return 0
    stale_names = []
    for doc in args.doc or [DOC, ANALYSIS_DOC]:
        blocks = DOCUMENTS.get(doc.name, BLOCKS)
        try:
            text = doc.read_text(encoding="utf-8")
            if args.update:
                computed = None
                if args.only:
                    computed = blocks_in(text)
                    computed.update(compute([n for n in args.only if n in blocks], blocks))
                doc.write_text(update(text, computed, blocks=blocks), encoding="utf-8")
                print(f"updated {doc}")
                continue
        except (OSError, ValueError) as err:
            print(f"model_doc: {doc}: {err}", file=sys.stderr)
            return 1
        stale_names += [f"{doc.name}: {n}" for n in stale(text, blocks=blocks)]
    if not args.update:
        print("stale: " + ", ".join(stale_names) if stale_names else "every block is current")
    return 1 if stale_names else 0


if __name__ == "__main__":
    sys.exit(main())
