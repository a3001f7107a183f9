"""The C compiler of the build: ``$CC``, gcc or cc on ``PATH``, else the clang of the
``ziglang`` package (a dependency of the project, so a fresh clone builds without a system
compiler)."""

from __future__ import annotations

import atexit
import hashlib
import os
import platform
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import threading
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path


class BuildError(RuntimeError):
    """The build cannot go on; the message says why and what to do."""


#: ziglang's clang targets the build machine's CPU unless told otherwise: a baseline CPU
#: (instructions every host of the architecture has) with glibc, so that a library built with
#: ziglang and one built with gcc call the same libm and compute the same numbers.
ZIG_TARGET = {"x86_64": "x86_64-linux-gnu", "aarch64": "aarch64-linux-gnu"}
_ZIG_WRAPPER: list[str] = []


def c_compiler() -> str:
    """The C compiler of the build, as one executable: ``$CC`` if set, else ``gcc`` or ``cc``
    on ``PATH``, else the clang of the ``ziglang`` package (``python -m ziglang cc``, through a
    small wrapper script).  BuildError when none works."""
    requested = os.environ.get("CC")
    if requested:
        found = shutil.which(requested)
        if found is None:
            raise BuildError(f"CC = {requested!r} is not an executable on PATH; allowed: a C "
                             "compiler such as gcc, or unset CC to use gcc or ziglang's clang")
        return found
    for name in ("gcc", "cc"):
        found = shutil.which(name)
        if found:
            return found
    if _ZIG_WRAPPER:
        return _ZIG_WRAPPER[0]
    try:
        import ziglang  # noqa: F401  (only its presence: it runs as python -m ziglang)
    except ImportError:
        raise BuildError(
            "no C compiler: gcc (or cc) is not on PATH and the ziglang package is not "
            "installed. Install one: `pip install ziglang` (a dependency of this project: "
            "reinstall it with `pip install -e .`) or your system's gcc (Debian/Ubuntu: "
            "`apt-get install gcc`), or set CC to a C compiler") from None
    folder = Path(tempfile.mkdtemp(prefix="drive_rattle_cc_"))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    target = ZIG_TARGET.get(platform.machine())
    args = ["-target", target] if target else []
    wrapper = folder / "zig-cc"
    wrapper.write_text(
        "#!/bin/sh\n# ziglang's C compiler (drive-rattle build: no gcc on PATH)\n"
        f"exec {shlex.join([sys.executable, '-m', 'ziglang', 'cc', *args])} \"$@\"\n",
        encoding="utf-8")
    wrapper.chmod(0o755)
    probe = subprocess.run([str(wrapper), "--version"], capture_output=True, text=True)
    if probe.returncode != 0:
        raise BuildError(f"no working C compiler: gcc is not on PATH and ziglang's clang "
                         f"fails:\n{probe.stderr}")
    _ZIG_WRAPPER.append(str(wrapper))
    return str(wrapper)


#: IEEE arithmetic without contraction (docs/model_library.md: "Reproducible numbers"),
#: warnings on: the flags of every C the build compiles for an FMU or the library.
IEEE_CFLAGS = ("-std=c99", "-O2", "-fno-fast-math", "-ffp-contract=off", "-Wall", "-Wextra")
#: The platforms of the model library the pythonfmu FMUs ship (``library``), by FMI 2.0
#: folder: the ziglang target of each (None: the build machine's compiler).  The FMUs' own
#: binaries: ``platforms``.
TARGETS = {"linux64": None, "win64": "x86_64-windows-gnu"}


def zig_cc(target: str) -> list[str]:
    """ziglang's ``zig cc -target <target> -g0`` (the ziglang package, a dependency; its
    executable on POSIX, ``python -m ziglang`` elsewhere): the cross-compiler of every binary
    but the build machine's own; no debug information, as gcc leaves none by default.  zig
    builds a target's C runtime once per optimization mode of the link (the link gets the
    compile's ``-O2``: :func:`at_link`) and once per place of ziglang's lib folder relative to
    the working folder: the build runs zig in a temporary folder, never in a folder that holds
    the lib folder, such as a clone with its .venv, where a program linked there would build
    a second C runtime (minutes of CPU for x86_64-windows)."""
    try:
        import ziglang
    except ImportError:
        raise BuildError(f"cross-compiling for {target} needs the ziglang package: "
                         "`pip install ziglang` (a dependency of this project)") from None
    if os.name == "posix":  # its executable itself (what ``python -m ziglang`` execs): a
        # build starts it once per C file, and a Python start each time would cost seconds
        return [str(Path(ziglang.__file__).with_name("zig")), "cc", "-target", target, "-g0"]
    return [sys.executable, "-m", "ziglang", "cc", "-target", target, "-g0"]


