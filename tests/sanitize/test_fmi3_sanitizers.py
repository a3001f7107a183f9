"""The FMI 3.0 face (fmu_src/fmi3/fmi3_functions.c) with the model library under
AddressSanitizer and UndefinedBehaviorSanitizer: each unit's binary compiled from the sources
the FMI 3.0 FMU ships, driven by the C host tests/faces/fmu_host.c (its FMI 3.0 adapter) over
the regression inputs (with and without a resources folder) and by fmi3_abuse.c's bad calls.
A report, a leak or a crash fails the test."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from drive_rattle.catalog import UNITS
from drive_rattle.interface import MODELS
from drive_rattle.parameters import specs
from drive_rattle_build.fmi3 import fmi3_token, stage_sources
from drive_rattle_build.model_description import variable_rows
from drive_rattle_build.model_description_fmi3 import is_enumeration, time_value_reference
from drive_rattle_build.native import RESOURCE_MARKER
from drive_rattle_cosim.regression import reference_files

from ..faces.hosts import ADAPTER, HOST_SOURCE
from ..faces.twin import bits, input_rows, twin_run
from .sanitizers import ASAN_FLAGS, IEEE, SANITIZE, reports

pytestmark = pytest.mark.slow


def build(model: str, folder: Path) -> tuple[Path, Path]:
    """The unit's FMI 3.0 binary with ASAN and UBSAN, and a resources folder with its marker."""
    sources = folder / "sources"
    stage_sources(model, fmi3_token(model), sources)
    binary = folder / f"{model}.so"
    cmd = ["gcc", *IEEE, *ASAN_FLAGS, "-Werror", "-fPIC", "-shared", "-I", str(sources), "-o",
           str(binary), *(str(s) for s in sorted(sources.glob("*.c"))), "-lm"]
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, f"{' '.join(cmd)}\n{run.stderr}"
    resources = folder / "resources"
    resources.mkdir(exist_ok=True)
    (resources / RESOURCE_MARKER).write_text(f"{model}\n", encoding="utf-8")
    return binary, resources


def program(exe: Path, source: Path, defines=()) -> Path:
    from drive_rattle_build.fmi3 import fmi3_headers

    cmd = ["gcc", "-std=c99", *ASAN_FLAGS, *defines, "-I", str(fmi3_headers()), "-o", str(exe),
           str(source), "-ldl", "-lm"]
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, f"{' '.join(cmd)}\n{run.stderr}"
    return exe


@pytest.fixture(scope="module")
def asan(tmp_path_factory):
    root = tmp_path_factory.mktemp("asan3")
    units = {model: build(model, root / model) for model in MODELS}
    host = program(root / "fmu_host", HOST_SOURCE, ADAPTER["3.0"])
    abuse = program(root / "fmi3_abuse", Path(__file__).with_name("fmi3_abuse.c"))
    return units, host, abuse


def assert_clean(run: subprocess.CompletedProcess) -> None:
    found = reports(run.stdout + run.stderr)
    assert not found and run.returncode == 0, (
        f"exit {run.returncode}; sanitizer reports:\n" + "\n".join(found[:20])
        + f"\n--- stdout (end)\n{run.stdout[-3000:]}\n--- stderr (end)\n{run.stderr[-6000:]}")


@pytest.mark.parametrize("model", MODELS)
def test_host_over_the_regression_inputs_under_asan(asan, model, tmp_path):
    units, host, _ = asan
    binary, resources = units[model]
    rows = variable_rows(model)
    inputs = [(vr, r[0]) for vr, r in enumerate(rows) if r[1] == "input"]
    outputs = [(vr, r[0], r[2].fmi_type) for vr, r in enumerate(rows) if r[1] == "output"]
    expected = bits(twin_run(model, input_rows(model), [n for _, n in inputs]))
    for path in (f"{resources}/", "-"):
        out = tmp_path / "outputs.csv"
        run = subprocess.run(
            [str(host), str(binary), path, fmi3_token(model), str(reference_files(model)[0]),
             str(out), ",".join(str(vr) for vr, _ in inputs),
             *(f"{'F' if t == 'Real' else 'I'}:{vr}:{n}" for vr, n, t in outputs)],
            env=SANITIZE, capture_output=True, text=True, timeout=120)
        assert_clean(run)
        assert not run.stderr
        lines = out.read_text(encoding="utf-8").splitlines()[1:]
        table = [[float(x) if k == 0 or outputs[k - 1][2] == "Real" else int(x)
                  for k, x in enumerate(line.split(","))] for line in lines]
        assert bits(table) == expected


@pytest.mark.parametrize("model", MODELS)
def test_bad_calls_under_asan(asan, model, tmp_path):
    units, _, abuse = asan
    binary, resources = units[model]
    rows = variable_rows(model)
    param = next(vr for vr, r in enumerate(rows) if r[1] == "parameter"
                 and r[2].fmi_type == "Real")
    inp = next(vr for vr, r in enumerate(rows) if r[1] == "input")
    enum = next((str(vr) for vr, r in enumerate(rows) if is_enumeration(r[2])), "-")
    string = next((str(vr) for vr, r in enumerate(rows) if r[2].fmi_type == "String"), "-")
    assert enum != "-" or not any(s.choices for _, s in specs(UNITS[model].parameters))
    run = subprocess.run([str(abuse), str(binary), f"{resources}/", fmi3_token(model),
                          str(binary.parent), str(param), str(inp),
                          str(time_value_reference(model)), enum, string],
                         env=SANITIZE, capture_output=True, text=True, timeout=120)
    assert_clean(run)
    summary = run.stdout.strip().splitlines()[-1]
    assert summary.startswith("cases ") and summary.endswith(" failures 0"), run.stdout[-3000:]
    assert int(summary.split()[1]) > 300
