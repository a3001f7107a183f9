"""The numbers of docs/model.md (and of docs/analysis.md's runs), computed: every ``<!-- BEGIN
name -->...<!-- END name -->`` block of docs/model.md is the output of ``BLOCKS[name]``, of
docs/analysis.md of ``ANALYSIS_BLOCKS[name]``, written by ``python -m
drive_rattle_cosim.model_doc --update`` (``update``; ``--only NAME`` rewrites one block and
keeps the others) and held against a fresh computation by
tests/cosim/test_model_doc.py (``stale``).  After a change of the default physics,
run that command and review the diff: the findings written around the tables are generated
from the same runs, so a sentence that no longer holds changes with its numbers.

This module is the registry and the command; the blocks are computed by two modules by job:
``doc_constants`` the closed forms (the model's laws and derived quantities at the default
parameters, static equilibria; ``CONSTANT_BLOCKS``, about two seconds) and ``doc_runs`` the
runs (co-simulation statistics and the multistability study; ``RUN_BLOCKS``, minutes).  Two
run blocks are not run on update: section 6.2's grid and section 6.1's table of its rows at the
default backlash are rendered from the data committed in docs/data/multistability_grid.json,
which ``--measure-grid`` measures again (or ``--grid-from`` reduces from the JSON of the
study's command).
"""

from __future__ import annotations

import argparse
import re
import sys
from collections.abc import Callable
from pathlib import Path

from . import doc_constants as const
from . import doc_runs as runs
from . import mesh_stiffness, squeeze_impacts

DOC = runs.DOCS / "model.md"
ANALYSIS_DOC = runs.DOCS / "analysis.md"

#: name -> function giving the block's text: the closed forms at the defaults.
CONSTANT_BLOCKS: dict[str, Callable[[], str]] = {
    "reference pair": const.reference_pair,
    "crown radius": const.crown_radius,
    "eq6 radius": const.eq6_radius,
    "eq6 laws": const.eq6_laws,
    "line lengths": const.line_lengths,
    "half lines": const.half_lines,
    "paper ellipse": const.paper_ellipse,
    "crowned laws": const.crowned_laws,
    "sphere at ratio": const.sphere_at_ratio,
    "crowned ellipse": const.crowned_ellipse,
    "dissipation constants": const.dissipation_constants,
    "line statics": const.line_statics,
    "smooth approaches": const.smooth_approaches,
    "layer approach": const.layer_approach,
    "roughness parameter": const.roughness_parameter,
    "roughness deficit": const.roughness_deficit,
    "plasticity index": const.plasticity_index,
    "mesh stiffness": lambda: "\n" + mesh_stiffness.report() + "\n",
    "rigid stiffness": const.rigid_stiffness,
    "barus factor": const.barus_factor,
    "ehl ellipticity": const.ehl_ellipticity,
    "ehl film": const.ehl_film,
    "mixed friction": const.mixed_friction,
    "form jump": const.form_jump,
    "form 1 coefficient": const.form_one_coefficient,
    "eq7 film": const.eq7_film,
    "boundary friction": const.boundary_friction,
    "sliding acceleration": const.sliding_acceleration,
    "extrapolation error": const.extrapolation_error,
    "backlash angle": const.backlash_angle,
    "vehicle mode": const.vehicle_mode,
    "start offset": const.start_offset,
    "shaft damping": const.shaft_damping,
    "vehicle damping": const.vehicle_damping,
    "separation load": const.separation_load,
    "order frequencies": const.order_frequencies,
}
#: name -> function giving the block's text: the runs.
RUN_BLOCKS: dict[str, Callable[[], str]] = {
    "single impacts": lambda: "\n" + squeeze_impacts.table() + "\n",
    "contact options": runs.contact_options,
    "contact findings": runs.contact_findings,
    "mixed regime": runs.mixed_regime,
    "coupled memory": runs.coupled_memory,
    "kicked coupled": runs.kicked_coupled,
    "separation loads": runs.separation_loads,
    "two states": runs.two_states,
    "compliant grid": runs.compliant_grid,
    "rigid orbit": runs.rigid_orbit,
    "hunt-crossley states": runs.hunt_crossley_states,
    "paper comparison": runs.paper_comparison,
    "paper findings": runs.paper_findings,
    "band": runs.band_table,
    "band findings": runs.band_findings,
}
#: Every block of docs/model.md.
BLOCKS: dict[str, Callable[[], str]] = {**CONSTANT_BLOCKS, **RUN_BLOCKS}
#: name -> function giving the block's text, in docs/analysis.md.
ANALYSIS_BLOCKS: dict[str, Callable[[], str]] = {"default run": runs.default_run}
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
                    help=f"run section 6.2's grid (about ten minutes) into {runs.GRID_DATA.name}")
    ap.add_argument("--grid-from", type=Path, metavar="JSON",
                    help=f"write {runs.GRID_DATA.name} from the JSON of "
                         f"`{runs.GRID_COMMAND} --out X`")
    args = ap.parse_args(argv)
    if args.measure_grid or args.grid_from:
        import json

        try:
            path = (runs.write_grid(json.loads(args.grid_from.read_text(encoding="utf-8")))
                    if args.grid_from else runs.measure_grid())
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
