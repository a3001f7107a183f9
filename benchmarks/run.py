"""Benchmarks of the paper scenario, every figure measured side by side in this one run.

    python benchmarks/run.py [--quick] [--out out/benchmarks]

* R1: wall time per simulated second of the GearMeshRattle + Driveline co-simulation under the
  project's fmpy harness at a 1e-4 s communication step (the real-time factor);
* R0: the same with the mesh replaced by NullMeshRattle (same interface, no physics): the FMI
  overhead floor; and R1/R0;
* R3: the monolithic reference (drive_rattle_cosim.reference, scipy solve_ivp LSODA, rtol 1e-9,
  contact events) per simulated second; and R1/R3;
* accuracy: the co-simulation's statistics against the monolithic reference, and one impact
  against the Hertz closed form;
* how cost grows: against the communication step (with the accuracy at each), against the
  simulated time, and against the number of pairs in contact (face width);
* sweep throughput: cases per minute with 1 and 2 dask workers.

Machines here are shared and noisy: each timing is the best of ``REPEATS`` runs.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from drive_rattle import MeshModel, MeshParameters, hertz
from drive_rattle.driveline import DrivelineParameters
from drive_rattle_build import build_fmus, package, validate
from drive_rattle_cosim.analysis import (
    LineSearch,
    catalogue_for,
    markdown_table,
    onsets_from_counters,
    rattle_statistics,
)
from drive_rattle_cosim.harness import CoSimulation
from drive_rattle_cosim.reference import solve
from drive_rattle_cosim.sweep import grid_design, run_sweep

ROOT = Path(__file__).resolve().parents[1]
REPEATS = 2
RECORD = ["GearMeshRattle.wheel.phi", "GearMeshRattle.wheel.w", "GearMeshRattle.mesh.W",
          "GearMeshRattle.mesh.W_peak", "GearMeshRattle.mesh.v_impact",
          "GearMeshRattle.mesh.impacts_drive", "GearMeshRattle.mesh.impacts_coast"]
CATALOGUE = catalogue_for(MeshParameters(), DrivelineParameters())


def _build(out: Path) -> dict[str, Path]:
    paths = build_fmus(out)
    null = package(ROOT / "benchmarks" / "NullMeshRattle.py", out, references=False)
    validate(null, use_fmutool=False)
    paths["NullMeshRattle"] = null
    return paths


def cosim(fmus, mesh: str, stop: float, step: float = 1e-4, params=None):
    """(best wall time [s], result) of one co-simulation."""
    best, result = math.inf, None
    for _ in range(REPEATS):
        with CoSimulation(fmus[mesh], fmus["Driveline"], params or {}, step=step) as sim:
            t0 = time.perf_counter()
            result = sim.run(stop, RECORD)
            best = min(best, time.perf_counter() - t0)
    return best, result


def statistics(t, phi, W, drive, coast, v_impact, onset_speeds=None, onset_flanks=None):
    """Statistics compared between co-simulation and reference (analysis.rattle_statistics
    over the whole run, from the signals both record: wheel angle and total normal force)."""
    t = np.asarray(t)
    if onset_speeds is None:
        _, onset_speeds, onset_flanks = onsets_from_counters(t, drive, coast, v_impact)
    s = rattle_statistics(t, {"wheel.phi": np.asarray(phi), "mesh.W": np.asarray(W)},
                          onset_speeds, onset_flanks, MeshModel(MeshParameters()).normal_mass,
                          lines=LineSearch(), catalogue=CATALOGUE)
    return {
        "mean wheel speed [rad/s]": s.mean_wheel_speed,
        "impacts/s drive": s.impacts_per_second_drive,
        "impacts/s coast": s.impacts_per_second_coast,
        "median impact speed [mm/s]": s.median_impact_speed * 1e3,
        "RMS normal force [N]": s.rms_normal_force,
        "peak normal force [N]": s.peak_normal_force,
        "strongest detected line 100-1500 Hz [Hz]": s.dominant_line_frequency,
    }


def cosim_statistics(res):
    c = {k.split(".", 1)[1]: np.asarray(v) for k, v in res.columns.items()}
    return statistics(res.time, c["wheel.phi"], c["mesh.W"], c["mesh.impacts_drive"],
                      c["mesh.impacts_coast"], c["mesh.v_impact"])


def reference_statistics(ref):
    return statistics(ref.time, ref.wheel_phi, ref.W, None, None, None, ref.onset_speeds,
                      ref.onset_flanks)


def timed_reference(stop: float):
    best, ref = math.inf, None
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        ref = solve(stop_time=stop)
        best = min(best, time.perf_counter() - t0)
    return best, ref


def single_impact_error() -> dict:
    """One 4 mm/s impact of the free wheel on the drive flank against the closed form."""
    p = MeshParameters(init_in_contact=False, friction_enabled=False)
    from drive_rattle import WheelStepper

    st = WheelStepper(p, 0.0, 0.0, 0.0)
    m = st.mesh
    v = 4e-3
    st.restore(replace(st.snapshot(), state=replace(
        st.state, phi=st._wheel_angle(1, 0.0, -20e-9), w=-v / m.arm_wheel)))
    ref = hertz.hertz_impact(m.normal_mass, m.stiffness_sum(1, 0.0), v)
    d_peak, events = 0.0, []
    for k in range(100):
        r = st.step(1e-4, 0.0, 0.0)
        d_peak = max(d_peak, r.delta_peak)
        events += [(k * 1e-4 + e.time, e) for e in r.events]
        if any(e.kind == "release" for _, e in events):
            break
    (t_on, _), (t_off, off) = events[:2]
    return {"delta_max": d_peak / ref.delta_max - 1,
            "contact duration": (t_off - t_on) / ref.t_contact - 1,
            "rebound speed": -off.speed / v - 1}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="shorter horizons (a smoke run)")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "benchmarks")
    args = ap.parse_args(argv)
    T = 0.3 if args.quick else 2.0
    report = [f"# Benchmarks ({time.strftime('%Y-%m-%d %H:%M')}, best of {REPEATS}, "
              f"paper scenario, {T:g} s simulated)\n"]

    def emit(title, rows, headers):
        text = f"## {title}\n\n" + markdown_table(rows, headers)
        print(text, flush=True)
        report.append(text)

    with tempfile.TemporaryDirectory(prefix="bench_") as tmp:
        fmus = _build(Path(tmp))
        w1, res1 = cosim(fmus, "GearMeshRattle", T)
        w0, _ = cosim(fmus, "NullMeshRattle", T)
        w3, ref = timed_reference(T)
        R1, R0, R3 = w1 / T, w0 / T, w3 / T
        emit("Ratios (wall time per simulated second)", [
            ("R1: co-simulation, fmpy harness, 1e-4 s", R1),
            ("R0: same with the null mesh model (FMI overhead floor)", R0),
            ("R3: monolithic reference, solve_ivp LSODA rtol 1e-9", R3),
            ("R1 / R0", R1 / R0), ("R1 / R3", R1 / R3)], ("quantity", "value"))

        s_co, s_ref = cosim_statistics(res1), reference_statistics(ref)
        emit("Accuracy: co-simulation (1e-4 s) against the monolithic reference",
             [(k, s_co[k], s_ref[k], (s_co[k] - s_ref[k]) / s_ref[k] if s_ref[k] else math.nan)
              for k in s_co], ("statistic", "co-simulation", "reference", "relative difference"))
        emit("Single impact (4 mm/s, default h_max) against the Hertz closed form",
             [(k, v) for k, v in single_impact_error().items()], ("quantity", "relative error"))

        rows = []
        for step in (1e-5, 3e-5, 1e-4, 3e-4, 1e-3):
            horizon = min(T, 0.3) if step < 3e-5 else T
            wall, res = cosim(fmus, "GearMeshRattle", horizon, step)
            s = cosim_statistics(res)
            rows.append((f"{step:g}", wall / horizon, s["impacts/s drive"] + s["impacts/s coast"],
                         s["median impact speed [mm/s]"], s["RMS normal force [N]"]))
        rows.append(("reference", R3, s_ref["impacts/s drive"] + s_ref["impacts/s coast"],
                     s_ref["median impact speed [mm/s]"], s_ref["RMS normal force [N]"]))
        emit("Cost and accuracy against the communication step",
             rows, ("step [s]", "wall/sim s", "impacts/s", "median impact speed [mm/s]",
                    "RMS force [N]"))

        rows = []
        for horizon in (0.25 * T, 0.5 * T, T, 2 * T):
            wall, _ = cosim(fmus, "GearMeshRattle", horizon)
            rows.append((f"{horizon:g}", wall, wall / horizon))
        emit("Cost against the simulated time", rows, ("simulated [s]", "wall [s]", "wall/sim s"))

        rows = []
        for b in (10e-3, 25e-3, 50e-3, 80e-3):
            pairs = MeshModel(MeshParameters(b=b)).geometry
            wall, res = cosim(fmus, "GearMeshRattle", T / 2, params={"GearMeshRattle.gear.b": b})
            rows.append((f"{b * 1e3:g}", pairs.eps_gamma, pairs.max_pairs, wall / (T / 2)))
        emit("Cost against the number of pairs in contact (face width)", rows,
             ("b [mm]", "eps_gamma", "max pairs", "wall/sim s"))

        rows = []
        cases = grid_design({"GearMeshRattle.gear.backlash": (0.05e-3, 0.2e-3),
                             "Driveline.vehicle.drag": (0.12, 0.2)}, 3)
        for workers in (1, 2):
            with tempfile.TemporaryDirectory() as sweep_dir:
                t0 = time.perf_counter()
                run_sweep(cases, Path(sweep_dir) / "s.csv", fmus["GearMeshRattle"].parent,
                          stop_time=0.2 * T, workers=workers, progress=False)
                wall = time.perf_counter() - t0
            rows.append((workers, len(cases), wall, 60 * len(cases) / wall))
        rows.append(("ratio 2/1", "", "", rows[1][3] / rows[0][3]))
        emit(f"Sweep throughput ({0.2 * T:g} s per case, LocalCluster incl. start-up)", rows,
             ("workers", "cases", "wall [s]", "cases/min"))

    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "report.md").write_text("\n".join(report), encoding="utf-8")
    print(f"wrote {args.out / 'report.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
