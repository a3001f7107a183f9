"""The platforms of the FMUs' binaries (drive_rattle_build/platforms.py) and
``drive-rattle-build --platform NAME --fmu FMU``, which cross-compiles an FMU's own sources
into it: the folders are the standards' (FMI 3.0 platform tuples; FMI 2.0's linux64, win64,
darwin64 for x86-64 and the FMI 3.0 tuple for any other platform); a macOS binary is a Mach-O
shared library of the right CPU that exports the FMI functions of the FMU's version and
nothing else (read from its symbol table; nothing here can run it); an aarch64 binary built
into an FMI 2.0 FMU runs under qemu-user with the library's numbers bit for bit; a refused or
failed request leaves the FMU as it was."""

from __future__ import annotations

import re
import shutil
import struct
import subprocess
import zipfile
from pathlib import Path

import pytest

from drive_rattle_build.cli import main
from drive_rattle_build.compiler import zig_cc
from drive_rattle_build.platforms import (
    FMI2_SHIPPED,
    FMI3_SHIPPED,
    PLATFORMS,
    UNTESTED,
)
from drive_rattle_cosim.regression import reference_files

from ..faces.hosts import compile_host, host_arguments, qemu_aarch64, read_table
from ..faces.twin import bits, input_rows, interface, twin_run
from ..fmi3.test_fmi3_build import header_functions

#: FMI 3.0.2, 2.5.1.4.1 "Platform Tuple Definition": <arch>-<sys>.
FMI3_ARCHITECTURES = {"aarch32", "aarch64", "x86", "x86_64"}
FMI3_SYSTEMS = {"darwin", "linux", "windows"}
#: FMI 2.0.5, 2.3: the standardized folders, "64" standing for 64-bit x86; any other
#: platform uses the FMI 3.0 platform tuple.
FMI2_X86_64_FOLDERS = {"linux": "linux64", "windows": "win64", "darwin": "darwin64"}
#: Mach-O (<mach-o/loader.h>, <mach-o/nlist.h>, <mach/machine.h>).
MH_MAGIC_64, MH_DYLIB, LC_SYMTAB, LC_CODE_SIGNATURE = 0xFEEDFACF, 6, 0x2, 0x1D
N_STAB, N_TYPE, N_EXT, N_SECT = 0xE0, 0x0E, 0x01, 0x0E
CPU_TYPES = {"x86_64": 0x01000007, "aarch64": 0x0100000C}
#: What the macOS linker itself exports from every shared library.
LINKER_SYMBOLS = {"__dso_handle", "_mh_dylib_header"}
#: The functions of the FMI 2.0 co-simulation interface (25 common, 9 co-simulation).
FMI2_CO_SIMULATION_FUNCTIONS = 34


def macho_dylib(data: bytes) -> tuple[int, int, set[str], set[int]]:
    """(CPU type, file type, the C names of the defined external symbols, the load commands)
    of a 64-bit Mach-O file, the symbols read from its LC_SYMTAB."""
    magic, cpu, _, filetype, ncmds, _, _, _ = struct.unpack_from("<IiiIIIII", data, 0)
    assert magic == MH_MAGIC_64, hex(magic)
    offset, exported, commands = 32, set(), set()
    for _ in range(ncmds):
        cmd, size = struct.unpack_from("<II", data, offset)
        commands.add(cmd)
        if cmd == LC_SYMTAB:
            symoff, nsyms, stroff, _ = struct.unpack_from("<IIII", data, offset + 8)
            for k in range(nsyms):
                strx, ntype, _, _, _ = struct.unpack_from("<IBBhQ", data, symoff + 16 * k)
                if not ntype & N_STAB and ntype & N_EXT and ntype & N_TYPE == N_SECT:
                    name = data[stroff + strx:data.index(b"\0", stroff + strx)].decode()
                    exported.add(name[1:])  # C names carry a leading underscore
        offset += size
    return cpu, filetype, exported, commands


