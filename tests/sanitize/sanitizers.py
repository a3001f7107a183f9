"""Compiling the project's C under AddressSanitizer, UndefinedBehaviorSanitizer and
ThreadSanitizer: probes, hosts and a native FMU's binary (the model library with its FMI 2.0
face, from the sources the FMU ships).  Any report makes the program exit non-zero
(halt_on_error), so a test fails on it."""

from __future__ import annotations

import os
import subprocess
from collections.abc import Sequence
from pathlib import Path

#: Flags of a sanitizer build: every report is an error that stops the program.
ASAN_FLAGS = ("-fsanitize=address,undefined", "-fno-sanitize-recover=all",
              "-fno-omit-frame-pointer", "-g", "-O1")
#: Flags of a ThreadSanitizer build.
TSAN_FLAGS = ("-fsanitize=thread", "-fno-omit-frame-pointer", "-g", "-O1")
#: The environment of a sanitized run: leaks and every other report fail it.
SANITIZE = {**os.environ,
            "ASAN_OPTIONS": "detect_leaks=1:halt_on_error=1:abort_on_error=0:exitcode=86",
            "UBSAN_OPTIONS": "halt_on_error=1:print_stacktrace=1:exitcode=87"}
#: The environment of a ThreadSanitizer run: the first report fails it.
TSAN = {**os.environ, "TSAN_OPTIONS": "halt_on_error=1:exitcode=66:second_deadlock_stack=1"}
#: What the sanitizers print when they report.
REPORT_MARKS = ("ERROR: AddressSanitizer", "ERROR: LeakSanitizer", "runtime error:",
                "WARNING: ThreadSanitizer", "SUMMARY: ")
#: The model library's arithmetic (docs/model.md: "Reproducible numbers").
IEEE = ("-std=c99", "-fno-fast-math", "-ffp-contract=off", "-Wall", "-Wextra")

HERE = Path(__file__).resolve().parent


def compile_probe(folder: Path, name: str, sources, include_dirs, flags=ASAN_FLAGS) -> Path:
    """Compile ``sources`` (with the probe ``<name>.c`` next to this module) with ``flags``
    (default: the address and undefined-behaviour sanitizers) into ``folder/name``;
    AssertionError with the compiler's output on failure."""
    exe = Path(folder) / name
    cmd = ["gcc", "-std=c99", *flags, *(f"-I{d}" for d in include_dirs), "-o", str(exe),
           str(HERE / f"{name}.c"), *(str(s) for s in sources), "-lm", "-lpthread"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, f"{' '.join(cmd)}\n{proc.stderr}"
    return exe


def build_fmu_binary(model: str, folder: Path, flags: Sequence[str]) -> tuple[Path, Path, str]:
    """The native ``model``'s binary compiled with ``flags`` from the sources the FMU ships
    (drive_rattle_build.native.stage_sources), in an FMU-like folder: ``folder/binary.so``
    and ``folder/resources`` with its marker.  Returns (binary, resources folder, GUID)."""
    from drive_rattle_build.native import RESOURCE_MARKER, native_guid, stage_sources

    folder = Path(folder)
    sources = folder / "sources"
    guid = native_guid(model)
    stage_sources(model, guid, sources)
    binary = folder / f"{model}.so"
    cmd = ["gcc", *IEEE, *flags, "-Werror", "-fPIC", "-shared", "-I", str(sources), "-o",
           str(binary), *(str(s) for s in sorted(sources.glob("*.c"))), "-lm"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, f"{' '.join(cmd)}\n{proc.stderr}"
    resources = folder / "resources"
    resources.mkdir(exist_ok=True)
    (resources / RESOURCE_MARKER).write_text(f"{model}\n", encoding="utf-8")
    return binary, resources, guid


def reports(text: str) -> list[str]:
    """The lines of a sanitizer report in a program's output."""
    return [line for line in text.splitlines() if any(m in line for m in REPORT_MARKS)]
