"""Compiling C probes of the project's C under AddressSanitizer and UndefinedBehaviorSanitizer:
any report makes the probe exit non-zero (halt_on_error), so a test fails on it."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

#: Flags of a sanitizer build: every report is an error that stops the program.
ASAN_FLAGS = ("-fsanitize=address,undefined", "-fno-sanitize-recover=all",
              "-fno-omit-frame-pointer", "-g", "-O1")
#: The environment of a sanitized run: leaks and every other report fail it.
SANITIZE = {**os.environ,
            "ASAN_OPTIONS": "detect_leaks=1:halt_on_error=1:abort_on_error=0:exitcode=86",
            "UBSAN_OPTIONS": "halt_on_error=1:print_stacktrace=1:exitcode=87"}


def compile_probe(folder: Path, name: str, sources, include_dirs, flags=()) -> Path:
    """Compile ``sources`` (with the probe ``<name>.c`` next to this module) under the
    sanitizers into ``folder/name``; AssertionError with the compiler's output on failure."""
    here = Path(__file__).resolve().parent
    exe = Path(folder) / name
    cmd = ["gcc", "-std=c99", *ASAN_FLAGS, *flags,
           *(f"-I{d}" for d in include_dirs), "-o", str(exe), str(here / f"{name}.c"),
           *(str(s) for s in sources), "-lm"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0, f"{' '.join(cmd)}\n{proc.stderr}"
    return exe
