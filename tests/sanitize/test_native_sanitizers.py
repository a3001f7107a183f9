"""The native FMUs' binaries (the model library with its FMI 2.0 face, compiled from the
sources the FMUs ship) under the sanitizers:

* AddressSanitizer + UndefinedBehaviorSanitizer (-fno-sanitize-recover=all, leaks detected):
  the C host fmu_host.c over the regression inputs, its outputs the in-process twin's bit for
  bit, and fmi_abuse.c's bad calls (its FMI 2.0 adapter) -- NULL pointers and arrays, unknown
  value references, calls out of order, non-finite values, resource locations that are not
  this FMU's ("resources", "", NULL, other schemes, a FIFO as the marker file), FMU states
  foreign, truncated at every length, and every byte of the record changed and re-sealed so
  that it reaches rm_restore;
* ThreadSanitizer: threads instantiating, stepping, saving, restoring and freeing their own
  instances at once (the Driveline reading its speed table), each run equal to a sequential
  one.

Any sanitizer report fails the test.  The FMI 3.0 face's: test_fmi3_sanitizers.py."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path
from xml.etree import ElementTree

import pytest
from fmpy import read_model_description

from drive_rattle.interface import MODELS
from drive_rattle_build.native import render_model_description
from drive_rattle_cosim.regression import reference_files

from ..faces.hosts import HOST_SOURCE, host_arguments, read_table
from ..faces.twin import bits, input_rows, interface, twin_run
from .sanitizers import (
    ASAN_FLAGS,
    HERE,
    PROBED,
    SANITIZE,
    TSAN,
    TSAN_FLAGS,
    assert_clean,
    build_fmu_binary,
    compile_abuse,
    compile_program,
    fifo_resources,
    run_abuse,
)

pytestmark = pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc is needed")

def fmu_folder(model: str, folder: Path, flags) -> tuple[Path, Path]:
    """An FMU-like folder of the sanitized binary (its modelDescription beside it):
    (binary, folder)."""
    binary, _, guid = build_fmu_binary(model, folder, flags)
    md = folder / "modelDescription.xml"
    md.write_text(ElementTree.tostring(render_model_description(model, guid),
                                       encoding="unicode"), encoding="utf-8")
    return binary, folder


def value_references(folder: Path) -> dict[str, int]:
    """{name: value reference} of the FMU-like folder's modelDescription."""
    return {v.name: v.valueReference for v in
            read_model_description(str(folder / "modelDescription.xml")).modelVariables}


@pytest.fixture(scope="module")
def asan(tmp_path_factory):
    """{model: FMU-like folder of its ASAN+UBSAN binary}, the host and the abuse probe."""
    root = tmp_path_factory.mktemp("asan")
    folders = {model: fmu_folder(model, root / model, ASAN_FLAGS)[1] for model in MODELS}
    host = compile_program(root / "fmu_host", HOST_SOURCE, ASAN_FLAGS)
    abuse = compile_abuse(root / "fmi_abuse", "2.0")
    return folders, host, abuse


@pytest.mark.slow
@pytest.mark.parametrize("model", MODELS)
def test_host_over_the_regression_inputs_under_asan(asan, model, tmp_path):
    folders, host, _ = asan
    folder = folders[model]
    md = folder / "modelDescription.xml"
    args = host_arguments(md, str(folder / f"{model}.so"), (folder / "resources").as_uri(),
                          str(reference_files(model)[0]),
                          str(tmp_path / "outputs.csv"))
    run = subprocess.run([str(host), *args], env=SANITIZE, capture_output=True, text=True,
                         timeout=60)
    assert_clean(run)
    assert not run.stderr  # nothing logged
    _, _, names, outputs = interface(md)
    rows = input_rows(model)
    # the sanitized build computes the same numbers (IEEE, no contraction) as every other
    assert bits(read_table(tmp_path / "outputs.csv", outputs)) == bits(
        twin_run(model, rows, names))


@pytest.mark.slow
@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
@pytest.mark.parametrize("model", MODELS)
def test_bad_calls_under_asan(asan, model, tmp_path):
    folders, _, abuse = asan
    folder = folders[model]
    guid = read_model_description(str(folder / "modelDescription.xml")).guid
    run_abuse(abuse, folder / f"{model}.so", (folder / "resources").as_uri(), guid, folder,
              fifo_resources(tmp_path / "fifo resources"), value_references(folder), model)


@pytest.fixture(scope="module")
def tsan(tmp_path_factory):
    root = tmp_path_factory.mktemp("tsan")
    folders = {model: fmu_folder(model, root / model, TSAN_FLAGS)[1] for model in MODELS}
    threads = compile_program(root / "fmi_threads", HERE / "fmi_threads.c", TSAN_FLAGS)
    return folders, threads


@pytest.mark.slow
@pytest.mark.parametrize("model", MODELS)
def test_threads_under_tsan(tsan, model):
    folders, threads = tsan
    folder = folders[model]
    guid = read_model_description(str(folder / "modelDescription.xml")).guid
    by_name = value_references(folder)
    _, vr_input, vr_output, _, vr_string, _ = (
        str(by_name[n]) if n is not None else "-" for n in PROBED[model])
    extra = []
    if model == "Driveline":  # each instance reads and parses its speed table
        (folder / "resources" / "run-up.csv").write_text(
            "time [s],speed [rad/s]\n0,80\n0.01,95\n0.02,85\n1,90\n", encoding="utf-8")
        extra = [vr_string, "run-up.csv"]
    run = subprocess.run([str(threads), str(folder / f"{model}.so"),
                          (folder / "resources").as_uri(), guid, "3", "3", "60", vr_input,
                          "80.0", vr_output, *extra],
                         env=TSAN, capture_output=True, text=True, timeout=60)
    assert_clean(run)
    assert "runs differing: 0" in run.stdout, run.stdout + run.stderr
