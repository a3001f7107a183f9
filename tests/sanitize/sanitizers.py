"""Compiling the project's C under AddressSanitizer, UndefinedBehaviorSanitizer and
ThreadSanitizer: probes, hosts and a native FMU's binary (the model library with its FMI 2.0
face, from the sources the FMU ships).  Any report makes the program exit non-zero
(halt_on_error), so a test fails on it."""

from __future__ import annotations

import os
import re
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


# ------------------------------------------------------------------ Python hosts
#: The project's C files: a leak whose memory one of them allocated is the project's.
OWN_SOURCES = re.compile(r"/(rattle_model|fmi2|sources|library)/[A-Za-z0-9_]+\.c:\d+|"
                         r"\b(unit|unit_mesh|unit_driveline|speed_table|driveline|stepper|"
                         r"mesh|contact|friction|geometry|start|system|text|refusals|roots|"
                         r"rm_tables|fmi2_functions|rattle_fmi_common|rattle_fmi_shim)\.c:\d+")
#: A report of a memory error, undefined behaviour or the sanitizer's own failure.
ERROR_MARK = re.compile(r"ERROR: AddressSanitizer|AddressSanitizer: CHECK failed|runtime error:|"
                        r"UndefinedBehaviorSanitizer|Sanitizer:DEADLYSIGNAL")
#: Frames of the sanitizer's own interceptors (malloc, strdup, realpath, ...).
RUNTIME_FRAME = re.compile(r"libsanitizer|/libasan|/libubsan|\(/lib/x86_64-linux-gnu/libc\.")


def preload() -> str:
    """What a Python host must preload: gcc's AddressSanitizer runtime, and the C++ runtime
    (pythonfmu's wrapper throws C++ exceptions: the sanitizer intercepts __cxa_throw only when
    the C++ runtime is there when it starts)."""
    proc = subprocess.run(["gcc", "-print-file-name=libasan.so"], capture_output=True,
                          text=True, check=True)
    return f"{os.path.realpath(proc.stdout.strip())}:libstdc++.so.6"


def python_environment(log_dir: Path, extra: dict | None = None) -> dict:
    """The environment of a Python host whose loaded C runs under the sanitizers: the
    runtime preloaded, every report written to ``log_dir`` (also from the processes the host
    starts) and fatal, Python's allocations made with malloc (so that LeakSanitizer sees the
    pointers Python objects hold)."""
    log_dir = Path(log_dir)
    log_dir.mkdir(parents=True, exist_ok=True)
    return {**os.environ, **(extra or {}),
            "LD_PRELOAD": preload(),
            "PYTHONMALLOC": "malloc",
            "RATTLE_SANITIZED": "1",
            "ASAN_OPTIONS": ("detect_leaks=1:halt_on_error=1:abort_on_error=1:"
                             "detect_stack_use_after_return=0:"
                             f"log_path={log_dir / 'asan'}"),
            "UBSAN_OPTIONS": ("halt_on_error=1:abort_on_error=1:print_stacktrace=1:"
                              f"log_path={log_dir / 'ubsan'}")}


def python_reports(log_dir: Path) -> list[str]:
    """The sanitizer reports the processes wrote to ``log_dir`` that are the project's: every
    memory error and undefined behaviour, and the leaks of memory that the project's C
    allocated (the first frame that is not the sanitizer's interceptor is in its sources;
    the interpreter's and pythonfmu's own allocations are theirs)."""
    found = []
    for path in sorted(Path(log_dir).glob("*")):
        text = path.read_text(errors="replace")
        for line in text.splitlines():
            if ERROR_MARK.search(line):
                found.append(f"{path.name}: {line}\n{text[:6000]}")
                break
        for block in re.split(r"\n(?=(?:Direct|Indirect) leak of )", text)[1:]:
            frames = [ln for ln in block.splitlines() if re.match(r"\s+#\d+ ", ln)]
            first = next((ln for ln in frames if not RUNTIME_FRAME.search(ln)), "")
            if OWN_SOURCES.search(first):
                found.append(f"{path.name}: {block.strip()[:3000]}")
    return found
