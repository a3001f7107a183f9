"""Building the model library (``fmu_src/rattle_model``): its tables from the specs, and the
shared library for linux64 (gcc, or ziglang's clang where there is none) and win64 (ziglang's
clang), compiled with the hash of its sources (``rm_build_id``) so that a stale library is
never loaded (``drive_rattle.library.load``).

``build_in_place()`` puts the linux64 library next to ``drive_rattle`` (what the Python API, the
studies and the tests load), with the test-only probes (``rm_probe.h``); the pythonfmu FMUs
ship it compiled without them in ``resources/``, the native FMUs compile the same sources
(without them) with their FMI glue.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from drive_rattle import library as binding

from . import model_tables
from .compiler import IEEE_CFLAGS, TARGETS, BuildError, c_compiler, compile_library, zig_cc
from .paths import MODEL_SOURCE, model_files

#: The IEEE flags with the interface exported.
CFLAGS = (*IEEE_CFLAGS, "-DRM_BUILD_SHARED")
#: platform folder -> (file name of the library, ziglang target or None for the build
#: machine's compiler).
PLATFORMS = {platform: (f"rattle_model{'.dll' if target else '.so'}", target)
             for platform, target in TARGETS.items()}


def sources(probes: bool = False) -> list[Path]:
    """The C sources of the library (the generated tables included); with ``probes`` the
    test-only probes too (``paths.TEST_ONLY_SOURCES``)."""
    return model_files("*.c", test_only=probes)


def headers() -> list[Path]:
    return model_files("*.h")


def source_flags() -> list[str]:
    """The flags that identify the sources: their hash as ``rm_build_id``."""
    return [f'-DRM_SOURCE_ID="{binding.source_id(MODEL_SOURCE)}"']


def compile_model_library(out_path: Path, platform: str = "linux64", cc: str | None = None,
                          extra_flags: Sequence[str] = (), probes: bool = False) -> Path:
    """Compile the library for ``platform`` into ``out_path`` (tables regenerated first when
    the specs changed); with ``probes`` the test-only probes (rm_probe.h) too, exported, as
    the library built in place has them -- a shipped FMU's library has not.  BuildError with
    the compiler's output on failure."""
    model_tables.update()
    _, target = PLATFORMS[platform]
    if target is None:
        compiler = [cc or c_compiler()]
        flags = [*CFLAGS, "-fPIC", "-shared", "-fvisibility=hidden"]
        libs = ["-lm"]
    else:
        compiler = zig_cc(target)
        flags = [*CFLAGS, "-shared"]
        libs = []
    flags += [*source_flags(), *extra_flags, "-I", str(MODEL_SOURCE)]
    try:
        return compile_library(compiler, flags, sources(probes), Path(out_path),
                               f"the model library for {platform}", libs=libs)
    except RuntimeError as err:
        raise BuildError(str(err)) from None


def build_in_place() -> Path:
    """The linux64 library next to the ``drive_rattle`` package, rebuilt when its sources
    changed (a marker beside it records the sources' hash)."""
    model_tables.update()
    out = binding.default_path()
    marker = out.with_name(out.name + ".id")
    current = binding.source_id(MODEL_SOURCE)
    if out.is_file() and marker.is_file() and marker.read_text().strip() == current:
        return out
    compile_model_library(out, probes=True)
    marker.write_text(current + "\n")
    return out
