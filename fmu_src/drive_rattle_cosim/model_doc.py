"""The numbers of docs/model.md, computed: every ``<!-- BEGIN name -->...<!-- END name -->``
block of the document is the output of ``BLOCKS[name]``, written by
``python -m drive_rattle_cosim.model_doc --update`` (``update``) and held against a fresh
computation by tests/cosim/test_model_doc.py (``stale``).  After a change of the default physics,
run that command and review the diff: the findings written around the tables are generated
from the same runs, so a sentence that no longer holds changes with its numbers.

The runs are the model library's compiled loop (the FMUs' numbers bit for bit), deterministic:
the same text on every machine with the same library.
"""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Callable
from functools import lru_cache
from pathlib import Path

from . import band, contact_laws, mesh_stiffness, paper_models
from .analysis import PAPER_FIGURES

DOC = Path(__file__).resolve().parents[2] / "docs" / "model.md"
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
        + ".\n")


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
    rows = _band_runs(_h(horizon))
    ws_note = (f"The paper's setup, {HORIZON['stop_time'] if horizon is None else horizon['stop_time']:g}"
               " s per case (`python -m drive_rattle_cosim.band`):\n\n")
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


#: name -> function giving the block's text.
BLOCKS: dict[str, Callable[[], str]] = {
    "mesh stiffness": lambda: "\n" + mesh_stiffness.report() + "\n",
    "contact options": contact_options,
    "contact findings": contact_findings,
    "paper comparison": paper_comparison,
    "paper findings": paper_findings,
    "band": band_table,
    "band findings": band_findings,
}
_BLOCK = re.compile(r"<!-- BEGIN (?P<name>[^>]+?) -->(?P<body>.*?)<!-- END (?P=name) -->", re.S)


def blocks_in(text: str) -> dict[str, str]:
    return {m["name"]: m["body"] for m in _BLOCK.finditer(text)}


def compute(names) -> dict[str, str]:
    return {name: BLOCKS[name]() for name in dict.fromkeys(names)}


def update(text: str, computed: dict[str, str] | None = None) -> str:
    """``text`` with every block's body replaced by its computed text; ValueError when a
    block of ``BLOCKS`` is missing or the text has a block ``BLOCKS`` lacks."""
    found = blocks_in(text)
    missing = sorted(set(BLOCKS) - set(found))
    unknown = sorted(set(found) - set(BLOCKS))
    if missing or unknown:
        raise ValueError(f"docs/model.md's blocks: missing {', '.join(missing) or 'none'}, "
                         f"unknown {', '.join(unknown) or 'none'}; allowed: exactly "
                         f"{', '.join(BLOCKS)}")
    computed = computed if computed is not None else compute(found)
    return _BLOCK.sub(lambda m: f"<!-- BEGIN {m['name']} -->{computed[m['name']]}"
                                f"<!-- END {m['name']} -->", text)


def stale(text: str, names=None) -> list[str]:
    """The names of the blocks of ``text`` (or of ``names`` only) whose body differs from a
    fresh computation."""
    bodies = blocks_in(text)
    names = list(bodies) if names is None else list(names)
    return [n for n in names if bodies[n] != BLOCKS[n]()]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m drive_rattle_cosim.model_doc",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("--update", action="store_true", help="rewrite docs/model.md's blocks")
    ap.add_argument("--doc", type=Path, default=DOC, help="the document (docs/model.md)")
    args = ap.parse_args(argv)
    try:
        text = args.doc.read_text(encoding="utf-8")
        if args.update:
            args.doc.write_text(update(text), encoding="utf-8")
            print(f"updated {args.doc}")
            return 0
    except (OSError, ValueError) as err:
        print(f"model_doc: {err}", file=sys.stderr)
        return 1
    names = stale(text)
    print("stale: " + ", ".join(names) if names else "every block is current")
    return 1 if names else 0


if __name__ == "__main__":
    sys.exit(main())
