"""Every native face in the native host, without Python: fmu_host.c (one minimal host in C,
its FMI 2.0 or FMI 3.0 adapter compiled in) runs each FMU on its regression inputs

* on x86-64 Linux, compiled with gcc, in an empty environment (no PATH to a Python, no
  LD_PRELOAD): its outputs equal the model library's unit driven by the same calls and fmpy's
  run of them, bit for bit, and no libpython is in the process (the host checks
  /proc/self/maps); FMI 3.0 with resourcePath NULL too (the standard allows it);
* with the binary compiled here from the FMU's sources/ alone (what <SourceFiles> or
  buildDescription.xml lists, with the headers beside them; warning-free under -pedantic
  -Werror): the same outputs;
* on 64-bit Windows under wine, host and FMU cross-compiled: the outputs pass the committed
  regression references (another C library, so not bit for bit);
* on aarch64-linux under qemu-user (the FMI 3.0 FMUs' binary), host and FMU cross-compiled: the
  outputs pass the committed regression references and equal the library's on x86-64 bit for
  bit (glibc's libm gives the same numbers on both).

The pythonfmu face runs in this host with libpython preloaded: tests/adversarial/
test_native_host.py.
"""

from __future__ import annotations

import subprocess
import zipfile
from pathlib import Path

import pytest
from fmpy.model_description import read_build_description

from drive_rattle.interface import MODELS
from drive_rattle_build.compiler import zig_cc
from drive_rattle_build.fmi3 import source_files as fmi3_source_files
from drive_rattle_cosim.regression import reference_files

from .conftest import FACES
from .hosts import (
    STRICT,
    compile_host,
    gcc,
    host_arguments,
    qemu_aarch64,
    read_table,
    run_fmpy,
    windows_path,
    wine,
)
from .twin import assert_passes_references, bits, input_rows, interface, twin_run

pytestmark = pytest.mark.skipif(gcc() is None,
                                reason="gcc is not installed: the native host cannot be compiled")
#: clang -pedantic: the FMI 3.0 fmi3FunctionTypes.h declares the preemption callbacks without a
#: prototype, "()"
CLANG = {"2.0": (), "3.0": ("-Wno-strict-prototypes",)}


def resources_argument(face, resources: Path) -> str:
    """The resources folder as the standard gives it: FMI 2.0 a file URI (percent-encoded),
    FMI 3.0 a path with its trailing separator."""
    return resources.as_uri() if face.standard == "2.0" else f"{resources}/"


def unpacked(fmu: Path, folder: Path) -> Path:
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    return folder


@pytest.fixture(scope="module")
def linux_host(native_face, tmp_path_factory) -> Path:
    return compile_host(tmp_path_factory.mktemp("fmu_host") / "fmu_host", native_face.standard)


def run_linux_host(face, host: Path, fmu: Path, root: Path, work: Path,
                   resources: str | None = None) -> subprocess.CompletedProcess:
    model = interface(fmu)[0]
    args = host_arguments(fmu, str(root / "binaries" / face.linux / f"{model}.so"),
                          resources or resources_argument(face, root / "resources"),
                          str(reference_files(model)[0]), str(work / "outputs.csv"))
    # what a system-simulation tool's process may have: nothing of Python at all
    return subprocess.run([str(host), *args], env={"PATH": "/nonexistent"}, capture_output=True,
                          text=True, timeout=300)


@pytest.mark.parametrize("model", MODELS)
def test_linux_host_without_python_is_the_library(native_face, linux_host, face_fmus, model,
                                                  tmp_path):
    face = native_face
    fmu = face_fmus[model]
    root = unpacked(fmu, tmp_path / "unpacked ä%20")  # a URI percent-encodes both
    _, _, names, outputs = interface(fmu)
    rows = input_rows(model)
    expected = bits(twin_run(model, rows, names))
    assert bits(run_fmpy(fmu, rows)) == expected
    # the resources folder, and (FMI 3.0) NULL
    for resources in (None, "-") if face.standard == "3.0" else (None,):
        run = run_linux_host(face, linux_host, fmu, root, tmp_path, resources)
        assert run.returncode == 0, f"fmu_host failed (rc {run.returncode}):\n{run.stderr}"
        assert not run.stderr, run.stderr  # nothing logged
        table = read_table(tmp_path / "outputs.csv", outputs)
        assert len(table) == len(rows) == 501
        assert bits(table) == expected


