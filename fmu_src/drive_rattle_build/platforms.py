"""The platforms the FMUs' C compiles for, and a binary for one of them compiled from an FMU's
own sources into that FMU (``drive-rattle-build --platform NAME --fmu FMU``).

A platform is named by its FMI 3.0 platform tuple ``<arch>-<sys>`` (FMI 3.0.2, section
2.5.1.4.1, "Platform Tuple Definition"), the folder below ``binaries/`` of an FMI 3.0 FMU.  FMI
2.0 names four folders of its own, "32" and "64" standing for x86 (FMI 2.0.5, section 2.3):
``linux64``, ``win64``, ``darwin64`` for the x86-64 tuples; for any other platform FMI 2.0.4
and later say to use the FMI 3.0 platform tuple (so ``aarch64-linux``, ``aarch64-darwin``).

Every binary except the build machine's is cross-compiled by the clang of the ``ziglang``
package (a dependency).  What ships where (tested here; docs/native_fmu.md, docs/fmi3.md):

* the FMI 3.0 FMUs: ``x86_64-linux``, ``x86_64-windows`` and ``aarch64-linux`` (the last run
  under qemu-user in the tests);
* the FMI 2.0 native FMUs: ``linux64`` and ``win64`` only.  FMI 2.0 importers load
  ``binaries/linux64/`` on aarch64 Linux too (fmpy 0.3.20 to 0.3.32 ``fmpy.platform``, the
  Reference-FMUs' fmusim ``FMI_PLATFORM``, the FMI Library's ``FMI_PLATFORM`` for every LP64
  Linux), where the x86-64 binary is, so none of them would find an ``aarch64-linux`` one;
  on ARM use the FMI 3.0 FMUs, which fmpy and fmusim load from ``binaries/aarch64-linux/``;
* macOS (``x86_64-darwin``, ``aarch64-darwin``): nothing here can run a Mach-O binary, so
  none is shipped; :func:`add_binary` cross-compiles one on request, untested.
"""

from __future__ import annotations

import atexit
import hashlib
import os
import platform as host
import shutil
import sys
import tempfile
import threading
import zipfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from xml.etree import ElementTree

from .compiler import (
    IEEE_CFLAGS,
    BuildError,
    c_compiler,
    compile_library,
    compile_objects,
    zig_cc,
)
from .paths import model_files


@dataclass(frozen=True)
class Platform:
    """One platform: its FMI 3.0 platform tuple, its folder in an FMI 2.0 FMU, the ziglang
    target that cross-compiles it and the suffix of a shared library there."""

    name: str  # FMI 3.0 platform tuple: binaries/<name>/ of an FMI 3.0 FMU
    fmi2_folder: str  # binaries/<fmi2_folder>/ of an FMI 2.0 FMU
    zig_target: str
    suffix: str

    @property
    def system(self) -> str:
        return self.name.split("-", 1)[1]

    def folder(self, fmi_major: int) -> str:
        """The folder below ``binaries/`` in an FMU of FMI version ``fmi_major``."""
        return self.name if fmi_major >= 3 else self.fmi2_folder


PLATFORMS = {p.name: p for p in (
    Platform("x86_64-linux", "linux64", "x86_64-linux-gnu", ".so"),
    Platform("aarch64-linux", "aarch64-linux", "aarch64-linux-gnu", ".so"),
    Platform("x86_64-windows", "win64", "x86_64-windows-gnu", ".dll"),
    Platform("x86_64-darwin", "darwin64", "x86_64-macos", ".dylib"),
    Platform("aarch64-darwin", "aarch64-darwin", "aarch64-macos", ".dylib"),
)}
#: The binaries each kind of FMU ships (every one run by the tests).
FMI2_SHIPPED = ("x86_64-linux", "x86_64-windows")
FMI3_SHIPPED = ("x86_64-linux", "x86_64-windows", "aarch64-linux")
#: Platforms whose binaries nothing here can run: built only on request, and said so.
UNTESTED = ("x86_64-darwin", "aarch64-darwin")
UNTESTED_NOTE = ("untested: nothing on the build machine runs a macOS binary, so this one "
                 "has been compiled but never loaded or run")