def copy_of(fmu: Path, folder: Path) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    return Path(shutil.copy2(fmu, folder / fmu.name))


def members(fmu: Path) -> dict[str, bytes]:
    with zipfile.ZipFile(fmu) as z:
        names = z.namelist()
        assert len(names) == len(set(names)), "an FMU member is there twice"
        return {n: z.read(n) for n in names}


def test_platform_folders_are_the_standards():
    for name, platform in PLATFORMS.items():
        arch, system = name.split("-")
        assert arch in FMI3_ARCHITECTURES and system in FMI3_SYSTEMS, name
        assert platform.folder(3) == name
        assert platform.folder(2) == (FMI2_X86_64_FOLDERS[system] if arch == "x86_64"
                                      else name)
        assert platform.suffix == {"linux": ".so", "windows": ".dll", "darwin": ".dylib"}[system]
    # no binary is shipped that nothing here runs
    assert set(UNTESTED) == {n for n in PLATFORMS if n.endswith("-darwin")}
    assert not set(UNTESTED) & (set(FMI2_SHIPPED) | set(FMI3_SHIPPED))


@pytest.mark.slow
def test_macos_binaries_from_an_fmi3_fmus_sources(fmi3_fmus, tmp_path, capsys):
    fmu = copy_of(fmi3_fmus["GearMeshRattle"], tmp_path)
    before = members(fmu)
    assert main(["--platform", "x86_64-darwin", "--platform", "aarch64-darwin",
                 "--fmu", str(fmu)]) == 0
    said = capsys.readouterr().out
    assert said.count("untested") == 2, said
    after = members(fmu)
    added = {n: after.pop(n) for n in set(after) - set(before)}
    assert after == before  # everything else as it was
    assert set(added) == {"binaries/x86_64-darwin/GearMeshRattle.dylib",
                          "binaries/aarch64-darwin/GearMeshRattle.dylib"}
    for arch in ("x86_64", "aarch64"):
        cpu, filetype, exported, commands = macho_dylib(added[f"binaries/{arch}-darwin/"
                                                             "GearMeshRattle.dylib"])
        assert (cpu, filetype) == (CPU_TYPES[arch], MH_DYLIB)
        assert exported - LINKER_SYMBOLS == set(header_functions())
        if arch == "aarch64":  # Apple Silicon runs no arm64 code without a signature
            assert LC_CODE_SIGNATURE in commands


@pytest.mark.slow
def test_an_fmi2_fmu_gets_its_x86_64_macos_binary_in_darwin64(native_fmus, tmp_path):
    fmu = copy_of(native_fmus["Driveline"], tmp_path)
    assert main(["--platform", "x86_64-darwin", "--fmu", str(fmu)]) == 0
    cpu, filetype, exported, _ = macho_dylib(members(fmu)["binaries/darwin64/Driveline.dylib"])
    assert (cpu, filetype) == (CPU_TYPES["x86_64"], MH_DYLIB)
    exported -= LINKER_SYMBOLS
    assert all(name.startswith("fmi2") for name in exported), sorted(exported)
    assert len(exported) == FMI2_CO_SIMULATION_FUNCTIONS
    assert {"fmi2Instantiate", "fmi2DoStep", "fmi2SerializeFMUstate"} <= exported


