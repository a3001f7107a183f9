"""Run a Python test script (the boundary rows, the fuzzer) in a process whose C runs under
AddressSanitizer, then check it for leaks at a point where the host has freed what it made:

    LD_PRELOAD=<libasan> python sanitized_child.py <script> <its arguments...>

(``sanitizers.python_environment`` sets the environment).  The script runs as ``__main__``;
then every FMU instance it left alive is freed (fmi2FreeInstance frees their states), the
garbage is collected, and LeakSanitizer looks for memory nobody points to any more.  The
process then ends with ``os._exit``, the script's exit code, so that the interpreter's own
shutdown (which leaves memory behind by design) is not checked.  Processes the script starts
get the same sanitizers without the leak check."""

from __future__ import annotations

import ctypes
import gc
import os
import runpy
import sys
import traceback


def main() -> int:
    script = sys.argv[1]
    sys.argv = sys.argv[1:]
    sys.path.insert(0, os.path.dirname(os.path.abspath(script)))
    # the leak check is this process's; the processes a row starts are checked for
    # memory errors only (their interpreter's shutdown would be reported as leaks)
    os.environ["ASAN_OPTIONS"] = os.environ.get("ASAN_OPTIONS", "").replace(
        "detect_leaks=1", "detect_leaks=0")
    code = 0
    try:
        runpy.run_path(script, run_name="__main__")
    except SystemExit as exit_:
        code = exit_.code if isinstance(exit_.code, int) else (0 if exit_.code is None else 1)
    except BaseException:
        traceback.print_exc()
        code = 1
    try:
        import raw_fmi

        raw_fmi.free_all()
    except Exception:
        traceback.print_exc()
        code = code or 1
    gc.collect()
    sys.stdout.flush()
    sys.stderr.flush()
    leaks = ctypes.CDLL(None).__lsan_do_recoverable_leak_check()
    print(f"sanitized_child: leak check {'found leaks' if leaks else 'clean'}", file=sys.stderr,
          flush=True)
    return code


if __name__ == "__main__":
    os._exit(main())