def platform_named(name: str) -> Platform:
    """The platform of FMI 3.0 platform tuple ``name``; BuildError naming the allowed ones."""
    try:
        return PLATFORMS[name]
    except KeyError:
        raise BuildError(f"unknown platform {name!r}; allowed: {', '.join(PLATFORMS)} (FMI "
                         "3.0 platform tuples)") from None


def build_machine() -> str | None:
    """The platform tuple of the machine the build runs on (None: not one of PLATFORMS)."""
    system = {"linux": "linux", "win32": "windows", "darwin": "darwin"}.get(sys.platform)
    arch = {"x86_64": "x86_64", "amd64": "x86_64", "aarch64": "aarch64",
            "arm64": "aarch64"}.get(host.machine().lower())
    name = f"{arch}-{system}"
    return name if name in PLATFORMS else None


def toolchain(platform: str, cc: str | Sequence[str] | None = None,
              flags: Sequence[str] = ()) -> tuple[str | list[str], list[str], list[str]]:
    """(compiler, flags, libraries) of a shared library for ``platform``: ``cc`` (default the
    build's compiler, ``compiler.c_compiler``) on the build machine's own platform, else
    ziglang's clang for the platform's target; IEEE arithmetic without contraction
    (``IEEE_CFLAGS``), only the FMI functions exported (the standard's headers mark them),
    ``flags`` added."""
    target = platform_named(platform)
    if platform == build_machine():
        compiler = cc or c_compiler()
        options = []
    else:
        compiler, options = zig_cc(target.zig_target), []  # with -g0, as gcc's default
    if target.system != "windows":
        options += ["-fPIC", "-fvisibility=hidden"]
    libs = ["-lm"] if target.system == "linux" else []  # libm is in libSystem and the CRT
    return compiler, [*IEEE_CFLAGS, *options, "-shared", *flags], libs


def compile_for(platform: str, files: Sequence[Path], include: Path, out: Path,
                cc: str | Sequence[str] | None = None, flags: Sequence[str] = (),
                what: str = "the FMU", objects: Sequence[Path] = ()) -> Path:
    """Compile the C ``files`` (headers in ``include``) with :func:`toolchain` into the
    shared library ``out`` for ``platform``, linked with the already compiled ``objects``
    (:func:`shared_objects`).  BuildError with the compiler's output."""
    compiler, options, libs = toolchain(platform, cc, flags)
    try:
        return compile_library(compiler, [*options, "-I", str(Path(include).resolve())], files,
                               Path(out), f"{what} for {platform}", libs=libs,
                               objects=objects)
    except RuntimeError as err:
        raise BuildError(str(err)) from None


def compile_face_binary(platform: str, sources: Path, glue: Sequence[str], out: Path,
                        cc: str | Sequence[str] | None, flags: Sequence[str], what: str) -> Path:
    """An FMU's binary for ``platform`` from its staged ``sources`` folder: the model library
    (``paths.model_files``, compiled once per process for all FMUs alike:
    :func:`shared_objects`) linked with the face's ``glue`` files, compiled for this FMU (its
    generated config header).  BuildError with the compiler's output."""
    sources = Path(sources)
    objects = shared_objects(platform, [sources / p.name for p in model_files("*.c")],
                             [sources / p.name for p in model_files("*.h")], cc, flags)
    return compile_for(platform, [sources / name for name in glue], sources, Path(out), cc,
                       flags, what, objects)


#: The objects :func:`shared_objects` compiled in this process, by what they are compiled
#: from (platform, compiler, flags and the contents of the files and headers).
_SHARED_OBJECTS: dict[str, list[Path]] = {}


