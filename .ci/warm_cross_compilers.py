"""Fill ziglang's cache for every cross target the tests compile for, in the background of CI's
installation (.ci/run): on a new machine the first program zig links for a target builds
that target's C runtime first (minutes of CPU for x86_64-windows-gnu, tens of seconds for each
of the others), which otherwise falls on whichever test compiles for it first.  Each target
gets a shared library compiled as the build compiles the FMUs' (platforms.compile_for) and a
program, both linked with -O2 and outside the clone: the one C runtime of the target that
every build and test host links (compiler.zig_cc).  zig's own cache locks make a test that
starts meanwhile wait rather than build it again.  Prints each target's time."""

import platform as host
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from drive_rattle_build.compiler import ZIG_TARGET, zig_cc
from drive_rattle_build.platforms import PLATFORMS, build_machine, compile_for

#: A library function exported as the FMI functions are (an empty export list crashes zig's
#: macOS linker), and a program around it.
SOURCE = """#include <math.h>
#include <stdio.h>
#if defined(_WIN32)
#define EXPORT __declspec(dllexport)
#else
#define EXPORT __attribute__((visibility("default")))
#endif
EXPORT double warm(double x) { return sqrt(x); }
#ifdef WARM_PROGRAM
int main(void) { printf("%g\\n", warm(2.0)); return 0; }
#endif
"""


#: The first needed first: the second session of the tests (-m slow) builds the faces'
#: Windows and aarch64-linux binaries before anything else.
WARM_ORDER = ("x86_64-windows", "aarch64-linux", "x86_64-linux", "x86_64-darwin",
              "aarch64-darwin")


def run(cc: list, flags: list, source: Path, out: Path) -> None:
    # in the output's folder, as every compile of the build and the tests: run from a folder
    # that holds ziglang's lib folder (the clone, with its .venv), zig keys the C runtime
    # differently and builds it again (compiler.zig_cc)
    subprocess.run([*cc, *flags, "-o", str(out), str(source), "-lm"], check=True,
                   capture_output=True, timeout=1800, cwd=out.parent)


def main() -> int:
    with tempfile.TemporaryDirectory(prefix="warm_zig_") as tmp:
        source = Path(tmp) / "warm.c"
        source.write_text(SOURCE, encoding="utf-8")
        for name in (*WARM_ORDER, *sorted(set(PLATFORMS) - set(WARM_ORDER))):
            target = PLATFORMS[name]
            start = time.monotonic()
            if name == build_machine():  # the build's compiler where gcc is missing
                run(zig_cc(ZIG_TARGET[host.machine()]), ["-O2", "-shared", "-fPIC"], source,
                    Path(tmp) / "zig-native.so")
            else:  # the FMUs' binaries, and the test hosts (no macOS host runs here)
                compile_for(name, [source], Path(tmp), Path(tmp) / f"{name}{target.suffix}",
                            what="warm-up")
                if target.system != "darwin":
                    # -O2, as the tests' hosts (a debug program needs a C runtime of its
                    # own)
                    run(zig_cc(target.zig_target), ["-O2", "-DWARM_PROGRAM"], source,
                        Path(tmp) / f"{name}.exe")
            print(f"warm_cross_compilers: {name} ({target.zig_target}) "
                  f"{time.monotonic() - start:.0f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
