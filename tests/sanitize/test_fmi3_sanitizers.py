"""The FMI 3.0 face (fmu_src/fmi3/fmi3_functions.c) with the model library under
AddressSanitizer and UndefinedBehaviorSanitizer: each unit's binary compiled from the sources
the FMI 3.0 FMU ships, driven by the C host tests/faces/fmu_host.c (its FMI 3.0 adapter) over
the regression inputs (with and without a resources folder) and by fmi_abuse.c's bad calls (its
FMI 3.0 adapter: the cases of the FMI 2.0 face's, in FMI 3.0's calls, and FMI 3.0's own --
nValues, the types the units lack, Enumerations beyond 32 bits, the independent variable,
fmi3DoStep's output pointers, Event Mode).  A report, a leak or a crash fails the test."""

from __future__ import annotations

import os
import subprocess

import pytest

from drive_rattle.catalog import UNITS
from drive_rattle.interface import MODELS
from drive_rattle.parameters import specs
from drive_rattle_build.fmi3 import fmi3_token
from drive_rattle_build.model_description import variable_rows
from drive_rattle_build.model_description_fmi3 import is_enumeration, time_value_reference
from drive_rattle_cosim.regression import reference_files

from ..faces.hosts import ADAPTER, HOST_SOURCE
from ..faces.twin import bits, input_rows, twin_run
from .sanitizers import (
    ASAN_FLAGS,
    PROBED,
    SANITIZE,
    assert_clean,
    build_fmu_binary,
    compile_abuse,
    compile_program,
    fifo_resources,
    run_abuse,
)

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def asan(tmp_path_factory):
    root = tmp_path_factory.mktemp("asan3")
    units = {model: build_fmu_binary(model, root / model, ASAN_FLAGS, "3.0")[:2]
             for model in MODELS}
    host = compile_program(root / "fmu_host", HOST_SOURCE, ASAN_FLAGS, "3.0", ADAPTER["3.0"])
    abuse = compile_abuse(root / "fmi_abuse", "3.0")
    return units, host, abuse


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


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
@pytest.mark.parametrize("model", MODELS)
def test_bad_calls_under_asan(asan, model, tmp_path):
    units, _, abuse = asan
    binary, resources = units[model]
    rows = variable_rows(model)
    references = {r[0]: vr for vr, r in enumerate(rows)}
    enumeration = PROBED[model][5]  # FMI 3.0's own cases need one where the unit has one
    assert (enumeration is None) == (not any(s.choices for _, s in specs(UNITS[model].parameters)))
    assert enumeration is None or is_enumeration(rows[references[enumeration]][2]), enumeration
    run_abuse(abuse, binary, f"{resources}/", fmi3_token(model), binary.parent,
              fifo_resources(tmp_path / "fifo resources"), references, model,
              time_value_reference(model))