def shared_objects(platform: str, files: Sequence[Path], headers: Sequence[Path],
                   cc: str | Sequence[str] | None = None, flags: Sequence[str] = (),
                   what: str = "the model library") -> list[Path]:
    """The objects of the C ``files`` for ``platform``, compiled as :func:`compile_for`
    compiles (``headers``: every file they may include, in one folder): once per process for
    the same contents, flags and compiler.  The model library is the same in every FMU of a
    build (both models, both FMI faces: it does not include the FMU's generated config
    header), so a build compiles it once per platform and links it into each.
    BuildError with the compiler's output."""
    compiler, options, _ = toolchain(platform, cc, flags)
    digest = hashlib.sha256(repr((platform, compiler, options)).encode())
    for path in sorted({*map(Path, files), *map(Path, headers)}, key=lambda p: p.name):
        digest.update(f"\0{path.name}\0".encode() + path.read_bytes())
    key = digest.hexdigest()
    with _SHARED_LOCK:  # two threads building at once compile a set once, not into one folder
        return _shared_objects(key, compiler, options, files, headers, f"{what} for {platform}")


def _shared_objects(key, compiler, options, files, headers, what) -> list[Path]:
    """:func:`shared_objects`' set ``key``, compiled on first use (under its lock)."""
    if key not in _SHARED_OBJECTS:
        if not _OBJECTS_FOLDER:
            folder = Path(tempfile.mkdtemp(prefix="drive_rattle_objects_"))
            atexit.register(shutil.rmtree, folder, ignore_errors=True)
            _OBJECTS_FOLDER.append(folder)
        include = Path(next(iter(headers), Path(files[0]))).parent.resolve()
        try:
            _SHARED_OBJECTS[key] = compile_objects(
                compiler, [*options, "-I", str(include)], files, _OBJECTS_FOLDER[0] / key[:16],
                what)
        except RuntimeError as err:
            raise BuildError(str(err)) from None
    return _SHARED_OBJECTS[key]


_OBJECTS_FOLDER: list[Path] = []
_SHARED_LOCK = threading.Lock()


# ------------------------------------------------------------------ in the FMU
def binary_member(model: str, fmi_major: int, platform: str) -> str:
    """The path of ``platform``'s binary inside an FMU of FMI version ``fmi_major``."""
    target = platform_named(platform)
    return f"binaries/{target.folder(fmi_major)}/{model}{target.suffix}"


def write_binary(archive: zipfile.ZipFile, member: str, data: bytes) -> None:
    """Write a binary into the open FMU ``archive``, executable (mode 755) when unpacked."""
    entry = zipfile.ZipInfo(member)
    entry.compress_type = zipfile.ZIP_DEFLATED
    entry.external_attr = 0o100755 << 16
    archive.writestr(entry, data)


def binaries_html(model: str, fmi_major: int, platforms: Sequence[str]) -> str:
    """The sentence of an FMU's documentation page that lists its binaries (HTML)."""
    items = [f"{name} (<code>{binary_member(model, fmi_major, name)}</code>"
             + (f"; {UNTESTED_NOTE}" if name in UNTESTED else "") + ")" for name in platforms]
    listed = ", ".join(items[:-1]) + (" and " if len(items) > 1 else "") + items[-1]
    return f"Binaries for {listed} {'are' if len(items) > 1 else 'is'} included"


def cross_compile_html(model: str) -> str:
    """The paragraph of an FMU's documentation page on building a binary for another
    platform into the FMU (HTML)."""
    return (f"<p>To add a binary for another platform to this FMU, cross-compiled from its "
            f"sources by the clang of the ziglang package, run drive-rattle's build command "
            f"(<code>pip install .</code> in its repository installs it and ziglang):</p>\n"
            f"<pre>drive-rattle-build --platform aarch64-darwin --fmu {model}.fmu</pre>\n"
            f"<p>Platforms: {', '.join(PLATFORMS)}. The macOS ones "
            f"({' and '.join(UNTESTED)}) are {UNTESTED_NOTE.split(':')[0]}: nothing where "
            "this FMU was built runs a macOS binary.</p>")


