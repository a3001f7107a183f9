"""Building the compiled kernel: its layout header, generated from
``drive_rattle.kernel_layout`` and committed next to the C source, and the shared library the
runtime loads (``drive_rattle.kernel.load_kernel``)."""

from __future__ import annotations

import sys
from pathlib import Path

from drive_rattle import kernel_layout
from drive_rattle.kernel import LIBRARY_NAME

from .compiler import compile_library
from .paths import NATIVE

#: The C source of the kernel; it includes the generated layout header next to it.
SOURCE = NATIVE / "rattle_kernel.c"
#: The generated layout header (committed: the C source includes it).
HEADER = NATIVE / "rattle_kernel_layout.h"
#: Compiler flags: IEEE semantics without contraction (no FMA), as the bit-for-bit identity
#: with the Python stepper requires (docs/kernel.md, "Keeping the numbers identical").
CFLAGS = ("-std=c99", "-O2", "-fno-fast-math", "-ffp-contract=off", "-fPIC", "-shared")


def header_is_current(path: Path = HEADER) -> bool:
    """True when the header at ``path`` is the one ``kernel_layout.render_header`` writes."""
    path = Path(path)
    return path.is_file() and path.read_text(encoding="utf-8") == kernel_layout.render_header()


def write_header(path: Path = HEADER) -> bool:
    """Write the layout header at ``path`` when it differs; True when it was written."""
    if header_is_current(path):
        return False
    Path(path).write_text(kernel_layout.render_header(), encoding="utf-8")
    return True


def update_header() -> None:
    """Regenerate the committed layout header when the declarations changed (every build does
    it; the kernel tests fail while the committed one is stale)."""
    if write_header():
        print(f"drive-rattle-build: regenerated {HEADER}; commit it", file=sys.stderr)


def compile_kernel(out_path, cc: str = "gcc", source=None) -> Path:
    """Compile the kernel into the shared library ``out_path`` (written atomically).

    ``source`` defaults to :data:`SOURCE`; it includes the layout header from the folder of
    :data:`HEADER`.  RuntimeError when that header is stale (it no longer matches
    ``drive_rattle.kernel_layout``), or with the compiler's output when the compiler is missing
    or fails."""
    if not header_is_current():
        raise RuntimeError(
            f"{HEADER} does not match drive_rattle/kernel_layout.py; regenerate it with "
            "`drive-rattle-build --update-kernel-header` (every build does it) and commit it")
    src = Path(source) if source is not None else SOURCE
    return compile_library(cc, [*CFLAGS, "-I", str(HEADER.parent)], [src], out_path,
                           "the rattle kernel", libs=["-lm"])


__all__ = ["CFLAGS", "HEADER", "LIBRARY_NAME", "SOURCE", "compile_kernel", "header_is_current",
           "update_header", "write_header"]
