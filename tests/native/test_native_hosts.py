"""The native FMUs in native hosts, without Python: fmu_host.c (a minimal FMI 2.0 host in C)
runs each FMU on its regression inputs

* on linux64, compiled with gcc, in an empty environment (no PATH to a Python, no
  LD_PRELOAD): its outputs equal the in-process twin's (the model library's unit driven by the
  same calls) and fmpy's run of the same calls, bit for bit, and no libpython is in the
  process (the host checks /proc/self/maps);
* on linux64 with the binary compiled here from the FMU's sources/ alone (warning-free under
  -pedantic -Werror): the same outputs;
* on win64 under wine, host and FMU cross-compiled: the outputs pass the committed regression
  references (another C library, so not bit for bit).  Skipped with the reason where wine is
  missing, unless RATTLE_REQUIRE_WINE=1 (CI sets it), which makes that a failure.

The aarch64-linux binaries run under qemu-user (``qemu_aarch64``, the FMI 3.0 FMUs' in
tests/fmi3, a binary built into an FMI 2.0 FMU on request in tests/fmu/test_platforms.py).
"""

from __future__ import annotations

import itertools
import os
import shutil
import subprocess
import zipfile
from pathlib import Path

import pytest

from drive_rattle.interface import MODELS
from drive_rattle_build.compiler import zig_cc
from drive_rattle_cosim.harness import Unit
from drive_rattle_cosim.regression import reference_files

from .twin import (
    STRICT,
    assert_passes_references,
    bits,
    compile_host,
    gcc,
    host_arguments,
    input_rows,
    interface,
    read_table,
    twin_run,
)

pytestmark = pytest.mark.skipif(gcc() is None,
                                reason="gcc is not installed: the native host cannot be compiled")


def run_fmpy(fmu: Path, rows) -> list[list]:
    """fmu_host.c's call sequence through fmpy in this process (the harness's unit, so an FMI
    2.0 or 3.0 FMU): start at the first row's time, the first row's inputs set in
    initialization mode, then per row the inputs set and a step to the next row's time;
    [time, outputs...] at every row."""
    _, _, input_names, outputs = interface(fmu)
    names = [name for name, _, _ in outputs]
    unit = Unit(fmu, "fmpy_reference")
    try:
        unit.enter_initialization(rows[0][0])
        unit.set(dict(zip(input_names, rows[0][1:], strict=True)))
        unit.exit_initialization()
        table = [[rows[0][0], *unit.get(names)]]
        for row, following in itertools.pairwise(rows):
            unit.set(dict(zip(input_names, row[1:], strict=True)))
            unit.do_step(row[0], following[0] - row[0])
            table.append([following[0], *unit.get(names)])
        assert not unit.messages, unit.messages
        return table
    finally:
        unit.close()


@pytest.fixture(scope="module")
def linux_host(tmp_path_factory) -> Path:
    return compile_host(tmp_path_factory.mktemp("fmu_host") / "fmu_host")


def run_linux_host(host: Path, fmu: Path, unpacked: Path,
                   work: Path) -> subprocess.CompletedProcess:
    model = interface(fmu)[0]
    args = host_arguments(fmu, str(unpacked / "binaries" / "linux64" / f"{model}.so"),
                          (unpacked / "resources").as_uri(), str(reference_files(model)[0]),
                          str(work / "outputs.csv"))
    # what a system-simulation tool's process may have: nothing of Python at all
    return subprocess.run([str(host), *args], env={"PATH": "/nonexistent"}, capture_output=True,
                          text=True, timeout=300)


@pytest.mark.parametrize("model", MODELS)
def test_linux_host_without_python_is_the_twin(linux_host, native_fmus, model, tmp_path):
    fmu = native_fmus[model]
    unpacked = tmp_path / "unpacked ä%20"  # the URI percent-encodes both
    with zipfile.ZipFile(fmu) as z:
        z.extractall(unpacked)
    run = run_linux_host(linux_host, fmu, unpacked, tmp_path)
    assert run.returncode == 0, f"fmu_host failed (rc {run.returncode}):\n{run.stderr}"
    assert not run.stderr, run.stderr  # nothing logged
    _, _, names, outputs = interface(fmu)
    table = read_table(tmp_path / "outputs.csv", outputs)
    rows = input_rows(model)
    assert len(table) == len(rows) == 501
    assert bits(table) == bits(twin_run(model, rows, names))
    assert bits(table) == bits(run_fmpy(fmu, rows))