def link_only(flag: str) -> bool:
    """Whether the compiler ``flag`` concerns the link alone (a C file compiled with ``-c``
    takes every other flag; with clang's -Werror a link-only one would fail the compile)."""
    return flag == "-shared" or flag.startswith(("-Wl,", "-L", "-l"))


def at_link(flag: str) -> bool:
    """Whether ``flag`` is also given to the link: the link-only ones, and those that choose
    the runtime, optimization or debug information the objects were compiled for.  (zig
    builds the target's C runtime in the optimization mode of the link: a link without the
    compile's ``-O2`` is a Debug link, which builds a second C runtime, compiler-rt and UBSan
    runtime for every target, about 30 s of CPU each and over two minutes for
    x86_64-windows.)"""
    return link_only(flag) or flag == "-pthread" or flag.startswith(
        ("-fsanitize", "-fno-sanitize", "-g", "-O"))


def run_compiler(cmd: list[str], cwd: Path, output: Path, doing: str) -> Path:
    """Run the compiler command ``cmd`` in ``cwd``, which writes ``output``; RuntimeError with
    the command and the compiler's output when it is missing, fails or writes nothing."""
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, check=False, cwd=cwd)
    except OSError as exc:
        raise RuntimeError(f"cannot run the C compiler {cmd[0]!r}: {exc}") from exc
    if proc.returncode != 0 or not output.is_file():
        raise RuntimeError(f"{doing} failed (exit {proc.returncode}): {' '.join(cmd)}\n"
                           f"{proc.stdout}{proc.stderr}")
    return output


#: The environment variable naming a folder of compiled objects kept by what they are
#: compiled from (:func:`object_keys`), shared by every build that names it, in any process:
#: a build finds there what another compiled from the same inputs.  Unset: none is kept.
OBJECT_CACHE = "DRIVE_RATTLE_OBJECT_CACHE"
_INCLUDE_OPTIONS = ("-I", "-iquote", "-isystem", "-idirafter")


def _place_arguments(flags: Sequence[str]) -> dict[int, tuple[str, str]]:
    """{position in ``flags``: (option, path)} of every argument that names a place: a folder
    of the include path (``-I<dir>`` or ``-I <dir>``, and likewise -iquote, -isystem,
    -idirafter: the option ``-I<`` when joined) or a header given by ``-include <file>``."""
    found, args, k = {}, list(flags), 0
    while k < len(args):
        if args[k] in (*_INCLUDE_OPTIONS, "-include") and k + 1 < len(args):
            found[k + 1] = (args[k], args[k + 1])
            k += 1
        elif args[k].startswith("-I") and len(args[k]) > 2:
            found[k] = ("-I<", args[k][2:])
        k += 1
    return found


def include_folders(flags: Sequence[str], cwd: Path) -> list[Path]:
    """The folders that ``flags`` add to the include path (``-I<dir>`` or ``-I <dir>``, and
    likewise -iquote, -isystem, -idirafter), relative ones taken from ``cwd``."""
    return [cwd / path for option, path in _place_arguments(flags).values()
            if option != "-include"]


def _placeless(flags: Sequence[str]) -> list[str]:
    """``flags`` with each folder of the include path as its rank in that path, and a header
    given by ``-include`` without its place: what the compile reads from them is in the key
    by name and bytes (:class:`_Includes`), so the same files staged in another folder
    compile alike."""
    out, rank = list(flags), 0
    for k, (option, _) in _place_arguments(flags).items():
        if option == "-include":  # its bytes are in the key
            out[k] = "<forced header>"
        else:
            out[k] = f"{'-I' if option == '-I<' else ''}<include folder {rank}>"
            rank += 1
    return out