# ------------------------------------------------------------------ into a finished FMU
def fmu_sources(fmu: Path, platform: str) -> tuple[str, int, list[str]]:
    """(model identifier, FMI major version, the C files to compile) of the co-simulation FMU
    ``fmu`` for ``platform``, its sources as the FMU lists them: FMI 2.0 ``<SourceFiles>``,
    FMI 3.0 ``sources/buildDescription.xml`` (the build configuration of the model for that
    platform, else the one without a platform: FMI 3.0.2, section 2.4.10).  The files are
    compiled with the build's flags (``compile_for``: those the FMUs of this build list), not
    a source set's own options.  BuildError when the FMU lists none."""
    try:
        with zipfile.ZipFile(fmu) as z:
            root = ElementTree.fromstring(z.read("modelDescription.xml"))
            names = set(z.namelist())
            build = (ElementTree.fromstring(z.read("sources/buildDescription.xml"))
                     if "sources/buildDescription.xml" in names else None)
    except (OSError, zipfile.BadZipFile, KeyError, ElementTree.ParseError) as err:
        raise BuildError(f"{fmu} is not a readable FMU ({err}); allowed: an FMU archive "
                         "with a modelDescription.xml") from None
    major = int(root.get("fmiVersion", "0").split(".")[0])
    cosim = root.find("CoSimulation")
    if cosim is None or major not in (2, 3):
        raise BuildError(f"{fmu} is not an FMI 2.0 or 3.0 co-simulation FMU (fmiVersion "
                         f"{root.get('fmiVersion')!r}); allowed: FMI 2.0 or 3.0 with "
                         "<CoSimulation>")
    model = cosim.get("modelIdentifier")
    if major == 2:
        files = [f.get("name") for f in cosim.findall("SourceFiles/File")]
    else:
        configs = [c for c in (build.findall("BuildConfiguration") if build is not None else [])
                   if c.get("modelIdentifier") == model]
        chosen = ([c for c in configs if c.get("platform") == platform]
                  or [c for c in configs if not c.get("platform")])
        files = [f.get("name") for c in chosen[:1]
                 for s in c.findall("SourceFileSet") for f in s.findall("SourceFile")]
    if not files:
        where = ("<SourceFiles> is missing or empty" if major == 2 else
                 "sources/buildDescription.xml has no "
                 f"build configuration of {model} for {platform} or for every platform")
        raise BuildError(f"{fmu} lists no C sources to compile for {platform} ({where}); "
                         "allowed: an FMU that ships its sources, such as the native and FMI "
                         "3.0 FMUs of drive-rattle-build")
    missing = [f for f in files if f"sources/{f}" not in names]
    if missing:
        raise BuildError(f"{fmu} lists sources it does not ship: {', '.join(missing)}")
    return model, major, files


def add_binary(fmu: Path, platform: str) -> str:
    """Compile the FMU's own sources (:func:`fmu_sources`) for ``platform`` and put the
    binary into the FMU at ``binaries/<folder>/<model identifier><suffix>`` (the folder of the
    FMU's FMI version, ``Platform.folder``), replacing one that is there; the archive is
    rewritten whole and renamed into place, so a failure leaves it as it was.  Returns the
    binary's path inside the FMU."""
    fmu = Path(fmu)
    target = platform_named(platform)
    if not fmu.is_file():
        raise BuildError(f"no FMU at {fmu}; allowed: the path of an .fmu file")
    model, major, files = fmu_sources(fmu, platform)
    member = binary_member(model, major, platform)
    with tempfile.TemporaryDirectory(prefix="drive_rattle_platform_") as tmp:
        tmp = Path(tmp)
        with zipfile.ZipFile(fmu) as z:
            for name in z.namelist():
                if name.startswith("sources/") and not name.endswith("/"):
                    z.extract(name, tmp)
        sources = tmp / "sources"
        binary = compile_for(platform, [sources / f for f in files], sources,
                             tmp / f"{model}{target.suffix}", what=f"{fmu.name}'s sources")
        part = fmu.with_name(f".{fmu.name}.{os.getpid()}.part")
        try:
            with zipfile.ZipFile(fmu) as old, zipfile.ZipFile(part, "w",
                                                               zipfile.ZIP_DEFLATED) as new:
                for info in old.infolist():
                    if info.filename != member:
                        new.writestr(info, old.read(info))
                write_binary(new, member, binary.read_bytes())
            os.replace(part, fmu)
        finally:
            part.unlink(missing_ok=True)
    return member