def listed_sources(face, fmu: Path, root: Path) -> list[Path]:
    """The C files of sources/ (FMI 3.0: as buildDescription.xml lists them)."""
    if face.standard == "2.0":
        return sorted((root / "sources").glob("*.c"))
    listed = [f for c in read_build_description(str(fmu), validate=True)
              for s in c.sourceFileSets for f in s.sourceFiles]
    assert listed == fmi3_source_files()
    return [root / "sources" / f for f in listed]


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.slow
def test_sources_alone_compile_into_a_working_fmu(native_face, linux_host, face_fmus, model,
                                                  tmp_path):
    """The FMU's sources/ compile alone, warning-free, into a binary that gives the shipped
    binary's outputs bit for bit."""
    face = native_face
    fmu = face_fmus[model]
    root = unpacked(fmu, tmp_path / "unpacked")
    own = tmp_path / f"{model}.so"
    cc = subprocess.run([gcc(), *STRICT, "-ffp-contract=off", "-fPIC", "-shared", "-o",
                         str(own), *(str(s) for s in listed_sources(face, fmu, root)), "-lm"],
                        capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert cc.returncode == 0, f"compiling the FMU's sources failed:\n{cc.stderr}"
    shipped = tmp_path / "shipped"
    shipped.mkdir()
    assert run_linux_host(face, linux_host, fmu, root, shipped).returncode == 0
    (root / "binaries" / face.linux / f"{model}.so").write_bytes(own.read_bytes())
    run = run_linux_host(face, linux_host, fmu, root, tmp_path)
    assert run.returncode == 0 and not run.stderr, run.stderr
    outputs = interface(fmu)[3]
    assert bits(read_table(tmp_path / "outputs.csv", outputs)) == bits(
        read_table(shipped / "outputs.csv", outputs))


# ------------------------------------------------------------------ win64 under wine
@pytest.fixture(scope="module")
def win64_host(windows_face, tmp_path_factory) -> Path:
    face = windows_face
    wine()
    exe = tmp_path_factory.mktemp("fmu_host_win64") / "fmu_host.exe"
    return compile_host(exe, face.standard, zig_cc("x86_64-windows-gnu"), libs=(),
                        flags=(*STRICT, *CLANG[face.standard]))


@pytest.mark.cross
@pytest.mark.parametrize("model", MODELS)
def test_win64_binary_under_wine(windows_face, win64_host, wine_env, shipped_face_fmus, model,
                                tmp_path):
    face = windows_face
    fmu = shipped_face_fmus[model]
    root = unpacked(fmu, tmp_path / "unpacked")
    folder = windows_path(root / "resources")
    resources = ("file:///" + folder.replace("\\", "/") if face.standard == "2.0"
                 else folder + "\\")
    args = host_arguments(fmu, windows_path(root / "binaries" / face.windows / f"{model}.dll"),
                          resources, windows_path(reference_files(model)[0]),
                          windows_path(tmp_path / "outputs.csv"))
    run = subprocess.run([wine(), str(win64_host), *args], env=wine_env, capture_output=True,
                         text=True, timeout=600, cwd=tmp_path)
    logged = [line for line in run.stderr.splitlines() if line.startswith("[")]
    assert run.returncode == 0, f"fmu_host.exe failed (rc {run.returncode}):\n{run.stderr[-3000:]}"
    assert not logged, logged
    outputs = interface(fmu)[3]
    assert_passes_references(model, read_table(tmp_path / "outputs.csv", outputs),
                             ["time", *(n for n, _, _ in outputs)])


# ------------------------------------------------------------------ aarch64-linux under qemu
@pytest.fixture(scope="module")
def aarch64_host(tmp_path_factory) -> list[str]:
    """fmu_host.c (FMI 3.0) cross-compiled for aarch64-linux, with the qemu command that runs
    it."""
    qemu = qemu_aarch64()
    exe = tmp_path_factory.mktemp("fmu_host_aarch64") / "fmu_host"
    compile_host(exe, "3.0", zig_cc("aarch64-linux-gnu"), flags=(*STRICT, *CLANG["3.0"]))
    return [*qemu, str(exe)]


@pytest.mark.cross
@pytest.mark.parametrize("model", MODELS)
def test_aarch64_binary_under_qemu(aarch64_host, shipped_fmi3_fmus, model, tmp_path):
    """Only the FMI 3.0 face ships an aarch64-linux binary (FMI 2.0 importers load
    binaries/linux64 there too: docs/native_fmu.md)."""
    fmu = shipped_fmi3_fmus[model]
    root = unpacked(fmu, tmp_path / "unpacked")
    args = host_arguments(fmu, str(root / "binaries" / "aarch64-linux" / f"{model}.so"),
                          resources_argument(FACES["fmi3"], root / "resources"),
                          str(reference_files(model)[0]), str(tmp_path / "outputs.csv"))
    run = subprocess.run([*aarch64_host, *args], capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, f"fmu_host (aarch64) failed (rc {run.returncode}):\n{run.stderr}"
    assert not run.stderr, run.stderr  # nothing logged
    _, _, names, outputs = interface(fmu)
    table = read_table(tmp_path / "outputs.csv", outputs)
    assert_passes_references(model, table, ["time", *(n for n, _, _ in outputs)])
    assert bits(table) == bits(twin_run(model, input_rows(model), names))