def compiler_identity(compiler: Sequence[str]) -> str:
    """The compiler's executable as found on ``PATH``, with its size and modification time:
    an upgraded compiler at the same path is another compiler."""
    exe = shutil.which(str(compiler[0])) or str(compiler[0])
    try:
        stat = os.stat(exe)
    except OSError:
        return exe
    return f"{os.path.realpath(exe)} {stat.st_size} {stat.st_mtime_ns}"


def _folder_files(folder: Path) -> bytes:
    """The name and bytes of every file in ``folder`` (not its subfolders), in name order."""
    files = sorted(f for f in folder.iterdir() if f.is_file()) if folder.is_dir() else []
    return b"".join(f"\0{f.name}\0".encode() + f.read_bytes() for f in files)


#: An include of a file named in quotes or angle brackets (``#include``, ``#include_next``,
#: ``#import``), and any include line at all: one that names no file (a computed include)
#: is resolved only as the preprocessor runs, as is ``__has_include``.
_NAMED_INCLUDE = re.compile(
    rb'^[ \t]*#[ \t]*(?:include|include_next|import)[ \t]*(?:"([^"\n]+)"|<([^>\n]+)>)', re.M)
_ANY_INCLUDE = re.compile(rb"^[ \t]*#[ \t]*(?:include|include_next|import)\b", re.M)


class _Includes:
    """What the files of one compile call include from the project's folders (the source's
    own and those of the include path), read once per call."""

    def __init__(self, folders: Sequence[Path]):
        self.folders = list(folders)
        self.texts: dict[Path, bytes] = {}

    def text(self, path: Path) -> bytes:
        if path not in self.texts:
            self.texts[path] = path.read_bytes()
        return self.texts[path]

    def reached(self, source: Path) -> tuple[bytes, set[Path], bool]:
        """(the name, place and bytes of every file that ``source`` includes from its own
        folder, the including file's folder or a folder of the include path, directly or
        through such a file, wherever the name is found and in every branch of a conditional
        (more than the compile reads, never less); the folders of those files; whether one
        of them includes what only the preprocessor resolves: a computed include,
        ``__has_include``)."""
        source = source.resolve()
        found, seen, todo, computed = [], {source}, [source], False
        while todo:
            including = todo.pop(0)
            text = self.text(including)
            named = _NAMED_INCLUDE.findall(text)
            if len(named) != len(_ANY_INCLUDE.findall(text)) or b"__has_include" in text:
                computed = True
            for quoted, angled in named:
                name = (quoted or angled).decode("utf-8", "surrogateescape")
                # place 0: the including file's folder (where a quoted name is looked up
                # first), 1: the source's, then the include path's
                for place, folder in enumerate([including.parent, source.parent,
                                                *self.folders]):
                    path = folder / name
                    if path.is_file():
                        found.append(f"\0{place}\0{name}\0".encode() + self.text(path))
                        if path.resolve() not in seen:
                            seen.add(path.resolve())
                            todo.append(path.resolve())
        return b"".join(found), {f.parent for f in seen}, computed


def object_keys(compiler: Sequence[str], flags: Sequence[str], sources: Sequence[Path],
                cwd: Path) -> list[str]:
    """What each of ``sources`` is compiled from, as a digest: the compiler command and
    executable (:func:`compiler_identity`), the compile's flags without the places of the
    include path's folders (:func:`_placeless`), the bytes of a header given by
    ``-include``, the source's bytes, and the name, place and bytes of every file it
    includes from its folder or the include path (:meth:`_Includes.reached`).  Where an
    include is computed, every file of those folders and of the included files' folders is
    in the key instead.  A header found elsewhere is a system header, the same for every
    build on one machine.  So a source compiles alike beside headers it does not include
    (an FMU's generated one), in any folder.  What the sources share is read once."""
    common = hashlib.sha256(repr((list(map(str, compiler)), compiler_identity(compiler),
                                  _placeless(flags))).encode())
    folders = list(dict.fromkeys(include_folders(flags, cwd)))
    includes = _Includes(folders)
    # headers included before each source's first line: the same for every source
    forced = [(cwd / path).resolve() for option, path in _place_arguments(flags).values()
              if option == "-include"]
    for header in forced:
        common.update(b"\0-include\0" + includes.text(header))
    forced_reached = [includes.reached(header) for header in forced]
    keys = []
    for source in (Path(s).resolve() for s in sources):
        digest = common.copy()
        reached = [*forced_reached, includes.reached(source)]
        if any(computed for _, _, computed in reached):  # every file the compile could read
            places = {source.parent, *folders}.union(*(seen for _, seen, _ in reached))
            digest.update(b"\0folders\0" + b"".join(
                _folder_files(f) for f in sorted(places)))
        else:
            digest.update(b"\0includes\0" + b"\0".join(found for found, _, _ in reached))
        digest.update(b"\0source\0" + includes.text(source))
        keys.append(digest.hexdigest())
    return keys


