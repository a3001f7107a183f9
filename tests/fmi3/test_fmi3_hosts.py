"""The FMI 3.0 FMUs in native hosts, without Python: fmu3_host.c (a minimal FMI 3.0 host in C,
the counterpart of tests/native/fmu_host.c) runs each FMU on its regression inputs

* on x86_64-linux, compiled with gcc, in an empty environment: its outputs equal the library's
  unit driven by the same calls and fmpy's run of them, bit for bit, and no libpython is in
  the process; with resourcePath NULL (FMI 3.0 allows it) too;
* with the binary compiled here from the FMU's sources/ alone (what buildDescription.xml
  lists, warning-free under -pedantic -Werror): the same outputs;
* on x86_64-windows under wine, host and FMU cross-compiled: the outputs pass the committed
  regression references (another C library, so not bit for bit).  Skipped with the reason
  where wine is missing, unless RATTLE_REQUIRE_WINE=1 (CI sets it), which makes that a
  failure;
* on aarch64-linux under qemu-user, host and FMU cross-compiled: the outputs pass the committed
  regression references and equal the library's on x86-64 bit for bit (glibc's libm gives
  the same numbers on both).  Skipped with the reason where qemu-user or the aarch64 C library
  is missing, unless RATTLE_REQUIRE_QEMU=1 (CI sets it), which makes that a failure.
"""

from __future__ import annotations

import subprocess
import zipfile
from pathlib import Path

import pytest
from fmpy import read_model_description
from fmpy.model_description import read_build_description

from drive_rattle.interface import MODELS
from drive_rattle_build.compiler import zig_cc
from drive_rattle_build.fmi3 import fmi3_headers, source_files
from drive_rattle_cosim.regression import reference_files

from ..native.test_native_hosts import qemu_aarch64, run_fmpy, windows_path, wine
from ..native.twin import STRICT, assert_passes_references, bits, gcc, input_rows, twin_run

pytestmark = pytest.mark.skipif(gcc() is None,
                                reason="gcc is not installed: the native host cannot be compiled")
HOST_SOURCE = Path(__file__).with_name("fmu3_host.c")


def compile_host(exe: Path, cc=("gcc",), libs=("-ldl",), flags=()) -> Path:
    cmd = [*cc, *STRICT, *flags, "-I", str(fmi3_headers()), "-o", str(exe), str(HOST_SOURCE),
           *libs]
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=900, cwd=Path(exe).parent)
    assert run.returncode == 0, f"{' '.join(cmd)}\n{run.stderr}"
    return Path(exe)


def interface3(fmu: Path):
    """(input names, input vrs, [(output name, FMI 3.0 type, vr)], token)."""
    md = read_model_description(str(fmu))
    inputs = [v for v in md.modelVariables if v.causality == "input"]
    outputs = [(v.name, v.type, v.valueReference) for v in md.modelVariables
               if v.causality == "output"]
    assert {kind for _, kind, _ in outputs} <= {"Float64", "Int32"}
    return [v.name for v in inputs], [v.valueReference for v in inputs], outputs, md.guid


def host_arguments(fmu: Path, binary: str, resources: str, inputs: str, outputs: str):
    _, vrs, outs, token = interface3(fmu)
    return [binary, resources, token, inputs, outputs, ",".join(map(str, vrs)),
            *(f"{kind[0]}:{vr}:{name}" for name, kind, vr in outs)]


def read_table(path: Path, outputs) -> list[list]:
    lines = Path(path).read_text(encoding="utf-8").splitlines()
    assert lines[0] == ",".join(["time", *(n for n, _, _ in outputs)])
    return [[float(x) if k == 0 or outputs[k - 1][1] == "Float64" else int(x)
             for k, x in enumerate(line.split(","))] for line in lines[1:]]


@pytest.fixture(scope="module")
def linux_host(tmp_path_factory) -> Path:
    return compile_host(tmp_path_factory.mktemp("fmu3_host") / "fmu3_host")


def run_linux_host(host: Path, fmu: Path, unpacked: Path, work: Path,
                   resources: str | None = None) -> subprocess.CompletedProcess:
    model = read_model_description(str(fmu)).coSimulation.modelIdentifier
    args = host_arguments(fmu, str(unpacked / "binaries" / "x86_64-linux" / f"{model}.so"),
                          resources or f"{unpacked / 'resources'}/",
                          str(reference_files(model)[0]), str(work / "outputs.csv"))
    return subprocess.run([str(host), *args], env={"PATH": "/nonexistent"}, capture_output=True,
                          text=True, timeout=300)


@pytest.mark.parametrize("model", MODELS)
def test_linux_host_without_python_is_the_library(linux_host, fmi3_fmus, model, tmp_path):
    fmu = fmi3_fmus[model]
    unpacked = tmp_path / "unpacked ä%20"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(unpacked)
    names, _, outputs, _ = interface3(fmu)
    rows = input_rows(model)
    expected = bits(twin_run(model, rows, names))
    assert bits(run_fmpy(fmu, rows)) == expected
    for resources in (None, "-"):  # the resources folder, and NULL
        run = run_linux_host(linux_host, fmu, unpacked, tmp_path, resources)
        assert run.returncode == 0, f"fmu3_host failed (rc {run.returncode}):\n{run.stderr}"
        assert not run.stderr, run.stderr  # nothing logged
        table = read_table(tmp_path / "outputs.csv", outputs)
        assert len(table) == len(rows) == 501
        assert bits(table) == expected


