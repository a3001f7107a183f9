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


def build_fmu_binary(model: str, folder: Path, flags: Sequence[str],
                     standard: str = "2.0") -> tuple[Path, Path, str]:
    """The native ``model``'s binary of ``standard`` compiled with ``flags`` from the sources
    its FMU ships (drive_rattle_build.native's or drive_rattle_build.fmi3's stage_sources), in
    an FMU-like folder: ``folder/<model>.so`` and ``folder/resources`` with its marker.
    Returns (binary, resources folder, token: FMI 2.0's GUID, FMI 3.0's instantiation
    token)."""
    from drive_rattle_build import fmi3, native

    folder = Path(folder)
    sources = folder / "sources"
    if standard == "3.0":
        token = fmi3.fmi3_token(model)
        fmi3.stage_sources(model, token, sources)
    else:
        token = native.native_guid(model)
        native.stage_sources(model, token, sources)
    # as the build compiles it (the library's objects shared by both models of one standard
    # and flags: drive_rattle_build.platforms.shared_objects), with the sanitizers' flags
    face = fmi3 if standard == "3.0" else native
    binary = face.compile_binary(sources, folder / f"{model}.so", "x86_64-linux", "gcc", flags)
    resources = folder / "resources"
    resources.mkdir(exist_ok=True)
    (resources / native.RESOURCE_MARKER).write_text(f"{model}\n", encoding="utf-8")
    return binary, resources, token


def compile_program(exe: Path, source: Path, flags: Sequence[str] = ASAN_FLAGS,
                    standard: str = "2.0", defines: Sequence[str] = ()) -> Path:
    """A host program (``source``, with ``defines``) against the C headers of ``standard``,
    compiled with ``flags`` and warning-free into ``exe``; AssertionError with the compiler's
    output."""
    from ..faces.hosts import headers

    cmd = ["gcc", "-std=c99", *flags, *defines, "-Wall", "-Wextra", "-Werror", "-I",
           str(headers(standard)), "-o", str(exe), str(source), "-lm", "-lpthread", "-ldl"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, f"{' '.join(cmd)}\n{proc.stderr}"
    return Path(exe)


def reports(text: str) -> list[str]:
    """The lines of a sanitizer report in a program's output."""
    return [line for line in text.splitlines() if any(m in line for m in REPORT_MARKS)]


def assert_clean(run: subprocess.CompletedProcess) -> None:
    """A sanitized program's run: exit 0 and no sanitizer report; AssertionError with the
    reports and the ends of its output otherwise."""
    found = reports(run.stdout + run.stderr)
    assert not found and run.returncode == 0, (
        f"exit {run.returncode}; sanitizer reports:\n" + "\n".join(found[:20])
        + f"\n--- stdout (end)\n{run.stdout[-3000:]}\n--- stderr (end)\n{run.stderr[-6000:]}")


# ------------------------------------------------------------------ the abuse host
#: One abuse host for both standards: its FMI 2.0 or FMI 3.0 adapter chosen when it is
#: compiled (as tests/faces/fmu_host.c's, tests/faces/hosts.py's ADAPTER).
ABUSE_SOURCE = HERE / "fmi_abuse.c"
ABUSE_ADAPTER = {"2.0": (), "3.0": ("-DFMI_ABUSE_FMI3",)}
#: The variables the abuse host probes, by model: a Real parameter, a Real input, a Real
#: output, an Integer output, a String parameter, an Enumeration parameter (None where the
#: unit has none).
PROBED = {
    "GearMeshRattle": ("gear.backlash", "pinion.w", "wheel.w", "mesh.n_contact", None,
                       "contact.hertz_law"),
    "Driveline": ("shaft.k", "wheel.w", "pinion.w", None, "engine.speed_table",
                  "vehicle.model"),
}
#: Fewer cases than this means the states' loops did not run (the record's every byte
#: changed and re-sealed, so that it reaches rm_restore: thousands of cases per unit).
ABUSE_CASES = 1000


def compile_abuse(exe: Path, standard: str) -> Path:
    """fmi_abuse.c with the adapter of ``standard``, under ASAN and UBSAN, into ``exe``."""
    return compile_program(exe, ABUSE_SOURCE, ASAN_FLAGS, standard, ABUSE_ADAPTER[standard])


def run_abuse(abuse: Path, binary: Path, resources: str, token: str, root: Path,
              fifo_folder: Path, references: dict, model: str, time: int | None = None) -> str:
    """The abuse host on ``binary`` (``references``: the value references by name; ``time``:
    the independent variable's, FMI 3.0's); asserts a clean run and no failed expectation,
    with the number of cases above ABUSE_CASES, and returns the host's summary line."""
    vrs = [str(references[n]) if n is not None else "-" for n in PROBED[model]]
    run = subprocess.run([str(abuse), str(binary), resources, token, str(root),
                          str(fifo_folder), *vrs, "-" if time is None else str(time)],
                         env=SANITIZE, capture_output=True, text=True, timeout=120)
    assert_clean(run)
    summary = run.stdout.strip().splitlines()[-1]
    fields = summary.split()
    assert fields[0::2] == ["cases", "failures", "logged"], run.stdout[-3000:]
    assert fields[3] == "0", run.stdout[-3000:]
    assert int(fields[1]) > ABUSE_CASES, summary
    return summary


def fifo_resources(folder: Path) -> Path:
    """A resources folder whose marker file is a FIFO (opening it to read would block)."""
    from drive_rattle_build.native import RESOURCE_MARKER

    folder.mkdir()
    os.mkfifo(folder / RESOURCE_MARKER)
    return folder


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
