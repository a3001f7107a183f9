"""The binaries of every face export their standard's functions and nothing of the library
(rm_*) or the face's helpers (rattle_*), and need only the C library: FMI 2.0's co-simulation
interface (25 common functions, 9 of co-simulation) and only those; FMI 3.0's whole API, every
function fmi3Functions.h declares.  Linux binaries need only libc and libm (the FMI 3.0
aarch64-linux one glibc 2.29, ziglang's default); Windows binaries import only the Universal C
runtime and the kernel."""

from __future__ import annotations

import re
import shutil
import subprocess
import zipfile

import pytest

from drive_rattle.interface import MODELS

from ..fmi3.test_fmi3_build import header_functions
from .conftest import FACES

#: The functions of the FMI 2.0 co-simulation interface (25 common, 9 co-simulation).
FMI2_CO_SIMULATION_FUNCTIONS = 34
#: readelf's name of each Linux binary's machine.
MACHINES = {"x86_64-linux": "Advanced Micro Devices X86-64", "aarch64-linux": "AArch64"}


def _tool(name: str) -> str:
    path = shutil.which(name)
    if path is None:
        pytest.skip(f"{name} (binutils) is not installed")
    return path


def assert_the_standards_functions(face, exported: set[str]) -> None:
    if face.standard == "2.0":
        assert {"fmi2Instantiate", "fmi2DoStep", "fmi2SerializeFMUstate"} <= exported
        assert all(name.startswith("fmi2") for name in exported), sorted(exported)
        assert len(exported) == FMI2_CO_SIMULATION_FUNCTIONS
    else:
        functions = header_functions()
        assert len(functions) == 75  # FMI 3.0's API
        assert exported == set(functions), sorted(exported ^ set(functions))


def assert_a_linux_binary_of_the_standard(face, fmu, member: str, platform: str,
                                          tmp_path) -> None:
    """The binary ``member`` of ``fmu``: built for ``platform``'s machine, needing only libc
    and libm (glibc 2.29 on aarch64-linux), exporting the standard's functions alone."""
    binary = tmp_path / f"{platform}.so"
    with zipfile.ZipFile(fmu) as z:
        binary.write_bytes(z.read(member))
    header = subprocess.run([_tool("readelf"), "-h", str(binary)], capture_output=True,
                            text=True, check=True).stdout
    assert re.search(rf"Machine:\s+{MACHINES[platform]}\n", header), header
    dynamic = subprocess.run([_tool("readelf"), "-d", "-W", str(binary)],
                             capture_output=True, text=True, check=True).stdout
    needed = set(re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]", dynamic))
    assert needed and needed <= {"libc.so.6", "libm.so.6"}, needed
    if platform == "aarch64-linux":  # docs/fmi3.md: glibc 2.29 or later
        versions = subprocess.run([_tool("readelf"), "-V", "-W", str(binary)],
                                  capture_output=True, text=True, check=True).stdout
        assert max(tuple(map(int, v.split("."))) for v in re.findall(
            r"Name: GLIBC_([0-9.]+)", versions)) == (2, 29)
    symbols = subprocess.run([_tool("nm"), "-D", "--defined-only", str(binary)],
                             capture_output=True, text=True, check=True).stdout
    assert_the_standards_functions(
        face, {line.split()[-1] for line in symbols.splitlines() if line.strip()})


@pytest.mark.parametrize("model", MODELS)
def test_x86_64_linux_binary_exports_the_standards_functions_and_needs_only_libc(
        face, face_fmus, model, tmp_path):
    assert_a_linux_binary_of_the_standard(face, face_fmus[model], f"binaries/{face.linux}/"
                                          f"{model}.so", "x86_64-linux", tmp_path)


@pytest.mark.cross
@pytest.mark.parametrize("model", MODELS)
def test_aarch64_linux_binary_exports_the_standards_functions_and_needs_glibc_2_29(
        shipped_fmi3_fmus, model, tmp_path):
    """Only the FMI 3.0 face ships one (FMI 2.0 importers load binaries/linux64 on aarch64
    Linux too: docs/native_fmu.md)."""
    assert_a_linux_binary_of_the_standard(FACES["fmi3"], shipped_fmi3_fmus[model],
                                          f"binaries/aarch64-linux/{model}.so",
                                          "aarch64-linux", tmp_path)


@pytest.mark.cross
@pytest.mark.parametrize("model", MODELS)
def test_windows_binary_exports_the_standards_functions_and_imports_only_the_c_runtime(
        windows_face, shipped_face_fmus, model, tmp_path):
    face = windows_face
    with zipfile.ZipFile(shipped_face_fmus[model]) as z:
        binary = tmp_path / f"{model}.dll"
        binary.write_bytes(z.read(f"binaries/{face.windows}/{model}.dll"))
    headers = subprocess.run([_tool("objdump"), "-p", str(binary)], capture_output=True,
                             text=True)
    if headers.returncode != 0:
        pytest.skip(f"objdump cannot read PE files here: {headers.stderr.strip()}")
    assert "pei-x86-64" in headers.stdout
    imported = {d.lower() for d in re.findall(r"DLL Name: (\S+)", headers.stdout)}
    assert imported and all(d.startswith("api-ms-win-crt-") or d in ("kernel32.dll",
                                                                    "msvcrt.dll")
                            for d in imported), imported
    table = headers.stdout.split("[Ordinal/Name Pointer] Table")[1].split("\n\n")[0]
    assert_the_standards_functions(face, set(re.findall(r"\]\s+(\w+)", table)))
