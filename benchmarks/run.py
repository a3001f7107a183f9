"""Benchmarks of the paper scenario, every figure measured side by side in this one run.

    python benchmarks/run.py [--quick] [--out out/benchmarks]

* R1: wall time per simulated second of the GearMeshRattle + Driveline co-simulation under the
  project's fmpy harness at a 1e-4 s communication step (the real-time factor), for the
  pythonfmu pair and for the native pair (C only, dist/native; target <= 0.2); the same pairs
  in libcosim through the SSP; the native pair in a C master that makes the harness's calls
  (benchmarks/native_floor.c, no Python at all); and the kernel-only floor (rattle_kernel.c's
  rk_step, alone and with rk_outputs, on the paper scenario's pinion, in C);
* R0: the same with the mesh replaced by NullMeshRattle (same interface, no physics): the FMI
  overhead floor; and R1/R0;
* R3: the monolithic reference (drive_rattle_cosim.reference, scipy solve_ivp LSODA, rtol 1e-9,
  contact events) per simulated second; and R1/R3;
* accuracy: the co-simulation's statistics against the monolithic reference, and one impact
  against the Hertz closed form;
* how cost grows: against the communication step (with the accuracy at each), against the
  simulated time, and against the number of pairs in contact (face width);
* sweep throughput: cases per minute with 1 and 2 dask workers, each flavour.

Machines here are shared and noisy: each timing is the best of ``REPEATS`` runs.
"""

from __future__ import annotations

import argparse
import math
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import zipfile
from dataclasses import replace
from pathlib import Path

import numpy as np
from fmpy import read_model_description

from drive_rattle import MeshModel, MeshParameters, WheelStepper, hertz
from drive_rattle.driveline import DrivelineParameters, EngineOrderKinematics
from drive_rattle.interface import CONNECTIONS
from drive_rattle.kernel_layout import MODEL_SIZE, OUTPUT_FIELDS, RESULT_FIELDS, pack_model
from drive_rattle_build import build_fmus, package, validate
from drive_rattle_build.native import build_native
from drive_rattle_build.shim import fmi2_headers
from drive_rattle_cosim.analysis import (
    LineSearch,
    catalogue_for,
    markdown_table,
    onsets_from_counters,
    rattle_statistics,
)
from drive_rattle_cosim.harness import CoSimulation, Unit
from drive_rattle_cosim.reference import solve
from drive_rattle_cosim.ssp import write_ssp
from drive_rattle_cosim.sweep import grid_design, run_sweep

ROOT = Path(__file__).resolve().parents[1]
REPEATS = 2
RECORD = ["GearMeshRattle.wheel.phi", "GearMeshRattle.wheel.w", "GearMeshRattle.mesh.W",
          "GearMeshRattle.mesh.W_peak", "GearMeshRattle.mesh.v_impact",
          "GearMeshRattle.mesh.impacts_drive", "GearMeshRattle.mesh.impacts_coast"]
CATALOGUE = catalogue_for(MeshParameters(), DrivelineParameters())


def _build(out: Path) -> dict[str, Path]:
    """The pythonfmu FMUs, the null mesh, and the native FMUs (linux64) as "native <name>"."""
    paths = build_fmus(out)
    null = package(ROOT / "benchmarks" / "NullMeshRattle.py", out, references=False)
    validate(null, use_fmutool=False)
    paths["NullMeshRattle"] = null
    for p in build_native(out / "native", use_fmutool=False, platforms=("linux64",)):
        paths[f"native {p.stem}"] = p
    return paths


def cosim(fmus, mesh: str, stop: float, step: float = 1e-4, params=None,
          driveline: str = "Driveline"):
    """(best wall time [s], result) of one co-simulation."""
    best, result = math.inf, None
    for _ in range(REPEATS):
        with CoSimulation(fmus[mesh], fmus[driveline], params or {}, step=step) as sim:
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
    """One 4 mm/s impact of the free wheel on the drive flank against the undamped Hertz closed
    form (a spur pair without dissipation: every pair in mesh shares one penetration, W = sum
    K_i delta^1.5; with crowned helical pairs there is no closed form)."""
    p = MeshParameters(init_in_contact=False, friction_enabled=False, dissipation=0,
                       beta=0.0, b=20e-3)
    st = WheelStepper(p, 0.0, 0.0, 0.0)
    m = st.mesh
    v = 4e-3
    st.restore(replace(st.snapshot(), state=replace(
        st.state, phi=st._wheel_angle(1, 0.0, -20e-9), w=-v / m.arm_wheel)))
    K = sum(m.law.coefficients(st.geometry.normal_radii(s)[2])[0]
            for _, s, _, _ in st.geometry.pairs(1, 0.0))
    ref = hertz.hertz_impact(m.normal_mass, K, v)
    d_peak, events = 0.0, []
    for k in range(100):
        r = st.step(1e-5, 0.0, 0.0, 0.0, 0.0)
        d_peak = max(d_peak, r.delta_peak)
        events += [(k * 1e-5 + e.time, e) for e in r.events]
        if any(e.kind == "release" for _, e in events):
            break
    (t_on, _), (t_off, off) = events[:2]
    return {"delta_max": d_peak / ref.delta_max - 1,
            "contact duration": (t_off - t_on) / ref.t_contact - 1,
            "rebound speed": -off.speed / v - 1}


