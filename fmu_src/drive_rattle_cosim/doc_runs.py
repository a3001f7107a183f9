"""The numbers of docs/model.md and docs/analysis.md that are runs: co-simulation statistics of
the paper's setup and the coupled driveline (the contact options, the films, the band, the
paper comparison, the coupled system's memory) and the multistability study's attractors, each
the text of one block of ``model_doc.BLOCKS`` or ``model_doc.ANALYSIS_BLOCKS``.

The runs are the model library's compiled loop (the FMUs' numbers bit for bit), deterministic:
the same text on every machine with the same library.  Section 6.2's grid of the compliant
teeth with 24 phases (minutes of runs), and section 6.1's table of its rows at the default
backlash, are rendered from the data committed in docs/data/multistability_grid.json, which
``python -m drive_rattle_cosim.model_doc --measure-grid`` measures again (``measure_grid``;
``--grid-from`` reduces it from the JSON of the study's command, ``write_grid``); the slow
tests/analysis/test_multistability.py measures two of its points again against it.
"""

from __future__ import annotations

import itertools
from functools import lru_cache
from pathlib import Path

from . import band, contact_laws, paper_models
from .analysis import PAPER_FIGURES
from .doc_constants import JOHNSON_ALPHA

#: The repository's docs folder (the grid's data lives under it).
DOCS = Path(__file__).resolve().parents[2] / "docs"
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
        + ("above" if min(ratios) > JOHNSON_ALPHA else "not everywhere above")
        + f" the {JOHNSON_ALPHA:g} below which a smooth-surface law holds (section 3.5).\n")


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

#: The backlash of section 6.1's table [m]: the default's, the first of the grid's (section
#: 6.2), whose rows at it the table shows.
LOAD_BACKLASH = 1e-4


def separation_loads(data: dict | None = None) -> str:
    """The attractors of the committed grid (GRID_DATA, section 6.2) over the load at the
    default backlash, a row per attractor with its onset statistics, and what they show.  The
    grid runs these loads from every start of the table's study and more (the phase starts),
    so the table is read from its data rather than run a second time."""
    data = data or grid_data()
    points = [p for p in data["points"] if p["backlash"] == LOAD_BACKLASH]
    if not points:
        raise ValueError(f"the grid's data has no point at backlash {LOAD_BACKLASH:g} m; "
                         f"allowed: the backlashes of `{GRID_COMMAND}`")
    rows = ["| load | verdict | starts | drive / coast onsets [1/s] | drive onset speed p10 / "
            "p50 / p90 [mm/s] | impact energy rate [mW] | δmax [µm] | pairs loaded |",
            "|---|---|---|---|---|---|---|---|"]
    for p in points:
        n = sum(len(a["starts"]) for a in p["attractors"]) + len(p["unsettled"])
        for a in p["attractors"]:
            m = a["mean"]
            rows.append(
                f"| {p['load_fraction']:g} M* ({p['load']:.4g} N·m) | {p['verdict']} | "
                f"{len(a['starts'])} of {n} | {m['drive_rate']:.3g} / "
                f"{m['coast_rate']:.3g} | {m['drive_p10'] * 1e3:.2g} / "
                f"{m['drive_p50'] * 1e3:.3g} / {m['drive_p90'] * 1e3:.3g} | "
                f"{m['energy_rate'] * 1e3:.3g} | {m['delta_max'] * 1e6:.3g} | "
                f"{m['pairs']:.3g} |")
        for u in p["unsettled"]:
            rows.append(f"| {p['load_fraction']:g} M* | unsettled: {u['start']} after "
                        f"{u['seconds']:.3g} s | | | | | | |")
    both = [p["load_fraction"] for p in points
            if all(a["mean"]["coast_rate"] > 0 for a in p["attractors"])]
    drive_only = [p["load_fraction"] for p in points
                  if all(a["mean"]["coast_rate"] == 0 for a in p["attractors"])]
    top = points[-1]
    p90 = max(a["mean"]["drive_p90"] for a in top["attractors"]) * 1e3
    multi = [f"{p['load_fraction']:g} M*" for p in points if p["verdict"] == "multistable"]
    return ("\n" + "\n".join(rows) + "\n\n"
            f"(The rows at {LOAD_BACKLASH * 1e3:g} mm of `{data['command']}`, measured on "
            f"{data['measured']} at commit {data['commit']}: "
            f"`{GRID_DATA.relative_to(DOCS.parent)}`, rendered by "
            "`doc_runs.separation_loads`.) Impacts on "
            f"both flanks (creep rattle) at {', '.join(f'{x:g}' for x in both) or 'no load'} "
            f"M*; on the drive flank only at "
            f"{', '.join(f'{x:g}' for x in drive_only) or 'no load'} M*; at "
            f"{top['load_fraction']:g} M* the drive onsets' 90th percentile is {p90:.2g} mm/s. "
            + (f"Several attractors at {', '.join(multi)} (section 6.2)." if multi
               else "Every point single-valued from these starts.") + "\n")


# --- section 6.2: the compliant teeth's two states -----------------------------------------

#: The operating point of section 6.2's two states: load [M*], backlash [m], and the starts.
TWO_STATES = (0.4, 1e-4, ("smooth", "kick+1"))


def _mean_and_scatter(mean: dict, scatter: dict, name: str, scale: float = 1.0) -> str:
    """An attractor's statistic ``name`` as "mean ± window scatter" (times ``scale``); a
    periodic orbit's windows differ by rounding only, so a scatter below 1e-9 of the mean (or
    none recorded) is said as 0."""
    m, sd = mean[name], scatter[name]
    sd = sd if sd is not None and sd > 1e-9 * abs(m) else 0.0
    return f"{m * scale:.3g} ± {sd * scale:.2g}"


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

    def c(a, name, scale=1.0):  # an attractor of the study
        return _mean_and_scatter(a.mean, a.scatter, name, scale)

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
GRID_DATA = DOCS / "data" / "multistability_grid.json"


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
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=DOCS,
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

    def c(a, name, scale=1.0):  # an attractor of the data (a dict)
        return _mean_and_scatter(a["mean"], a["scatter"], name, scale)

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
            f"`{GRID_DATA.relative_to(DOCS.parent)}`, rendered by "
            "`doc_runs.compliant_grid`.) "
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

    def c(a, name, scale=1.0):  # an attractor of the study
        return _mean_and_scatter(a.mean, a.scatter, name, scale)

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
            "GearMeshRattle.tooth.compliance=0`, `doc_runs.rigid_orbit_point`; mean ± scatter "
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
            "`doc_runs.HUNT_CROSSLEY_PINNED`, `doc_runs.hunt_crossley_points`.)\n")



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
            f"(`doc_runs.kicked_coupled`, the compiled loop at 1e-4 s)")



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
