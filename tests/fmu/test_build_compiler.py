"""The build's C compiler: gcc, else the clang of the ziglang package, else a clear message
(the pythonfmu FMUs: the model library and the status shim)."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from drive_rattle_cosim.harness import CoSimulation
from drive_rattle_cosim.masters import COUPLING

ROOT = Path(__file__).resolve().parents[2]
BUILD = ROOT / "build_fmu.py"


def build_without_gcc(out: Path, hide_ziglang: bool = False, **env) -> subprocess.CompletedProcess:
    """`python build_fmu.py --out OUT` with nothing on PATH (no gcc, no cc), optionally with
    the ziglang package made unimportable too."""
    empty = out.parent / "empty_path"
    empty.mkdir(exist_ok=True)
    code = ("import runpy, sys\n"
            + ("sys.modules['ziglang'] = None\n" if hide_ziglang else "")
            + f"sys.argv = ['build_fmu.py', '--out', {str(out)!r}, '--no-fmutool', "
            "'--no-native', '--no-fmi3']\n"
            + f"runpy.run_path({str(BUILD)!r}, run_name='__main__')\n")
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=600, env={"HOME": os.environ.get("HOME", "/tmp"),
                                            "PATH": str(empty), **env})


@pytest.mark.slow
def test_without_gcc_the_build_uses_ziglang_and_runs_the_same(fmus, tmp_path):
    pytest.importorskip("ziglang")
    out = tmp_path / "dist"
    run = build_without_gcc(out)
    assert run.returncode == 0, run.stdout + run.stderr
    assert (out / "DriveRattle.ssp").is_file() and (out / "DriveRattle_outputs.ssp").is_file()
    # The model library and the shim compiled by ziglang's clang compute what gcc's do, bit
    # for bit.
    results = []
    for folder in (out, fmus["GearMeshRattle"].parent):
        with CoSimulation(folder / "GearMeshRattle.fmu", folder / "Driveline.fmu") as sim:
            r = sim.run(0.06, [*COUPLING, "GearMeshRattle.mesh.W", "GearMeshRattle.mesh.h",
                               "GearMeshRattle.mesh.impacts_drive"])
        results.append(r.columns)
    assert results[0]["GearMeshRattle.mesh.impacts_drive"][-1] > 0  # contacts and impacts
    assert results[0] == results[1]


def test_without_any_compiler_the_build_says_what_to_install(tmp_path):
    run = build_without_gcc(tmp_path / "dist", hide_ziglang=True)
    assert run.returncode == 1
    assert "Traceback" not in run.stderr
    assert "no C compiler" in run.stderr and "pip install ziglang" in run.stderr
    assert "apt-get install gcc" in run.stderr


def test_a_cc_that_is_not_there_is_named(tmp_path):
    run = build_without_gcc(tmp_path / "dist", CC="no-such-cc")
    assert run.returncode == 1 and "Traceback" not in run.stderr
    assert "CC = 'no-such-cc' is not an executable" in run.stderr


def test_each_file_is_compiled_alone_and_a_failure_names_it(tmp_path):
    from drive_rattle_build.compiler import c_compiler, compile_library

    good, bad = tmp_path / "good.c", tmp_path / "bad.c"
    good.write_text("int rattle_answer(void) { return 42; }\n", encoding="utf-8")
    bad.write_text("int rattle_broken(void) { return undeclared; }\n", encoding="utf-8")
    out = compile_library(c_compiler(), ["-std=c99", "-O2", "-fPIC", "-shared", "-Werror"],
                          [good], tmp_path / "libgood.so", "good")
    assert "rattle_answer" in subprocess.run(["nm", "-D", str(out)], capture_output=True,
                                             text=True, check=True).stdout
    with pytest.raises(RuntimeError, match=r"compiling two files failed .*bad\.c"):
        compile_library(c_compiler(), ["-std=c99", "-fPIC", "-shared"], [good, bad],
                        tmp_path / "libbad.so", "two files")
    assert not (tmp_path / "libbad.so").exists()


def test_the_link_gets_the_flags_of_the_link_and_the_compile_the_others():
    from drive_rattle_build.compiler import at_link, link_only

    assert [f for f in ("-shared", "-lm", "-Wl,-z,defs", "-L/x") if link_only(f)] == [
        "-shared", "-lm", "-Wl,-z,defs", "-L/x"]
    for flag in ("-Werror", "-Wall", "-std=c99", "-DRM=1", "-I", "-fPIC",
                 "-fvisibility=hidden", "-ffp-contract=off"):
        assert not link_only(flag) and not at_link(flag), flag
    for flag in ("-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-g", "-g0",
                 "-pthread", "-shared", "-O2", "-O0", "-Os"):
        assert at_link(flag), flag
    assert not link_only("-O2")  # also compiles


@pytest.mark.slow
def test_the_model_library_is_compiled_once_per_platform_and_content(tmp_path):
    """``shared_objects`` gives the same objects for the same files, headers and flags, from
    any folder; a changed header or flag compiles them again."""
    from drive_rattle_build.paths import model_files
    from drive_rattle_build.platforms import build_machine, shared_objects

    platform = build_machine()
    copies = []
    for k in range(2):
        folder = tmp_path / f"copy{k}"
        folder.mkdir()
        for path in model_files("*.[ch]"):
            (folder / path.name).write_bytes(path.read_bytes())
        copies.append(folder)

    def objects(folder, flags=("-Werror",)):
        return shared_objects(platform, [folder / p.name for p in model_files("*.c")],
                              [folder / p.name for p in model_files("*.h")], flags=flags)

    first = objects(copies[0])
    assert [o.stem.split("-", 1)[1] for o in first] == [p.stem for p in model_files("*.c")]
    assert objects(copies[1]) == first
    assert objects(copies[0], ("-Werror", "-DRATTLE_TEST_FLAG=1")) != first
    header = copies[1] / "rm_private.h"
    header.write_text(header.read_text(encoding="utf-8") + "\n/* changed */\n",
                      encoding="utf-8")
    assert objects(copies[1]) != first


def test_the_object_cache_reuses_an_object_only_for_the_same_inputs(tmp_path, monkeypatch):
    """With DRIVE_RATTLE_OBJECT_CACHE, an object compiled from the same compiler, flags,
    source and headers, in another folder, is the kept one and the compiler does not run; a
    changed header, flag, source or compiler executable, or no cache at all, runs it."""
    from drive_rattle_build.compiler import OBJECT_CACHE, compile_objects

    calls = tmp_path / "calls"
    counting = tmp_path / "counting-cc"  # the system's compiler, each run noted
    counting.write_text(f"#!/bin/sh\necho \"$@\" >> {calls}\nexec gcc \"$@\"\n",
                        encoding="utf-8")
    counting.chmod(0o755)

    def copy(name: str, header: str = "#define ANSWER 42\n") -> Path:
        folder = tmp_path / name
        folder.mkdir()
        (folder / "answer.h").write_text(header, encoding="utf-8")
        (folder / "answer.c").write_text(
            '#include "answer.h"\nint rattle_answer(void) { return ANSWER; }\n',
            encoding="utf-8")
        return folder / "answer.c"

    def compiled(source: Path, flags=("-O2", "-fPIC")) -> tuple[bytes, int]:
        before = calls.read_text().count("\n") if calls.exists() else 0
        [obj] = compile_objects(str(counting), list(flags), [source],
                                source.parent / "objects", "the answer")
        return obj.read_bytes(), calls.read_text().count("\n") - before

    cache = tmp_path / "cache"
    monkeypatch.setenv(OBJECT_CACHE, str(cache))
    first, ran = compiled(copy("a"))
    assert ran == 1 and len(list(cache.glob("*.o"))) == 1
    assert compiled(copy("b")) == (first, 0)  # the same inputs elsewhere: kept
    assert compiled(copy("c", "#define ANSWER 43\n"))[1] == 1  # a header changed
    assert compiled(tmp_path / "a" / "answer.c", ("-O1", "-fPIC"))[1] == 1  # a flag changed
    other = copy("d")
    other.write_text(other.read_text() + "int rattle_other(void) { return 1; }\n")
    assert compiled(other)[1] == 1  # the source changed
    stat = counting.stat()  # the compiler replaced at the same path (an upgrade)
    os.utime(counting, ns=(stat.st_atime_ns, stat.st_mtime_ns + 1_000_000_000))
    assert compiled(copy("f")) == (first, 1)
    assert len(list(cache.glob("*.o"))) == 5 and not [
        p for p in cache.iterdir() if p.name.startswith(".")]  # no partial object left
    monkeypatch.delenv(OBJECT_CACHE)
    assert compiled(copy("g")) == (first, 1)  # no cache: compiled, the same object


def test_the_object_keys_follow_what_a_source_includes(tmp_path):
    """A source staged in another folder, given with its own -I and beside a header it does
    not include (an FMU's generated one), has the same key; a change in a header it reaches
    through another, or in any header beside a computed include, is another key."""
    from drive_rattle_build.compiler import object_keys

    def staged(name: str, inner: str = "#define INNER 1\n", extra: str = "",
               source: str = '#include "outer.h"\n#include <math.h>\n') -> Path:
        folder = tmp_path / name
        (folder / "include").mkdir(parents=True)
        (folder / "include" / "outer.h").write_text('#include "inner.h"\n#define OUTER 1\n')
        (folder / "include" / "inner.h").write_text(inner)
        (folder / "s.c").write_text(source + "int f(void) { return OUTER + INNER; }\n")
        if extra:
            (folder / "config.h").write_text(extra)
        return folder

    def key(folder: Path) -> str:
        [k] = object_keys(["gcc"], ["-O2", "-I", str(folder / "include"), f"-I{folder}"],
                          [folder / "s.c"], folder)
        return k

    first = key(staged("a"))
    assert key(staged("b", extra="#define MODEL 2\n")) == first
    assert key(staged("c", inner="#define INNER 2\n")) != first
    missing = staged("h")  # a header the staged sources lack (an incomplete wheel)
    (missing / "include" / "inner.h").unlink()
    assert key(missing) != first
    computed = '#define OUTER_H "outer.h"\n#include OUTER_H\n'
    plain = key(staged("d", source=computed))
    assert key(staged("e", source=computed)) == plain
    assert key(staged("f", source=computed, extra="#define MODEL 2\n")) != plain
    looped = staged("g", source='#include "loop.h"\n')  # a header that includes itself
    (looped / "loop.h").write_text('#include "../g/loop.h"\n')
    assert len(key(looped)) == 64


def test_an_object_cache_that_cannot_be_written_is_named(tmp_path, monkeypatch):
    from drive_rattle_build.compiler import OBJECT_CACHE, c_compiler, compile_objects

    source = tmp_path / "answer.c"
    source.write_text("int rattle_answer(void) { return 42; }\n", encoding="utf-8")
    blocker = tmp_path / "a_file"  # a file where the folder should be: no user can write it
    blocker.write_text("", encoding="utf-8")
    monkeypatch.setenv(OBJECT_CACHE, str(blocker / "cache"))
    with pytest.raises(RuntimeError, match=r"DRIVE_RATTLE_OBJECT_CACHE = '.*a_file/cache': "
                                           r"cannot keep a compiled object there .*allowed: a "
                                           r"folder this user can write"):
        compile_objects(c_compiler(), ["-O2"], [source], tmp_path / "objects", "the answer")


def test_no_file_of_the_model_library_includes_the_fmus_config_header():
    # What shared_objects relies on: the FMU's generated header (its model identifier and
    # GUID) reaches only the face's functions, so the library compiles alike for every FMU.
    from drive_rattle_build.native import CONFIG_HEADER
    from drive_rattle_build.paths import model_files

    for path in model_files("*.[ch]"):
        assert CONFIG_HEADER not in path.read_text(encoding="utf-8"), path.name
