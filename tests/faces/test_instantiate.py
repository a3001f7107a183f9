"""Instantiation on every face: the instance name, the token (FMI 2.0's GUID, FMI 3.0's
instantiation token), the resources folder (its form, its marker file, another FMU's) and the
standard's own arguments, each refused with a message to the host's logger before any
instance exists; the forms of the resources folder the faces accept."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from .raw_fmi import ERROR, MODEL_EXCHANGE, unpack

ROOT = Path(__file__).resolve().parents[2]
#: standard -> (the token's name, the resources argument's name) in the messages
WORDS = {"2.0": ("GUID", "fmuResourceLocation"), "3.0": ("instantiationToken", "resourcePath")}


def refusals(face, mesh, driveline, tmp_path) -> list[tuple[dict, str]]:
    """(instantiate's arguments, a fragment of its refusal) for ``face``."""
    token, resources = WORDS[face.standard]
    cases = [
        (dict(name=b"  "), "instanceName is blank; allowed: a non-empty string (FMI "
                           f"{face.standard}"),
        (dict(name=None), "instanceName is NULL"),
        (dict(name=b"\xff"), "is not valid UTF-8"),
        (dict(token=b"{not-this-one}"), f"{token} {{not-this-one}} does not match this "
                                        "FMU's {"),
        (dict(resources=b""), f"{resources} '' is empty"),
        (dict(resources=b"resources"), f"{resources} 'resources' is a relative path"),
        (dict(resources=b"resources/"), f"{resources} 'resources/' is a relative path"),
        (dict(resources=b"http://example.org/r"), "has the URI scheme 'http'"),
        (dict(resources=b"file://otherhost/r"), "names a file on another host"),
        (dict(resources=b"file:///tmp/x%00y"), "holds %00"),
        (dict(resources=str(mesh.root).encode()), "the folder the FMU was unpacked to"),
        (dict(resources=str(tmp_path).encode()), f"which has no {face.marker}"),
        (dict(resources=str(tmp_path / "missing").encode()), "no such file or directory"),
        (dict(resources=driveline.dialect.resources(driveline)),
         "the resources of FMU 'Driveline', not of GearMeshRattle"),
    ]
    if face.standard == "2.0":
        cases += [
            (dict(kind=MODEL_EXCHANGE), "fmuType = 0 (fmi2ModelExchange) is not supported"),
            (dict(default_resources=False), "fmuResourceLocation '(null)' is NULL"),
        ]
    else:
        cases += [
            (dict(event_mode=True), "eventModeUsed = true, but this FMU has no Event Mode"),
            (dict(required=[3]), "nRequiredIntermediateVariables = 1, but no variable"),
        ]
    return cases


def test_instantiate_refusals(face, models, tmp_path):
    mesh, driveline = models["GearMeshRattle"], models["Driveline"]
    for kwargs, fragment in refusals(face, mesh, driveline, tmp_path):
        assert mesh.instantiate(**kwargs) is None, kwargs
        (status, category, message), = mesh.pending_log
        assert (status, category) == (ERROR, "logStatusError")
        assert message.startswith(face.instantiate), message
        assert fragment in message, (kwargs, message)
    # the resources folder as a plain absolute path and as a file URI is accepted too
    for resources in (str(mesh.root / "resources").encode(),
                      (mesh.root / "resources").as_uri().encode()):
        inst = mesh.instantiate(resources=resources)
        assert inst is not None, mesh.pending_log
        inst.free()
    if face.standard == "3.0":
        # no logger: refused all the same, silently
        assert mesh.instantiate(token=b"x", log=False) is None
        # (resourcePath NULL, FMI 3.0's "the importer has no path to give", accepted: the
        # boundary rows, tests/adversarial/boundary_rows.py row 2)
        logged = []
        log = type(mesh._logger)(lambda env, s, c, m: logged.append(m.decode()))
        assert not mesh.lib.fmi3InstantiateModelExchange(b"x", mesh.token.encode(), None,
                                                         False, False, None, log)
        assert logged == ["rattle native FMU: fmi3InstantiateModelExchange: this FMU is for "
                          "co-simulation only (its modelDescription has no <ModelExchange> or "
                          "<ScheduledExecution>); allowed: fmi3InstantiateCoSimulation"]


FIFO_PROBE = """
import sys
sys.path[:0] = sys.argv[3:]
from tests.faces.raw_fmi import Model
m = Model(sys.argv[1])
assert m.instantiate(resources=sys.argv[2].encode()) is None, "instantiated"
print(m.pending_log[0][2])
"""


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
def test_a_fifo_as_the_marker_does_not_block(face, face_fmus, tmp_path):
    """The file that marks an FMU's resources folder is read only when it is a regular file,
    opened non-blocking: a FIFO in its place is refused at once instead of blocking the host
    forever -- in a folder of its own and in place of the FMU's own marker (in a process of
    its own: a blocked open would hang the test)."""
    root = unpack(face_fmus["GearMeshRattle"], tmp_path / "fmu")
    (root / "resources" / face.marker).unlink()
    os.mkfifo(root / "resources" / face.marker)
    alone = tmp_path / "resources"
    alone.mkdir()
    os.mkfifo(alone / face.marker)
    for folder in (alone, root / "resources"):
        run = subprocess.run([sys.executable, "-c", FIFO_PROBE, str(root), str(folder),
                              str(ROOT), *sys.path], capture_output=True, text=True, timeout=60)
        assert run.returncode == 0, run.stdout + run.stderr
        assert f"whose {face.marker} is a FIFO, not a regular file" in run.stdout, run.stdout