@pytest.mark.parametrize("model", MODELS)
def test_sources_alone_compile_into_a_working_fmu(linux_host, fmi3_fmus, model, tmp_path):
    """sources/ (the files buildDescription.xml lists, the headers beside them) compile alone,
    warning-free, into a binary that gives the shipped binary's outputs bit for bit."""
    fmu = fmi3_fmus[model]
    unpacked = tmp_path / "unpacked"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(unpacked)
    listed = [f for c in read_build_description(str(fmu), validate=True)
              for s in c.sourceFileSets for f in s.sourceFiles]
    assert listed == source_files()
    own = tmp_path / f"{model}.so"
    cc = subprocess.run([gcc(), *STRICT, "-ffp-contract=off", "-fPIC", "-shared", "-o",
                         str(own), *(str(unpacked / "sources" / f) for f in listed), "-lm"],
                        capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert cc.returncode == 0, f"compiling the FMU's sources failed:\n{cc.stderr}"
    shipped = tmp_path / "shipped"
    shipped.mkdir()
    assert run_linux_host(linux_host, fmu, unpacked, shipped).returncode == 0
    (unpacked / "binaries" / "x86_64-linux" / f"{model}.so").write_bytes(own.read_bytes())
    run = run_linux_host(linux_host, fmu, unpacked, tmp_path)
    assert run.returncode == 0 and not run.stderr, run.stderr
    outputs = interface3(fmu)[2]
    assert bits(read_table(tmp_path / "outputs.csv", outputs)) == bits(
        read_table(shipped / "outputs.csv", outputs))


# ------------------------------------------------------------------ x86_64-windows under wine
@pytest.fixture(scope="module")
def wine_env(tmp_path_factory) -> dict:
    import os

    prefix = tmp_path_factory.mktemp("wineprefix3")
    return {**os.environ, "WINEPREFIX": str(prefix), "WINEDEBUG": "-all",
            "WINEDLLOVERRIDES": "mscoree,mshtml="}


@pytest.fixture(scope="module")
def win64_host(tmp_path_factory) -> Path:
    wine()
    exe = tmp_path_factory.mktemp("fmu3_host_win64") / "fmu3_host.exe"
    # clang -pedantic: the standard's fmi3FunctionTypes.h declares the preemption callbacks
    # without a prototype, "()"
    return compile_host(exe, zig_cc("x86_64-windows-gnu"), libs=(),
                        flags=("-Wno-strict-prototypes",))


@pytest.mark.slow
@pytest.mark.parametrize("model", MODELS)
def test_win64_binary_under_wine(win64_host, wine_env, fmi3_fmus, model, tmp_path):
    fmu = fmi3_fmus[model]
    unpacked = tmp_path / "unpacked"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(unpacked)
    args = host_arguments(
        fmu, windows_path(unpacked / "binaries" / "x86_64-windows" / f"{model}.dll"),
        windows_path(unpacked / "resources") + "\\", windows_path(reference_files(model)[0]),
        windows_path(tmp_path / "outputs.csv"))
    run = subprocess.run([wine(), str(win64_host), *args], env=wine_env, capture_output=True,
                         text=True, timeout=600, cwd=tmp_path)
    logged = [line for line in run.stderr.splitlines() if line.startswith("[")]
    assert run.returncode == 0, f"fmu3_host.exe failed (rc {run.returncode}):\n{run.stderr[-3000:]}"
    assert not logged, logged
    outputs = interface3(fmu)[2]
    assert_passes_references(model, read_table(tmp_path / "outputs.csv", outputs),
                             ["time", *(n for n, _, _ in outputs)])


# ------------------------------------------------------------------ aarch64-linux under qemu
@pytest.fixture(scope="module")
def aarch64_host(tmp_path_factory) -> list[str]:
    """fmu3_host.c cross-compiled for aarch64-linux, with the qemu command that runs it."""
    qemu = qemu_aarch64()
    exe = tmp_path_factory.mktemp("fmu3_host_aarch64") / "fmu3_host"
    compile_host(exe, zig_cc("aarch64-linux-gnu"), flags=("-Wno-strict-prototypes",))
    return [*qemu, str(exe)]


@pytest.mark.parametrize("model", MODELS)
def test_aarch64_binary_under_qemu(aarch64_host, fmi3_fmus, model, tmp_path):
    fmu = fmi3_fmus[model]
    unpacked = tmp_path / "unpacked"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(unpacked)
    args = host_arguments(fmu, str(unpacked / "binaries" / "aarch64-linux" / f"{model}.so"),
                          f"{unpacked / 'resources'}/", str(reference_files(model)[0]),
                          str(tmp_path / "outputs.csv"))
    run = subprocess.run([*aarch64_host, *args], capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, f"fmu3_host (aarch64) failed (rc {run.returncode}):\n{run.stderr}"
    assert not run.stderr, run.stderr  # nothing logged
    names, _, outputs, _ = interface3(fmu)
    table = read_table(tmp_path / "outputs.csv", outputs)
    assert_passes_references(model, table, ["time", *(n for n, _, _ in outputs)])
    assert bits(table) == bits(twin_run(model, input_rows(model), names))
