"""A mutation run: FMUs of both flavours built from the model library
with an injected defect (mutants.py) -- every step refused, a NaN output answered with fmi2OK,
a half-applied fmi2SetReal -- and the boundary rows and the fuzzer run against them.  Each
defect must be caught by at least one row, by the fuzzer, and by the fuzzer without its
shadow library (what it asserts whatever the model: valid calls succeed, no non-finite
output with OK, a refused call changes nothing).  Which row and which fuzzer check caught
each one is printed (pytest -s)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from .mutants import MUTANTS, SANITIZER_MUTANTS
from .variants import rebuild

HERE = Path(__file__).resolve().parent
#: A fixed seed and few examples: each mutant fails at its first chance (no shrinking).
FUZZ_SEED, FUZZ_EXAMPLES = 20, 40


def _child(args: list, timeout: float = 600) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(HERE), *(
        os.path.abspath(p) for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p)])}
    return subprocess.run([sys.executable, *map(str, args)], capture_output=True, text=True,
                          timeout=timeout, cwd=HERE, env=env)


@pytest.fixture(scope="module", params=("pythonfmu", "native"))
def mutant_fmus(request, tmp_path_factory) -> dict:
    """{mutant: {model: FMU}} of one flavour."""
    flavour = request.param
    built = request.getfixturevalue("fmus" if flavour == "pythonfmu" else "native_fmus")
    root = tmp_path_factory.mktemp(f"mutants_{flavour}")
    return {"flavour": flavour, **{
        name: {model: rebuild(built[model], root / name, patches=patches)
               for model in ("GearMeshRattle", "Driveline")}
        for name, (patches, _) in MUTANTS.items()}}


def test_every_mutant_finds_the_text_it_patches_once():
    """Each defect's patch (and the sanitizer's) names text that is in today's sources exactly
    once: checked here in the fast layer, since the mutants are built only in the slow one."""
    source = Path(__file__).resolve().parents[2] / "fmu_src" / "rattle_model"
    counts = {(name, file, old[:60]): (source / file).read_text(encoding="utf-8").count(old)
              for name, (patches, _) in {**MUTANTS, **SANITIZER_MUTANTS}.items()
              for file, old, _new in patches}
    assert {key: n for key, n in counts.items() if n != 1} == {}


def _first_failure(stderr: str) -> str:
    """The fuzzer's failed check: the first line of its AssertionError."""
    match = re.search(r"AssertionError: (.*)", stderr)
    return match.group(1)[:200] if match else stderr.strip().splitlines()[-1][:200]


@pytest.mark.slow
@pytest.mark.parametrize("mutant", list(MUTANTS))
def test_the_rows_and_the_fuzzer_catch_the_mutant(mutant_fmus, mutant, tmp_path):
    fmus = mutant_fmus[mutant]
    flavour = mutant_fmus["flavour"]
    rows = _child([HERE / "boundary_rows.py", "all", fmus["GearMeshRattle"], fmus["Driveline"],
                   tmp_path / "rows", "--keep-going"])
    caught = re.findall(r"row (\d+) FAILED: (.*)", rows.stdout)
    assert rows.returncode > 0 and caught, (
        f"no row caught the mutant {mutant} ({MUTANTS[mutant][1]}) in the {flavour} FMUs "
        f"(exit {rows.returncode})\n{rows.stdout}\n{rows.stderr[-3000:]}")
    found = {}
    for mode in ("--with-shadow", "--no-shadow"):
        fuzz = _child([HERE / "boundary_fuzz.py", fmus["GearMeshRattle"], FUZZ_EXAMPLES,
                       FUZZ_SEED, tmp_path / mode.strip("-"), "--no-shrink", mode])
        assert fuzz.returncode > 0, (
            f"the fuzzer ({mode}) did not catch the mutant {mutant} ({MUTANTS[mutant][1]}) in "
            f"the {flavour} GearMeshRattle:\n{fuzz.stdout[-2000:]}")
        found[mode] = _first_failure(fuzz.stderr)
    print(f"\nmutant {mutant} ({flavour}): rows {[int(k) for k, _ in caught]} failed "
          f"(row {caught[0][0]}: {caught[0][1][:120]}); fuzzer: {found['--with-shadow']}; "
          f"fuzzer without its shadow: {found['--no-shadow']}")
