"""Variants of the built FMUs, for the tests: the same FMU with its C compiled with other flags
(a sanitizer build) or from patched sources (a mutant the tests must catch).

* native FMU (FMI 2.0 or 3.0): its x86-64 Linux binary compiled again from the sources the
  FMU ships (``sources/``);
* pythonfmu FMU: the model library in ``resources/drive_rattle/`` compiled again from the
  library's sources, and, with ``shim_flags``, the status shim in ``binaries/linux64``.

A patch is (file name, old text, new text): the old text must occur exactly once in the file
(else ValueError), so that a patch that no longer applies fails loudly instead of testing the
unpatched code.
"""

from __future__ import annotations

import hashlib
import shutil
import tempfile
import zipfile
from collections.abc import Sequence
from pathlib import Path
from xml.etree import ElementTree

Patch = tuple[str, str, str]

#: A shared library's flags beside the library's own (drive_rattle_build.compiler.IEEE_CFLAGS).
SHARED = ("-fPIC", "-shared", "-fvisibility=hidden")


def _description(root: Path) -> tuple[str, str, int, bool, str]:
    """(model identifier, GUID or instantiation token, number of variables, native?, FMI
    version) of an unpacked FMU."""
    md = ElementTree.parse(root / "modelDescription.xml").getroot()
    cosim = md.find("CoSimulation")
    return (cosim.get("modelIdentifier"), md.get("guid") or md.get("instantiationToken"),
            len(md.find("ModelVariables")), cosim.get("needsExecutionTool") == "false",
            md.get("fmiVersion"))


def apply_patches(folder: Path, patches: Sequence[Patch]) -> None:
    for name, old, new in patches:
        path = Path(folder) / name
        text = path.read_text(encoding="utf-8")
        if text.count(old) != 1:
            raise ValueError(f"patch of {name}: {old!r} occurs {text.count(old)} times")
        path.write_text(text.replace(old, new), encoding="utf-8")


def _compile(flags: Sequence[str], sources: Sequence[Path], include: Path, out: Path,
             defines: Sequence[str] = ()) -> Path:
    """The build's compile (each file alone, side by side: drive_rattle_build.compiler)."""
    from drive_rattle_build.compiler import IEEE_CFLAGS, compile_library

    return compile_library("gcc", [*IEEE_CFLAGS, *SHARED, *flags, *defines, "-I", str(include)],
                           sources, out, f"a variant's {Path(out).name}", libs=["-lm"])


def _source_id_flag() -> list[str]:
    from drive_rattle_build.library import source_flags

    return source_flags()


def model_library(out: Path, flags: Sequence[str] = (), patches: Sequence[Patch] = ()) -> Path:
    """The model library (what a pythonfmu FMU ships in resources/drive_rattle/) compiled
    from its sources with ``flags`` and ``patches`` into ``out``; kept there and reused while
    the sources, flags and patches are the same."""
    from drive_rattle_build.paths import MODEL_SOURCE

    out = Path(out)
    key = hashlib.sha256(repr((sorted((p.name, p.read_bytes()) for p in
                                      MODEL_SOURCE.glob("*.[ch]")), list(flags),
                               list(patches))).encode()).hexdigest()[:16]
    marker = out.with_name(out.name + ".key")
    if out.is_file() and marker.is_file() and marker.read_text() == key:
        return out
    with tempfile.TemporaryDirectory(prefix="rattle_library_") as tmp:
        work = Path(tmp) / "library"
        work.mkdir()
        for path in MODEL_SOURCE.glob("*.[ch]"):
            shutil.copy2(path, work / path.name)
        apply_patches(work, patches)
        built = _compile(flags, sorted(work.glob("*.c")), work, Path(tmp) / out.name,
                         ["-DRM_BUILD_SHARED", *_source_id_flag()])
        out.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(built, out)
    marker.write_text(key)
    return out


def rebuild(fmu: Path, out_dir: Path, flags: Sequence[str] = (),
            patches: Sequence[Patch] = (), shim_flags: Sequence[str] | None = None,
            library: Path | None = None) -> Path:
    """``fmu`` with its C compiled again with ``flags`` and ``patches`` applied to its sources,
    written as ``out_dir/<same name>``; returns the new FMU's path.  ``shim_flags`` (pythonfmu
    FMUs): the status shim compiled again too, with these flags.  (The model library of the
    pythonfmu FMUs is compiled once per ``library`` path, by default
    ``out_dir/rattle_model.so``: :func:`model_library`.)"""
    fmu, out_dir = Path(fmu), Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="rattle_variant_") as tmp:
        root = Path(tmp) / "fmu"
        with zipfile.ZipFile(fmu) as z:
            z.extractall(root)
            members = [(info, info.filename) for info in z.infolist()]
        identifier, guid, n_variables, native, version = _description(root)
        replaced: dict[str, Path] = {}
        if native:
            sources = root / "sources"
            work = Path(tmp) / "sources"
            shutil.copytree(sources, work)
            apply_patches(work, patches)
            from drive_rattle_build import fmi3
            from drive_rattle_build import native as fmi2

            build, folder = (fmi3, "x86_64-linux") if version == "3.0" else (fmi2, "linux64")
            # as the build compiles it, the library's objects shared by both models of one
            # variant (platforms.shared_objects: by the patched files' contents and the
            # flags); a patch may leave a warning the shipped sources have not
            replaced[f"binaries/{folder}/{identifier}.so"] = build.compile_binary(
                work, Path(tmp) / f"{identifier}.so", "x86_64-linux", "gcc",
                [*flags, "-Wno-error"])
        else:
            replaced["resources/drive_rattle/rattle_model.so"] = model_library(
                library or out_dir / "rattle_model.so", flags, patches)
            if shim_flags is not None:
                from drive_rattle_build.shim import compile_shim

                replaced[f"binaries/linux64/{identifier}.so"] = compile_shim(
                    Path(tmp) / "shim" / f"{identifier}.so", f"{identifier}_pythonfmu.so",
                    n_variables, n_variables + 1, cc=["gcc", *shim_flags], guid=guid,
                    model_identifier=identifier, vr_last_successful_time=n_variables + 2)
        target = out_dir / fmu.name
        with zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as z:
            for info, name in members:
                if name in replaced:
                    info.compress_type = zipfile.ZIP_DEFLATED
                    z.writestr(info, replaced[name].read_bytes())
                elif not info.is_dir():
                    z.writestr(info, (root / name).read_bytes())
        missing = set(replaced) - {name for _, name in members}
        if missing:
            raise ValueError(f"{fmu} has no {sorted(missing)}")
    return target
