"""Endurance scenarios run in their own process (python endurance.py <scenario> <fmu_dir>),
printing a JSON report: resident memory samples, counts, timings."""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

from drive_rattle_cosim.harness import CoSimulation, Unit

H = 1e-4


def rss_kib() -> int:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return -1


def cycles(fmu: Path, n: int = 1000) -> dict:
    """Instantiate, initialize, step, terminate and free one FMU n times, unpacked once (as a
    simulation tool does); resident memory sampled every 100 cycles."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(fmu))
    folder = extract(str(fmu))
    slave = FMU2Slave(guid=md.guid, unzipDirectory=folder,
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="cycle")
    samples, t0 = [], time.perf_counter()
    for k in range(n):
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        slave.doStep(0.0, H)
        slave.terminate()
        slave.fmi2FreeInstance(slave.component)
        if k % 100 == 99:
            samples.append(rss_kib())
    return {"rss_kib": samples, "seconds": time.perf_counter() - t0, "cycles": n}


def live_rounds(fmu: Path, n: int = 300, rounds: int = 4) -> dict:
    """``rounds`` times: ``n`` instances alive at once (initialized, one step), then all freed;
    resident memory after each round.  Memory freed in one round serves the next."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(fmu))
    folder = extract(str(fmu))
    samples, t0 = [rss_kib()], time.perf_counter()
    for _ in range(rounds):
        alive = []
        for k in range(n):
            s = FMU2Slave(guid=md.guid, unzipDirectory=folder,
                          modelIdentifier=md.coSimulation.modelIdentifier, instanceName=f"i{k}")
            s.instantiate()
            s.setupExperiment(startTime=0.0)
            s.enterInitializationMode()
            s.exitInitializationMode()
            s.doStep(0.0, H)
            alive.append(s)
        for s in alive:
            s.terminate()
            s.freeInstance()
        del alive, s
        samples.append(rss_kib())
    return {"rss_kib": samples, "seconds": time.perf_counter() - t0, "instances": n}


def soak(fmu_dir: Path, n: int) -> dict:
    """n communication steps of one GearMeshRattle instance: the wheel bounces freely between
    the flanks of a pinion at rest (impacts on both flanks, contact and free flight), with the
    inputs set and outputs read every step as a master does.  Without contact dissipation, so
    that the wheel keeps bouncing for the whole run (damped it comes to rest after ~90 impacts
    per flank)."""
    u = Unit(fmu_dir / "GearMeshRattle.fmu", "soak")
    u.set({"init.in_contact": False, "friction.enabled": False, "wheel.w_start": 0.5,
           "contact.dissipation": 0})
    u.slave.setupExperiment(startTime=0.0)
    u.slave.enterInitializationMode()
    u.slave.exitInitializationMode()
    s = u.slave
    vin = [u.var(x).vr for x in ("pinion.phi", "pinion.w", "pinion.a", "wheel.tau_load")]
    vout = [u.var(x).vr for x in ("wheel.phi", "wheel.w", "mesh.W", "mesh.delta_peak")]
    vcount = [u.var("mesh.impacts_drive").vr, u.var("mesh.impacts_coast").vr]
    samples, finite, t0 = [], True, time.perf_counter()
    for k in range(n):
        s.setReal(vin, [0.0, 0.0, 0.0, 0.0])
        s.doStep(k * H, H)
        out = s.getReal(vout)
        if k % 1000 == 0:
            finite = finite and all(math.isfinite(x) for x in out)
        if k % (n // 20) == n // 20 - 1:
            samples.append(rss_kib())
    counts = s.getInteger(vcount)
    u.close()
    return {"rss_kib": samples, "seconds": time.perf_counter() - t0, "steps": n,
            "impacts": counts, "finite": finite}


def many_instances(fmu_dir: Path) -> dict:
    """Three co-simulations (six instances of the two FMUs) alive and stepped interleaved in
    one process; the first and the last have the same parameters."""
    sims = [CoSimulation(fmu_dir / "GearMeshRattle.fmu", fmu_dir / "Driveline.fmu", p)
            for p in ({}, {"Driveline.engine.amplitude[1]": 1500.0}, {})]
    results = [[] for _ in sims]
    for k in range(1, 301):
        for sim, rec in zip(sims, results, strict=True):
            r = sim.run(k * H, ["GearMeshRattle.wheel.w", "Driveline.wheel.tau_load"])
            rec.append([r.columns[c][-1] for c in r.columns])
    for sim in sims:
        sim.close()
    return {"same_as_twin": results[0] == results[2], "differs": results[0] != results[1]}


def _mesh_instance(fmu_dir: Path, name: str) -> Unit:
    u = Unit(fmu_dir / "GearMeshRattle.fmu", name)
    u.slave.setupExperiment(startTime=0.0)
    u.slave.enterInitializationMode()
    u.set({"pinion.w": 86.92, "wheel.tau_load": 0.17})
    u.slave.exitInitializationMode()
    return u


def _drive(u: Unit, k0: int, k1: int) -> list:
    names = ("wheel.phi", "wheel.w", "mesh.W", "wheel.tau_mesh", "mesh.delta_peak")
    rows = []
    for k in range(k0, k1):
        t = k * H
        u.set({"pinion.phi": 86.92 * t, "pinion.a": 2000.0 * math.cos(174.0 * t)})
        u.slave.doStep(t, H)
        rows.append([repr(x) for x in u.slave.getReal([u.var(n).vr for n in names])])
    return rows


def save_state(fmu_dir: Path, blob_path: Path) -> dict:
    """Run 20 steps, serialize the state to ``blob_path``, run 40 more and report them."""
    u = _mesh_instance(fmu_dir, "saver")
    _drive(u, 0, 20)
    blob_path.write_bytes(bytes(u.slave.serializeFMUstate(u.slave.getFMUstate())))
    rows = _drive(u, 20, 60)
    u.close()
    return {"rows": rows}


def restore_state(fmu_dir: Path, blob_path: Path) -> dict:
    """A new instance in a new process: restore the serialized state, run the same 40 steps."""
    u = _mesh_instance(fmu_dir, "restorer")
    u.slave.setFMUstate(u.slave.deSerializeFMUstate(blob_path.read_bytes()))
    rows = _drive(u, 20, 60)
    u.close()
    return {"rows": rows}


def run_once(fmu_dir: Path) -> dict:
    """One deterministic co-simulation, all outputs, for determinism checks across processes."""
    with CoSimulation(fmu_dir / "GearMeshRattle.fmu", fmu_dir / "Driveline.fmu") as sim:
        r = sim.run(0.05)
    return {"time": r.time, "columns": {k: [repr(v) for v in c] for k, c in r.columns.items()}}


if __name__ == "__main__":
    scenario, fmu_dir = sys.argv[1], Path(sys.argv[2])
    arg = int(sys.argv[3]) if len(sys.argv) > 3 and sys.argv[3].isdigit() else None
    report = {"cycles": lambda: cycles(fmu_dir, arg or 1000),  # here fmu_dir is an .fmu
              "live": lambda: live_rounds(fmu_dir, arg or 300),  # here too
              "soak": lambda: soak(fmu_dir, arg or 1_000_000),
              "many": lambda: many_instances(fmu_dir),
              "once": lambda: run_once(fmu_dir),
              "save": lambda: save_state(fmu_dir, Path(sys.argv[3])),
              "restore": lambda: restore_state(fmu_dir, Path(sys.argv[3]))}[scenario]()
    print(json.dumps(report))