@pytest.mark.parametrize("model", MODELS)
def test_sources_alone_compile_into_a_working_fmu(linux_host, native_fmus, model, tmp_path):
    """The FMU's sources/ (what <SourceFiles> lists, with the headers beside them) compile
    alone, warning-free, into a binary that gives the shipped binary's outputs bit for bit."""
    fmu = native_fmus[model]
    unpacked = tmp_path / "unpacked"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(unpacked)
    sources = sorted((unpacked / "sources").glob("*.c"))
    own = tmp_path / f"{model}.so"
    cc = subprocess.run([gcc(), *STRICT, "-ffp-contract=off", "-fPIC", "-shared", "-o",
                         str(own), *(str(s) for s in sources), "-lm"],
                        capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert cc.returncode == 0, f"compiling the FMU's sources failed:\n{cc.stderr}"
    shipped = tmp_path / "shipped"
    shipped.mkdir()
    assert run_linux_host(linux_host, fmu, unpacked, shipped).returncode == 0
    (unpacked / "binaries" / "linux64" / f"{model}.so").write_bytes(own.read_bytes())
    run = run_linux_host(linux_host, fmu, unpacked, tmp_path)
    assert run.returncode == 0 and not run.stderr, run.stderr
    outputs = interface(fmu)[3]
    assert bits(read_table(tmp_path / "outputs.csv", outputs)) == bits(
        read_table(shipped / "outputs.csv", outputs))


# ------------------------------------------------------------------ win64 under wine
def wine() -> str:
    path = shutil.which("wine64") or shutil.which("wine")
    if path is None:
        reason = ("wine is not installed: the win64 binary is not run here (Debian/Ubuntu: "
                  "`apt-get install wine64`; CI installs it)")
        if os.environ.get("RATTLE_REQUIRE_WINE"):
            pytest.fail(f"RATTLE_REQUIRE_WINE is set but {reason}")
        pytest.skip(reason)
    return path


def windows_path(path: Path) -> str:
    """The path under wine's drive Z: (the root of the Linux file system)."""
    return "Z:" + str(path).replace("/", "\\")


@pytest.fixture(scope="module")
def wine_env(tmp_path_factory) -> dict:
    prefix = tmp_path_factory.mktemp("wineprefix")
    return {**os.environ, "WINEPREFIX": str(prefix), "WINEDEBUG": "-all",
            "WINEDLLOVERRIDES": "mscoree,mshtml="}  # no .NET/Gecko installers in a new prefix


@pytest.fixture(scope="module")
def win64_host(tmp_path_factory) -> Path:
    wine()
    exe = tmp_path_factory.mktemp("fmu_host_win64") / "fmu_host.exe"
    return compile_host(exe, zig_cc("x86_64-windows-gnu"), libs=())


@pytest.mark.slow
@pytest.mark.parametrize("model", MODELS)
def test_win64_binary_under_wine(win64_host, wine_env, native_fmus, model, tmp_path):
    fmu = native_fmus[model]
    unpacked = tmp_path / "unpacked"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(unpacked)
    resources = "file:///" + windows_path(unpacked / "resources").replace("\\", "/")
    args = host_arguments(fmu, windows_path(unpacked / "binaries" / "win64" / f"{model}.dll"),
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
#: The aarch64 C library of Debian's libc6-arm64-cross: qemu-user's root for a dynamically
#: linked aarch64 program (its loader and libc, libm, libdl).
AARCH64_ROOT = Path("/usr/aarch64-linux-gnu")


def qemu_aarch64() -> list[str]:
    """The command that runs a dynamically linked aarch64-linux program here
    (``qemu-aarch64-static -L /usr/aarch64-linux-gnu``).  Skipped with the reason where qemu-user
    or the aarch64 C library is missing, unless RATTLE_REQUIRE_QEMU=1 (CI sets it), which makes
    that a failure."""
    qemu = shutil.which("qemu-aarch64-static") or shutil.which("qemu-aarch64")
    missing = [what for what, there in (
        ("qemu-user (Debian/Ubuntu: `apt-get install qemu-user-static`)", qemu),
        ("the aarch64 C library (Debian/Ubuntu: `apt-get install libc6-arm64-cross`)",
         (AARCH64_ROOT / "lib" / "ld-linux-aarch64.so.1").is_file())) if not there]
    if missing:
        reason = (f"{' and '.join(missing)} not installed: the aarch64-linux binary is not run "
                  "here (CI installs them)")
        if os.environ.get("RATTLE_REQUIRE_QEMU"):
            pytest.fail(f"RATTLE_REQUIRE_QEMU is set but {reason}")
        pytest.skip(reason)
    return [qemu, "-L", str(AARCH64_ROOT)]