@pytest.mark.cross
def test_an_aarch64_binary_built_into_an_fmi2_fmu_runs_under_qemu(shipped_native_fmus, tmp_path):
    """In binaries/aarch64-linux (FMI 2.0.4+: the FMI 3.0 tuple for a platform FMI 2.0 does
    not name), built twice (the second replaces the first), run by fmu_host.c cross-compiled
    for aarch64: the library's numbers on x86-64, bit for bit."""
    qemu = qemu_aarch64()
    fmu = copy_of(shipped_native_fmus["GearMeshRattle"], tmp_path / "fmu")
    for _ in range(2):
        assert main(["--platform", "aarch64-linux", "--fmu", str(fmu)]) == 0
    assert [n for n in members(fmu) if n.startswith("binaries/")] == [
        "binaries/linux64/GearMeshRattle.so", "binaries/win64/GearMeshRattle.dll",
        "binaries/aarch64-linux/GearMeshRattle.so"]
    host = compile_host(tmp_path / "fmu_host", "2.0", zig_cc("aarch64-linux-gnu"))
    unpacked = tmp_path / "unpacked"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(unpacked)
    args = host_arguments(fmu, str(unpacked / "binaries" / "aarch64-linux" / "GearMeshRattle.so"),
                          (unpacked / "resources").as_uri(),
                          str(reference_files("GearMeshRattle")[0]), str(tmp_path / "out.csv"))
    run = subprocess.run([*qemu, str(host), *args], capture_output=True, text=True, timeout=600)
    assert run.returncode == 0 and not run.stderr, run.stderr
    _, _, names, outputs = interface(fmu)
    rows = input_rows("GearMeshRattle")
    assert bits(read_table(tmp_path / "out.csv", outputs)) == bits(
        twin_run("GearMeshRattle", rows, names))


def fmu_without_sources(path: Path) -> Path:
    """An FMI 2.0 co-simulation FMU that lists no sources (as the pythonfmu FMUs)."""
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("modelDescription.xml",
                   '<fmiModelDescription fmiVersion="2.0" modelName="M" guid="{0}">'
                   '<CoSimulation modelIdentifier="M"/></fmiModelDescription>')
    return path


def test_a_refused_request_says_why_and_leaves_the_fmu_as_it_was(tmp_path, capsys):
    fmu = fmu_without_sources(tmp_path / "M.fmu")
    before = fmu.read_bytes()
    assert main(["--platform", "aarch64-linux", "--fmu", str(fmu)]) == 1
    err = capsys.readouterr().err
    assert "lists no C sources" in err and "Traceback" not in err
    assert err.count("\n") == 1, err  # one line
    assert fmu.read_bytes() == before
    assert main(["--platform", "aarch64-linux", "--fmu", str(tmp_path / "none.fmu")]) == 1
    assert "no FMU at" in capsys.readouterr().err
    for argv, said in ((["--fmu", str(fmu)], "--fmu needs --platform"),
                       (["--platform", "sparc-solaris", "--fmu", str(fmu)], "invalid choice")):
        with pytest.raises(SystemExit) as stop:
            main(argv)
        assert stop.value.code == 2 and said in capsys.readouterr().err
    assert fmu.read_bytes() == before


def test_a_failed_compile_leaves_the_fmu_as_it_was(tmp_path, capsys):
    """An FMU whose listed source does not compile: the compiler's message, the FMU
    untouched, no temporary file left beside it."""
    fmu = tmp_path / "M.fmu"
    with zipfile.ZipFile(fmu, "w") as z:
        z.writestr("modelDescription.xml",
                   '<fmiModelDescription fmiVersion="3.0" modelName="M" '
                   'instantiationToken="{0}"><CoSimulation modelIdentifier="M"/>'
                   '</fmiModelDescription>')
        z.writestr("sources/buildDescription.xml",
                   '<fmiBuildDescription fmiVersion="3.0"><BuildConfiguration '
                   'modelIdentifier="M"><SourceFileSet><SourceFile name="m.c"/>'
                   '</SourceFileSet></BuildConfiguration></fmiBuildDescription>')
        z.writestr("sources/m.c", "int f(void) { return undeclared; }\n")
    before = fmu.read_bytes()
    assert main(["--platform", "aarch64-linux", "--fmu", str(fmu)]) == 1
    err = capsys.readouterr().err
    assert "compiling M.fmu's sources for aarch64-linux failed" in err
    assert re.search(r"undeclared", err)
    assert fmu.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["M.fmu"]
