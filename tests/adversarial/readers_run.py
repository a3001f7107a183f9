"""Read every item of a corpus (corpus.py) through built FMUs, in a child process:

    python readers_run.py <GearMeshRattle.fmu> <Driveline.fmu> <corpus.json> <out.json> <work>

or, with "library" for the two FMUs, through the model library in this process (what both
faces must answer).  A table: a Driveline initialized with it (engine.speed_table), stepped
three times; a state: a fresh instance given the record (deserialized in the FMU's own
envelope, then set).  For each item: the status, the refusal's message, the outputs (bit for
bit), a digest of the unit's record afterwards, and the seconds the reading call took (the
best of three for the large items).
"""

from __future__ import annotations

import hashlib
import json
import sys
import time
from pathlib import Path

H = 1e-4
DRIVE_INPUTS = {"wheel.phi": 0.0, "wheel.w": 44.57}
OK, WARNING, ERROR = 0, 1, 3


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()[:16]


class FmuReader:
    def __init__(self, fmus: dict[str, Path], work: Path):
        from raw_fmi import Model, unpack

        self.models = {name: Model(unpack(fmu, work / name)) for name, fmu in fmus.items()}

    def _outputs(self, inst) -> list:
        m = inst.m
        out = []
        for name in m.names("Real", "output"):
            st, (value,) = inst.get("Real", [m.vr(name)])
            out.append([name, st, value.hex() if st == OK else None])
        return out

    def table(self, path: str) -> tuple[dict, float]:
        inst = self.models["Driveline"].instantiate(b"reader")
        assert inst.setup(0.0) == OK and inst.enter() == OK
        assert inst.set_named({**DRIVE_INPUTS, "engine.speed_table": path}) == OK
        n = len(inst.log)
        t0 = time.perf_counter()
        status = inst.exit()
        seconds = time.perf_counter() - t0
        result = {"status": status, "message": _last(inst.messages(n, ERROR))}
        if status in (OK, WARNING):
            steps = [inst.step(k * H, H) for k in range(3)]
            result.update(steps=steps, outputs=self._outputs(inst),
                          record=_digest(_payload(inst.serialized())))
        inst.free()
        return result, seconds

    def state(self, model: str, record: bytes) -> tuple[dict, float]:
        from raw_fmi import with_payload

        inst = self.models[model].instantiate(b"reader")
        blob = with_payload(inst.serialized(), record)
        n = len(inst.log)
        t0 = time.perf_counter()
        st, state = inst.deserialize(blob)
        status = inst.set_state(state) if st == OK else st
        seconds = time.perf_counter() - t0
        result = {"status": status, "message": _last(inst.messages(n, ERROR))}
        if status in (OK, WARNING):
            result.update(outputs=self._outputs(inst),
                          record=_digest(_payload(inst.serialized())))
        if st == OK:
            inst.free_state(state)
        inst.free()
        return result, seconds


class LibraryReader:
    """The same through the library's units in this process."""

    def __init__(self):
        from drive_rattle.units import table as variables

        self.variables = variables

    def _outputs(self, sh, kind: int) -> list:
        out = []
        for name, v in self.variables(kind).items():
            if v.causality == "output" and v.type == "Real":
                st, (value,) = sh.get("Real", [v.vr])
                out.append([name, st, value.hex() if st == OK else None])
        return out

    def table(self, path: str) -> tuple[dict, float]:
        from shadow import Shadow

        from drive_rattle.library import DRIVELINE

        sh = Shadow("Driveline", None)
        vs = self.variables(DRIVELINE)
        for name, value in DRIVE_INPUTS.items():
            assert sh.set("Real", [vs[name].vr], [value]) == OK
        assert sh.set("String", [vs["engine.speed_table"].vr], [path.encode()]) == OK
        assert sh.setup(0.0) == OK and sh.enter() == OK
        t0 = time.perf_counter()
        status = sh.exit()
        seconds = time.perf_counter() - t0
        result = {"status": status, "message": sh.message() if status == ERROR else ""}
        if status in (OK, WARNING):
            steps = [sh.step(k * H, H) for k in range(3)]
            result.update(steps=steps, outputs=self._outputs(sh, DRIVELINE),
                          record=_digest(sh.save()))
        sh.free()
        return result, seconds

    def state(self, model: str, record: bytes) -> tuple[dict, float]:
        from shadow import KINDS, Shadow

        sh = Shadow(model, None)
        t0 = time.perf_counter()
        status = sh.restore(record)
        seconds = time.perf_counter() - t0
        result = {"status": status, "message": sh.message() if status == ERROR else ""}
        if status in (OK, WARNING):
            result.update(outputs=self._outputs(sh, KINDS[model]), record=_digest(sh.save()))
        sh.free()
        return result, seconds


def _last(messages: list[str]) -> str:
    return messages[-1] if messages else ""


def _payload(blob: bytes) -> bytes:
    from raw_fmi import state_payload

    return state_payload(blob)


def read_all(reader, corpus: dict) -> dict:
    results = {}
    for name, (kind, model, path) in corpus.items():
        repeats = 3 if "large_" in name else 1
        best = None
        for _ in range(repeats):
            if kind == "table":
                result, seconds = reader.table(path)
            else:
                result, seconds = reader.state(model, Path(path).read_bytes())
            best = seconds if best is None else min(best, seconds)
        results[name] = {**result, "seconds": best}
    return results


if __name__ == "__main__":
    mesh_fmu, drive_fmu, corpus_json, out_json, work = sys.argv[1:6]
    corpus = json.loads(Path(corpus_json).read_text())
    if mesh_fmu == "library":
        reader = LibraryReader()
    else:
        reader = FmuReader({"GearMeshRattle": Path(mesh_fmu), "Driveline": Path(drive_fmu)},
                           Path(work))
    Path(out_json).write_text(json.dumps(read_all(reader, corpus), indent=1))
    print("read", len(corpus))
