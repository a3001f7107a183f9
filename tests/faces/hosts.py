"""The C host of every native face, ``fmu_host.c`` (one source, its FMI 2.0 or FMI 3.0 adapter
chosen when it is compiled), its command line and output table, fmpy's run of the same calls,
and where the hosts run besides here: win64 under wine, aarch64-linux under qemu-user (each
skipped with the reason where missing, unless RATTLE_REQUIRE_WINE=1 or RATTLE_REQUIRE_QEMU=1,
which CI sets, makes that a failure)."""

from __future__ import annotations

import itertools
import os
import shutil
import subprocess
from collections.abc import Sequence
from pathlib import Path

import pytest
from fmpy import read_model_description

from drive_rattle_cosim.harness import Unit

from .twin import interface

HOST_SOURCE = Path(__file__).with_name("fmu_host.c")
#: The host compiles warning-free under these.
STRICT = ("-std=c99", "-O2", "-Wall", "-Wextra", "-pedantic", "-Werror")
#: The define that compiles the FMI 3.0 adapter, by standard.
ADAPTER = {"2.0": (), "3.0": ("-DFMU_HOST_FMI3",)}


def gcc() -> str | None:
    return shutil.which("gcc")


def headers(standard: str) -> Path:
    """The folder of the standard's C headers (fmpy's)."""
    if standard == "3.0":
        from drive_rattle_build.fmi3 import fmi3_headers

        return fmi3_headers()
    from drive_rattle_build.shim import fmi2_headers

    return fmi2_headers()


def compile_host(exe: Path, standard: str = "2.0", cc: Sequence[str] = ("gcc",),
                 flags: Sequence[str] = STRICT, libs: Sequence[str] = ("-ldl",)) -> Path:
    """fmu_host.c with the adapter of ``standard`` compiled into ``exe``; AssertionError with
    the compiler's output."""
    cmd = [*cc, *flags, *ADAPTER[standard], "-I", str(headers(standard)), "-o", str(exe),
           str(HOST_SOURCE), *libs]
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=900, cwd=Path(exe).parent)
    assert run.returncode == 0, f"{' '.join(cmd)}\n{run.stderr}"
    return Path(exe)


def host_arguments(fmu: Path, binary: str, resources: str, inputs: str,
                   outputs: str) -> list[str]:
    """fmu_host's command line for ``fmu``'s binary on an inputs file (``fmu``: the FMU, its
    folder or its modelDescription.xml)."""
    md = read_model_description(str(fmu))
    by_name = {v.name: v for v in md.modelVariables}
    _, token, input_names, outs = interface(fmu)
    return [binary, resources, token, inputs, outputs,
            ",".join(str(by_name[n].valueReference) for n in input_names),
            *(f"{kind[0]}:{vr}:{name}" for name, kind, vr in outs)]


def read_table(path: Path, outputs) -> list[list]:
    """fmu_host's output CSV: [time, outputs...] per row (integers as int)."""
    lines = Path(path).read_text(encoding="utf-8").splitlines()
    assert lines[0] == ",".join(["time", *(n for n, _, _ in outputs)])
    return [[float(x) if k == 0 or outputs[k - 1][1] in ("Real", "Float64") else int(x)
             for k, x in enumerate(line.split(","))] for line in lines[1:]]


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


# ------------------------------------------------------------------ aarch64-linux under qemu
#: The aarch64 C library of Debian's libc6-arm64-cross: qemu-user's root for a dynamically
#: linked aarch64 program (its loader and libc, libm, libdl).
AARCH64_ROOT = Path("/usr/aarch64-linux-gnu")


def qemu_aarch64() -> list[str]:
    """The command that runs a dynamically linked aarch64-linux program here
    (``qemu-aarch64-static -L /usr/aarch64-linux-gnu``)."""
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