LIBCOSIM_TIMING = """
import sys, time
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
log_output_level(CosimLogLevel.WARNING)
ex = CosimExecution.from_ssp_file(sys.argv[1], round(float(sys.argv[3]) * 1e9))
t0 = time.perf_counter()
assert ex.simulate_until(round(float(sys.argv[2]) * 1e9))
print(time.perf_counter() - t0)
"""


def libcosim_wall(mesh: Path, driveline: Path, stop: float, work: Path) -> float:
    """Best wall time [s] of libcosim running the pair's SSP to ``stop`` (simulate_until, no
    observer), each run in its own process (libcosim and Python FMUs share one)."""
    ssp = write_ssp(work / f"{mesh.parent.name}-{mesh.stem}.ssp", mesh, driveline, {}, step=1e-4)
    best = math.inf
    for _ in range(REPEATS):
        run = subprocess.run([sys.executable, "-c", LIBCOSIM_TIMING, str(ssp), repr(stop),
                              "1e-4"], capture_output=True, text=True, timeout=3600)
        if run.returncode != 0:
            raise RuntimeError(f"libcosim failed: {run.stderr[-2000:]}")
        best = min(best, float(run.stdout.strip().splitlines()[-1]))
    return best


def _floor_program(work: Path) -> Path | None:
    """benchmarks/native_floor.c compiled with gcc (None without gcc)."""
    cc = shutil.which("gcc")
    if cc is None:
        return None
    exe = work / "native_floor"
    subprocess.run([cc, "-std=c99", "-O2", "-I", str(fmi2_headers()), "-o", str(exe),
                    str(ROOT / "benchmarks" / "native_floor.c"), "-ldl"], check=True)
    return exe


def _unpacked(fmu: Path, work: Path) -> Path:
    folder = work / f"unpacked-{fmu.parent.name}-{fmu.stem}"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    return folder


def c_master_wall(exe: Path, mesh: Path, driveline: Path, stop: float, work: Path,
                  reference) -> float:
    """Best wall time [s] of the native pair in native_floor.c's C master, which makes the
    harness's calls (recording RECORD); its last recorded values must be the harness's."""
    units = {"GearMeshRattle": Unit(mesh, "probe-mesh"), "Driveline": Unit(driveline, "probe-d")}
    vr = {name: {v: u.var(v).vr for v in u.variables} for name, u in units.items()}
    guid = {name: read_model_description(str(u.fmu)).guid for name, u in units.items()}
    for u in units.values():
        u.close()
    m2d = [(vr["GearMeshRattle"][o], vr["Driveline"][i]) for s, o, d, i in CONNECTIONS
           if s == "GearMeshRattle"]
    d2m = [(vr["Driveline"][o], vr["GearMeshRattle"][i]) for s, o, d, i in CONNECTIONS
           if s == "Driveline"]
    names = [r.split(".", 1)[1] for r in RECORD]
    types = {v.name: v.type for v in read_model_description(str(mesh)).modelVariables}
    real = [vr["GearMeshRattle"][n] for n in names if types[n] == "Real"]
    ints = [vr["GearMeshRattle"][n] for n in names if types[n] == "Integer"]
    dirs = {name: _unpacked(fmu, work) for name, fmu in (("GearMeshRattle", mesh),
                                                          ("Driveline", driveline))}
    args = [str(exe), "pair"]
    for name in ("GearMeshRattle", "Driveline"):
        args += [str(dirs[name] / "binaries" / "linux64" / f"{name}.so"),
                 (dirs[name] / "resources").as_uri(), guid[name]]
    args += [repr(stop), "1e-4", ",".join(str(o) for o, _ in m2d),
             ",".join(str(i) for _, i in m2d), ",".join(str(o) for o, _ in d2m),
             ",".join(str(i) for _, i in d2m), ",".join(map(str, real)),
             ",".join(map(str, ints))]
    best = math.inf
    for _ in range(REPEATS):
        out = subprocess.run(args, capture_output=True, text=True, check=True).stdout.split()
        best = min(best, float(out[0]))
        last = [float(x) for x in out[1:]]
    expected = [reference[r][-1] for r in RECORD if types[r.split(".", 1)[1]] == "Real"]
    if last != expected:
        raise RuntimeError(f"the C master's last values {last} differ from the harness's "
                           f"{expected}")
    return best


