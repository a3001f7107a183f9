"""The boundary rows and the boundary fuzzer (tests/adversarial) against sanitizer builds of
every face: the native FMI 2.0 and FMI 3.0 FMUs' binaries and the pythonfmu FMUs' model
library and status shim compiled with AddressSanitizer and UndefinedBehaviorSanitizer
(-fno-sanitize-recover=all), driven by a Python host with the runtime preloaded
(sanitized_child.py).  Any memory error or undefined behaviour, and any leak of memory the
project's C allocated (checked after the host freed its instances), fails the test.  The
fuzzer's expected model (its shadow library unit) is the sanitized library too."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from ..adversarial.variants import rebuild
from ..faces.conftest import FACES
from ..seeds import fuzz_seed
from .sanitizers import ASAN_FLAGS, python_environment, python_reports

pytestmark = pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc is needed")

HERE = Path(__file__).resolve().parent
ADVERSARIAL = HERE.parent / "adversarial"
CHILD = HERE / "sanitized_child.py"
#: Fuzzer examples per FMU under the sanitizers (about 1500 calls; 250 in tests/adversarial).
FUZZ_EXAMPLES = 60
MODELS = ("GearMeshRattle", "Driveline")


@pytest.fixture(scope="module", params=list(FACES))
def sanitized(request, tmp_path_factory) -> dict:
    """{model: FMU} of one face, its C compiled with the sanitizers; "library": the
    sanitized model library (the pythonfmu FMUs ship it; the fuzzer's shadow loads it)."""
    from ..adversarial.variants import model_library

    flavour = request.param
    built = request.getfixturevalue(FACES[flavour].fixture)
    out = tmp_path_factory.mktemp(f"sanitized_{flavour}")
    # one sanitized library for the faces this process runs (the pythonfmu FMUs ship it; the
    # native faces' shadow loads it), compiled once: model_library keeps it while its
    # sources and flags are the same
    library = model_library(tmp_path_factory.getbasetemp() / "sanitized_library" /
                            "rattle_model.so", ASAN_FLAGS)
    fmus = {model: rebuild(built[model], out, ASAN_FLAGS,
                           shim_flags=ASAN_FLAGS if flavour == "pythonfmu" else None,
                           library=library)
            for model in MODELS}
    return {**fmus, "library": library, "flavour": flavour}


def _run(args: list, tmp_path: Path, timeout: float, extra_env: dict | None = None):
    logs = tmp_path / "sanitizer-logs"
    env = python_environment(logs, {
        "PYTHONPATH": os.pathsep.join([str(ADVERSARIAL), *(
            os.path.abspath(p) for p in os.environ.get("PYTHONPATH", "").split(os.pathsep)
            if p)]),
        **(extra_env or {})})
    run = subprocess.run([sys.executable, str(CHILD), *map(str, args)], capture_output=True,
                         text=True, timeout=timeout, cwd=ADVERSARIAL, env=env)
    return run, python_reports(logs)


def _explain(run, reports) -> str:
    return (f"exit code {run.returncode}{' (the host crashed)' if run.returncode < 0 else ''}"
            f"\nsanitizer reports:\n" + "\n".join(reports[:5])
            + f"\nstdout (end):\n{run.stdout[-2000:]}\nstderr (end):\n"
            + "\n".join(line for line in run.stderr.splitlines()
                        if not line.startswith("CALL "))[-5000:])


@pytest.mark.slow
def test_every_row_under_the_sanitizers(sanitized, tmp_path):
    run, reports = _run([ADVERSARIAL / "boundary_rows.py", "all", sanitized["GearMeshRattle"],
                         sanitized["Driveline"], tmp_path / "work"], tmp_path, 900)
    assert run.returncode == 0 and not reports, _explain(run, reports)
    from ..adversarial.test_fmi_boundary import ROWS

    assert all(f"row {row} ok" in run.stdout for row in ROWS), run.stdout
    assert "sanitized_child: leak check" in run.stderr  # it ran (what it found: above)


@pytest.mark.slow
@pytest.mark.seeded
@pytest.mark.parametrize("model", MODELS)
def test_the_fuzzer_under_the_sanitizers(sanitized, model, tmp_path):
    """Random call sequences from the unit's fixed seed (tests/seeds.py; RATTLE_FUZZ_SEED
    replaces it), the FMU and its shadow both sanitized."""
    seed = fuzz_seed(model)
    run, reports = _run([ADVERSARIAL / "boundary_fuzz.py", sanitized[model], FUZZ_EXAMPLES,
                         seed, tmp_path / "work"], tmp_path, 900,
                        {"RATTLE_MODEL_LIBRARY": str(sanitized["library"])})
    assert run.returncode == 0 and not reports, (
        f"the fuzzer under the sanitizers failed on {sanitized['flavour']} {model} with "
        f"RATTLE_FUZZ_SEED={seed}: " + _explain(run, reports))
    summary = json.loads(run.stdout.strip().splitlines()[-1])
    print(f"sanitized fuzzer {sanitized['flavour']} {model}: seed {seed}, {summary['calls']} "
          f"calls, {summary['compared with the library']} held against the library, "
          f"state calls {summary['counts']}")
    assert summary["calls"] >= 500 and "sanitized_child: leak check" in run.stderr


@pytest.mark.slow
@pytest.mark.parametrize("defect", ["leak", "overflow"])
def test_a_sanitized_run_reports_a_leak_and_an_overflow(fmus, defect, tmp_path):
    """The pipeline itself: the pythonfmu FMUs with a library that leaks rm_save's buffer, or
    writes a string's copy one byte past its allocation (tests/adversarial/mutants.py), give
    the right answers -- and the sanitized run of row 7 (states saved and restored, a speed
    table's name) reports the defect."""
    from ..adversarial.mutants import SANITIZER_MUTANTS

    patches, _ = SANITIZER_MUTANTS[defect]
    out = tmp_path / "fmus"
    built = {model: rebuild(fmus[model], out, ASAN_FLAGS, patches, shim_flags=ASAN_FLAGS)
             for model in MODELS}
    run, reports = _run([ADVERSARIAL / "boundary_rows.py", "7", built["GearMeshRattle"],
                         built["Driveline"], tmp_path / "work"], tmp_path, 600)
    expected = {"leak": "in write_raw", "overflow": "heap-buffer-overflow"}[defect]
    assert any(expected in report for report in reports), _explain(run, reports)
