"""Why the pythonfmu FMUs ship no Windows binary (docs/tools.md, Windows): pythonfmu's generic
win64 DLL, which its builder adds to every FMU, imports ``python3.dll`` and the VC++ 2015-2022
runtime, and without them Windows refuses to load it (error 126, ERROR_MOD_NOT_FOUND), where
the native FMU's DLL loads.  Measured under wine, which has neither; skipped without wine."""

import subprocess
import zipfile
from pathlib import Path

import pytest

from drive_rattle_build.compiler import zig_cc

from ..faces.hosts import windows_path, wine

LOADER = r"""
#include <windows.h>
#include <stdio.h>
int main(int argc, char** argv) {
    HMODULE h = LoadLibraryA(argv[1]);
    if (!h) { printf("error %lu\n", GetLastError()); return 1; }
    printf("loaded, fmi2DoStep %s\n", GetProcAddress(h, "fmi2DoStep") ? "found" : "missing");
    return 0;
}
"""


def pythonfmu_win64_dll() -> Path:
    import pythonfmu

    return Path(pythonfmu.__file__).parent / "resources" / "binaries" / "win64" / \
        "pythonfmu-export.dll"


def test_pythonfmus_win64_dll_needs_python_and_the_vc_runtime():
    imports = pythonfmu_win64_dll().read_bytes().lower()
    for dll in (b"python3.dll", b"msvcp140.dll", b"vcruntime140.dll", b"vcruntime140_1.dll"):
        assert dll in imports, dll


@pytest.mark.cross
def test_it_does_not_load_without_them_where_the_native_dll_does(shipped_native_fmus, wine_env,
                                                                 tmp_path):
    exe = tmp_path / "load.exe"
    source = tmp_path / "load.c"
    source.write_text(LOADER)
    # -O2, in a folder outside the clone, as every Windows program and DLL of the tests:
    # zig builds its C runtime once per optimization mode of the link and per place of its
    # lib folder relative to the working folder, and another would cost a second one
    # (minutes of CPU on a new machine: compiler.zig_cc)
    subprocess.run([*zig_cc("x86_64-windows-gnu"), "-O2", "-o", str(exe), str(source)],
                   check=True, capture_output=True, cwd=tmp_path)
    with zipfile.ZipFile(shipped_native_fmus["GearMeshRattle"]) as z:
        native = Path(z.extract("binaries/win64/GearMeshRattle.dll", tmp_path))

    def load(dll: Path) -> str:
        run = subprocess.run([wine(), str(exe), windows_path(dll)], env=wine_env, cwd=tmp_path,
                             capture_output=True, text=True, timeout=600)
        return run.stdout.strip()

    assert load(pythonfmu_win64_dll()) == "error 126"
    assert load(native) == "loaded, fmi2DoStep found"
