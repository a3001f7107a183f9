"""The resource location decoder of both flavours' glue (rattle_fmi_common.c) on strings that
end at a page boundary, under AddressSanitizer and UndefinedBehaviorSanitizer: a relative
location made only of URI-scheme characters ("resources") was once read past its end.  Each
string ends exactly at a page with an unmapped page after it (location_probe.c), so a read past
its end faults or is reported."""

import shutil
import subprocess

import pytest

from drive_rattle_build.paths import FMI_COMMON_SOURCE, MODEL_SOURCE
from drive_rattle_build.shim import fmi2_headers

from .sanitizers import SANITIZE, compile_probe

PROBE = [
    "resources", "a", "ab+c-d.e", "file:", "file://", "file:///", "http:", "C:", "",
    "/abs/path", "file:///tmp/x%2", "file:///tmp/x%",
]


@pytest.mark.skipif(shutil.which("gcc") is None, reason="gcc is needed")
def test_location_decoder_reads_no_byte_past_the_string(tmp_path):
    exe = compile_probe(tmp_path, "location_probe",
                        [FMI_COMMON_SOURCE / "rattle_fmi_common.c", MODEL_SOURCE / "portable.c"],
                        [FMI_COMMON_SOURCE, MODEL_SOURCE, fmi2_headers()])
    proc = subprocess.run([str(exe), *PROBE], capture_output=True, text=True, timeout=60,
                          env=SANITIZE)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "ERROR: AddressSanitizer" not in proc.stderr and "runtime error" not in proc.stderr
    lines = proc.stdout.splitlines()
    assert len(lines) == len(PROBE)
    assert lines[0].startswith("resources -> NULL (is a relative path")
    assert lines[2].startswith("ab+c-d.e -> NULL (is a relative path")
    assert lines[6].startswith("http: -> NULL (has the URI scheme 'http'")
    assert lines[9] == "/abs/path -> /abs/path ()"