def kernel_floor(exe: Path, mesh: Path, stop: float, work: Path) -> tuple[float, float]:
    """Best wall times [s] of rk_step alone and with rk_outputs over ``stop`` seconds of the
    paper scenario's pinion (default engine orders) under the default drag, in C."""
    params, drive = MeshParameters(), DrivelineParameters()
    kinematics = EngineOrderKinematics(drive)
    steps = round(stop / 1e-4)
    stepper = WheelStepper(params, *kinematics(0.0)[:2], drive.drag)
    data = work / "kernel_floor.bin"
    model = pack_model(stepper)
    inputs = [x for k in range(steps) for x in (1e-4, *kinematics(k * 1e-4), drive.drag)]
    values = [MODEL_SIZE, len(stepper.state.as_tuple()), len(RESULT_FIELDS),
              len(OUTPUT_FIELDS), steps, *model, *map(float, stepper.state.as_tuple()), *inputs]
    data.write_bytes(struct.pack(f"{len(values)}d", *values))
    library = _unpacked(mesh, work) / "binaries" / "linux64" / f"{mesh.stem}.so"
    walls = []
    for outputs in ("0", "1"):
        walls.append(min(float(subprocess.run([str(exe), "kernel", str(library), str(data),
                                                outputs], capture_output=True, text=True,
                                               check=True).stdout.split()[0])
                         for _ in range(REPEATS)))
    return walls[0], walls[1]


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
        work = Path(tmp)
        fmus = _build(work)
        w1, res1 = cosim(fmus, "GearMeshRattle", T)
        w1n, res1n = cosim(fmus, "native GearMeshRattle", T, driveline="native Driveline")
        if res1n.columns != res1.columns:
            raise RuntimeError("the native pair's run differs from the pythonfmu pair's")
        w0, _ = cosim(fmus, "NullMeshRattle", T)
        w3, ref = timed_reference(T)
        wl = libcosim_wall(fmus["GearMeshRattle"], fmus["Driveline"], T, work)
        wln = libcosim_wall(fmus["native GearMeshRattle"], fmus["native Driveline"], T, work)
        R1, R0, R3, R1n = w1 / T, w0 / T, w3 / T, w1n / T
        rows = [
            ("R1: pythonfmu pair, fmpy harness, 1e-4 s", R1),
            ("R1 native: native pair, fmpy harness, 1e-4 s (target <= 0.2)", R1n),
            ("pythonfmu pair in libcosim (SSP, 1e-4 s)", wl / T),
            ("native pair in libcosim (SSP, 1e-4 s)", wln / T)]
        exe = _floor_program(work)
        if exe is not None:
            wc = c_master_wall(exe, fmus["native GearMeshRattle"], fmus["native Driveline"], T,
                               work, res1n)
            k0, k1 = kernel_floor(exe, fmus["native GearMeshRattle"], T, work)
            rows += [("native pair in a C master making the harness's calls (no Python)", wc / T),
                     ("kernel-only floor: rk_step, mesh alone, in C", k0 / T),
                     ("kernel-only floor: rk_step + rk_outputs, mesh alone, in C", k1 / T)]
        rows += [
            ("R0: pythonfmu pair with the null mesh model (FMI overhead floor)", R0),
            ("R3: monolithic reference, solve_ivp LSODA rtol 1e-9", R3),
            ("R1 / R1 native", R1 / R1n), ("R1 / R0", R1 / R0), ("R1 / R3", R1 / R3),
            ("R1 native / R3", R1n / R3)]
        emit("Ratios (wall time per simulated second; the native pair's outputs equal the "
             "pythonfmu pair's bit for bit)", rows, ("quantity", "value"))

        s_co, s_ref = cosim_statistics(res1), reference_statistics(ref)
        emit("Accuracy: co-simulation (1e-4 s) against the monolithic reference",
             [(k, s_co[k], s_ref[k], (s_co[k] - s_ref[k]) / s_ref[k] if s_ref[k] else math.nan)
              for k in s_co], ("statistic", "co-simulation", "reference", "relative difference"))
        emit("Single impact (4 mm/s, spur pair, undamped, default h_max) against the Hertz "
             "closed form",
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
        for flavour, folder in (("pythonfmu", fmus["GearMeshRattle"].parent),
                                ("native", fmus["native GearMeshRattle"].parent)):
            per = []
            for workers in (1, 2):
                with tempfile.TemporaryDirectory() as sweep_dir:
                    t0 = time.perf_counter()
                    run_sweep(cases, Path(sweep_dir) / "s.csv", folder, stop_time=0.2 * T,
                              workers=workers, progress=False)
                    wall = time.perf_counter() - t0
                per.append(60 * len(cases) / wall)
                rows.append((flavour, workers, len(cases), wall, per[-1]))
            rows.append((flavour, "ratio 2/1", "", "", per[1] / per[0]))
        emit(f"Sweep throughput ({0.2 * T:g} s per case, LocalCluster incl. start-up)", rows,
             ("flavour", "workers", "cases", "wall [s]", "cases/min"))

    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "report.md").write_text("\n".join(report), encoding="utf-8")
    print(f"wrote {args.out / 'report.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