def compile_objects(cc, flags, sources, folder: Path, what: str) -> list[Path]:
    """Compile each of ``sources`` alone (``-c``) with ``cc`` (an executable, or a command as a
    list) and ``flags`` into ``folder/<n>-<stem>.o``, one compiler per core at a time, and
    return the objects in the order of ``sources``.  With the environment's
    ``DRIVE_RATTLE_OBJECT_CACHE`` (:data:`OBJECT_CACHE`), an object compiled before from the
    same inputs is copied from that folder instead, and each new one is kept there.
    RuntimeError with the command and the compiler's output when the compiler is missing or
    fails on a file."""
    compiler = [cc] if isinstance(cc, (str, Path)) else list(cc)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    jobs = [(Path(source).resolve(), folder / f"{n}-{Path(source).stem}.o")
            for n, source in enumerate(sources)]
    compile_flags = [f for f in flags if not link_only(f)]
    cache = os.environ.get(OBJECT_CACHE)
    keys = (object_keys(compiler, compile_flags, [source for source, _ in jobs], folder)
            if cache else [None] * len(jobs))

    def compile_one(job):
        (source, obj), key = job
        kept = None
        if key is not None:
            kept = Path(cache) / f"{key}.o"
            if kept.is_file():
                shutil.copyfile(kept, obj)
                return obj
        # in the objects' folder: a cross-compiler may leave files beside its output
        run_compiler([*compiler, *compile_flags, "-c", "-o", str(obj), str(source)], folder,
                     obj, f"compiling {what}")
        if kept is not None:  # whole or not at all: a reader never sees half an object
            partial = kept.with_name(f".{kept.name}.{os.getpid()}.{threading.get_ident()}")
            try:
                kept.parent.mkdir(parents=True, exist_ok=True)
                shutil.copyfile(obj, partial)
                os.replace(partial, kept)
            except OSError as exc:
                raise RuntimeError(
                    f"{OBJECT_CACHE} = {cache!r}: cannot keep a compiled object there "
                    f"({exc.strerror or exc}); allowed: a folder this user can write, or "
                    f"unset {OBJECT_CACHE}") from None
        return obj

    with ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as pool:
        return list(pool.map(compile_one, zip(jobs, keys, strict=True)))


def compile_library(cc, flags, sources, out_path: Path, what: str, libs=(),
                    objects: Sequence[Path] = ()) -> Path:
    """Compile ``sources`` with ``cc`` (an executable, or a command as a list) and ``flags``
    (each file alone, side by side: :func:`compile_objects`), linked with the already compiled
    ``objects`` and ``libs``, into the shared library ``out_path``, written atomically (a
    temporary file renamed into place).  RuntimeError with the command and the compiler's
    output when the compiler is missing or fails."""
    out = Path(out_path).resolve()
    out.parent.mkdir(parents=True, exist_ok=True)
    compiler = [cc] if isinstance(cc, (str, Path)) else list(cc)
    # in a folder of its own (a cross-compiler leaves an import library beside its output),
    # then copied next to the target and renamed into place
    with tempfile.TemporaryDirectory(prefix="drive_rattle_cc_") as scratch:
        built = Path(scratch) / out.name
        compiled = compile_objects(compiler, flags, sources, Path(scratch) / "objects", what)
        run_compiler([*compiler, *(f for f in flags if at_link(f)), "-o", str(built),
                      *(str(o) for o in compiled), *(str(Path(o).resolve()) for o in objects),
                      *libs], Path(scratch), built, f"linking {what}")
        tmp = out.with_name(f".{out.name}.{os.getpid()}.tmp")
        shutil.copy2(built, tmp)
    os.replace(tmp, out)
    return out
