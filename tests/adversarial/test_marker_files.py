"""The file that marks an FMU's resources folder (pythonfmu's slavemodule.txt, the native FMU's
model_identifier.txt) is read only when it is a regular file, opened non-blocking: a FIFO in
its place is refused at once by fmi2Instantiate instead of blocking the host forever
(issue 20, item 6), in both flavours."""

from __future__ import annotations

import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
MARKERS = {False: "slavemodule.txt", True: "model_identifier.txt"}  # by native

PROBE = """
import sys
sys.path[:0] = sys.argv[3:]
from tests.adversarial.raw_fmi import Model
m = Model(sys.argv[1])
assert m.instantiate(location=sys.argv[2].encode()) is None, "instantiated"
print(m.pending_log[0][2])
"""


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
def test_a_fifo_as_the_marker_is_refused_at_once(flavour_fmus, tmp_path):
    root = tmp_path / "fmu"
    with zipfile.ZipFile(flavour_fmus["GearMeshRattle"]) as z:
        z.extractall(root)
    native = (root / "binaries" / "linux64" / "GearMeshRattle.so").is_file() and \
        "needsExecutionTool=\"false\"" in (root / "modelDescription.xml").read_text()
    marker = root / "resources" / MARKERS[native]
    marker.unlink()
    os.mkfifo(marker)
    run = subprocess.run([sys.executable, "-c", PROBE, str(root), str(root / "resources"),
                          str(ROOT), *sys.path], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stdout + run.stderr
    assert f"{MARKERS[native]} is a FIFO, not a regular file" in run.stdout, run.stdout
