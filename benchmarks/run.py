"""Benchmarks of the paper scenario and of sweeps, every figure measured side by side in this
one run (the machines here are shared and noisy: absolute times vary between days, the ratios
measured in one run hold; each timing is the best of ``REPEATS``).

    python benchmarks/run.py [--quick] [--out out/benchmarks]

Wall time per simulated second of the paper scenario (default parameters, 1e-4 s step), and its
ratio to the floor:

* **floor**: the model's own work -- the mesh's stepper (``rm_wheel_step``) alone on the
  recorded pinion inputs, in C (``benchmarks/floor.c``): no unit layer, no driveline, no
  coupling, no Python;
* **compiled loop**: the two units coupled in the model library (``units.run_coupled``), one
  call from Python;
* **C master**: the native FMUs dlopen'ed by ``benchmarks/c_master.c``, which makes the fmpy
  harness's calls (no Python);
* **raw ctypes loop**: the native FMUs' fmi2 functions from a minimal Python loop
  (preallocated arrays, the harness's calls);
* **harness**: ``drive_rattle_cosim.harness`` on the native FMUs and on the pythonfmu FMUs;
* **libcosim**: the native SSP in libcosim, pinned to one core (``taskset -c 0``) and not;
* **monolithic reference**: ``tests/oracle/reference.py`` (scipy LSODA, rtol 1e-9).

Every run's last recorded wheel speed must equal the compiled loop's, bit for bit, before its
time is reported.  Then the sweep: seconds per 12 s case (end to end in the worker: the units,
the run, the metrics) with the library engine and with the native FMUs, and the throughput of
two workers against one (cluster start-up excluded).  Prints the tables and writes
``out/benchmarks/report.md``.
"""

from __future__ import annotations

import argparse
import ctypes
import math
import shutil
import statistics
import struct
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # the oracle's monolithic reference (tests/oracle)

from drive_rattle import DrivelineParameters, MeshParameters  # noqa: E402
from drive_rattle.interface import CONNECTIONS  # noqa: E402
from drive_rattle.units import (  # noqa: E402
    DrivelineUnit,
    MeshUnit,
    coupled_start_inputs,
    run_coupled,
)
from drive_rattle_build import build_fmus  # noqa: E402
from drive_rattle_build.library import build_in_place  # noqa: E402
from drive_rattle_build.native import build_native  # noqa: E402
from drive_rattle_build.shim import fmi2_headers  # noqa: E402
from drive_rattle_cosim.analysis import markdown_table  # noqa: E402
from drive_rattle_cosim.harness import CoSimulation  # noqa: E402
from drive_rattle_cosim.progress import Phases  # noqa: E402
from drive_rattle_cosim.ssp import write_ssp  # noqa: E402
from drive_rattle_cosim.sweep import grid_design, read_results, run_sweep  # noqa: E402
from tests.oracle.reference import solve  # noqa: E402

REPEATS = 3
STEP_NS = 100_000
RECORD = "GearMeshRattle.wheel.w"
MODEL = ROOT / "fmu_src" / "rattle_model"


# ------------------------------------------------------------------ the runs
def coupled_pair():
    """The two units initialized as the co-simulation starts them (default parameters)."""
    mp, dp = MeshParameters(), DrivelineParameters()
    m_in, wheel = coupled_start_inputs(mp, dp)
    return (MeshUnit(mp, m_in["pinion.phi"], m_in["pinion.w"], m_in["wheel.tau_load"],
                     m_in["pinion.a"]),
            DrivelineUnit(dp, wheel["wheel.phi"], wheel["wheel.w"]))


def compiled_loop(steps: int) -> tuple[float, float, object]:
    """(best wall [s], last wheel speed, the run recording the mesh's inputs)."""
    best, run = math.inf, None
    record = [RECORD, "Driveline.pinion.phi", "Driveline.pinion.w", "Driveline.pinion.a",
              "Driveline.wheel.tau_load"]
    for _ in range(REPEATS):
        mesh, drive = coupled_pair()
        t0 = time.perf_counter()
        run = run_coupled(mesh, drive, STEP_NS, steps, record)
        best = min(best, time.perf_counter() - t0)
        mesh.close()
        drive.close()
    return best, run.columns[RECORD][-1], run


def compile_c(work: Path, name: str, sources, includes, libs=()) -> Path:
    exe = work / name
    subprocess.run(["gcc", "-std=c99", "-O2", "-fno-fast-math", "-ffp-contract=off",
                    *(f"-I{i}" for i in includes), "-o", str(exe), *map(str, sources), *libs],
                   check=True)
    return exe


def floor_wall(work: Path, run, steps: int) -> tuple[float, float]:
    """(best wall [s], last wheel speed) of benchmarks/floor.c on the compiled loop's recorded
    mesh inputs."""
    data = [float(steps)]
    time = run.time
    inputs = [run.columns[f"Driveline.{n}"]
              for n in ("pinion.phi", "pinion.w", "pinion.a", "wheel.tau_load")]
    for k in range(steps):
        data += [time[k + 1] - time[k], *(column[k] for column in inputs)]
    path = work / "floor.bin"
    path.write_bytes(struct.pack(f"{len(data)}d", *data))
    exe = compile_c(work, "floor", [ROOT / "benchmarks" / "floor.c",
                                    *sorted(MODEL.glob("*.c"))], [MODEL], ["-lm"])
    out = subprocess.run([str(exe), str(path), str(REPEATS)], capture_output=True, text=True,
                         check=True).stdout.split()
    return float(out[0]), float(out[2])


def _unpacked(fmu: Path, work: Path) -> Path:
    folder = work / f"unpacked-{fmu.parent.name}-{fmu.stem}"
    if not folder.is_dir():
        with zipfile.ZipFile(fmu) as z:
            z.extractall(folder)
    return folder


def _plan(fmus: dict) -> tuple[dict, dict, list, list]:
    """The value references of the coupling and of the recorded output, from the FMUs."""
    from fmpy import read_model_description

    md = {name: read_model_description(str(path)) for name, path in fmus.items()}
    vr = {name: {v.name: v.valueReference for v in m.modelVariables} for name, m in md.items()}
    m2d = [(vr[s][o], vr[d][i]) for s, o, d, i in CONNECTIONS if s == "GearMeshRattle"]
    d2m = [(vr[s][o], vr[d][i]) for s, o, d, i in CONNECTIONS if s == "Driveline"]
    return md, vr, m2d, d2m


def c_master_wall(work: Path, native: dict, stop: float) -> tuple[float, float]:
    """(best wall [s], last wheel speed) of benchmarks/c_master.c on the native FMUs."""
    md, vr, m2d, d2m = _plan(native)
    exe = compile_c(work, "c_master", [ROOT / "benchmarks" / "c_master.c"], [fmi2_headers()],
                    ["-ldl"])
    args = [str(exe)]
    for name in ("GearMeshRattle", "Driveline"):
        folder = _unpacked(native[name], work)
        args += [str(folder / "binaries" / "linux64" / f"{name}.so"),
                 (folder / "resources").as_uri(), md[name].guid]
    args += [repr(stop), "1e-4", ",".join(str(o) for o, _ in m2d),
             ",".join(str(i) for _, i in m2d), ",".join(str(o) for o, _ in d2m),
             ",".join(str(i) for _, i in d2m), str(vr["GearMeshRattle"]["wheel.w"])]
    best, last = math.inf, math.nan
    for _ in range(REPEATS):
        out = subprocess.run(args, capture_output=True, text=True, check=True).stdout.split()
        best, last = min(best, float(out[0])), float(out[1])
    return best, last


def raw_ctypes_wall(work: Path, native: dict, steps: int) -> tuple[float, float]:
    """(best wall [s], last wheel speed): the native FMUs' fmi2 functions from a minimal
    Python loop making the harness's calls, on preallocated ctypes arrays."""
    from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackLoggerTYPE

    md, vr, m2d, d2m = _plan(native)
    logger = fmi2CallbackLoggerTYPE(lambda *a: None)
    callbacks = fmi2CallbackFunctions()
    callbacks.logger = logger
    best, last = math.inf, math.nan
    for _ in range(REPEATS):
        units = {}
        for name in ("GearMeshRattle", "Driveline"):
            folder = _unpacked(native[name], work)
            lib = ctypes.CDLL(str(folder / "binaries" / "linux64" / f"{name}.so"))
            lib.fmi2Instantiate.restype = ctypes.c_void_p
            lib.fmi2Instantiate.argtypes = [ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p,
                                            ctypes.c_char_p, ctypes.c_void_p, ctypes.c_int,
                                            ctypes.c_int]
            for fn in ("fmi2SetupExperiment", "fmi2EnterInitializationMode",
                       "fmi2ExitInitializationMode", "fmi2GetReal", "fmi2SetReal", "fmi2DoStep",
                       "fmi2FreeInstance"):
                getattr(lib, fn).argtypes = None
            c = ctypes.c_void_p(lib.fmi2Instantiate(
                b"raw", 1, md[name].guid.encode(), (folder / "resources").as_uri().encode(),
                ctypes.addressof(callbacks), 0, 0))
            lib.fmi2SetupExperiment(c, 0, ctypes.c_double(0.0), ctypes.c_double(0.0), 0,
                                    ctypes.c_double(0.0))
            lib.fmi2EnterInitializationMode(c)
            units[name] = (lib, c)
        (mlib, mc), (dlib, dc) = units["GearMeshRattle"], units["Driveline"]
        m_out = (ctypes.c_uint * 2)(*(o for o, _ in m2d))
        d_in = (ctypes.c_uint * 2)(*(i for _, i in m2d))
        d_out = (ctypes.c_uint * 4)(*(o for o, _ in d2m))
        m_in = (ctypes.c_uint * 4)(*(i for _, i in d2m))
        rec = (ctypes.c_uint * 1)(vr["GearMeshRattle"]["wheel.w"])
        b2, b4, r1 = (ctypes.c_double * 2)(), (ctypes.c_double * 4)(), (ctypes.c_double * 1)()
        for _round in range(2):  # the harness's exchange in initialization mode
            mlib.fmi2GetReal(mc, m_out, 2, b2)
            dlib.fmi2SetReal(dc, d_in, 2, b2)
            dlib.fmi2GetReal(dc, d_out, 4, b4)
            mlib.fmi2SetReal(mc, m_in, 4, b4)
        mlib.fmi2ExitInitializationMode(mc)
        dlib.fmi2ExitInitializationMode(dc)
        points = [ctypes.c_double(k * STEP_NS / 1e9) for k in range(steps + 1)]
        sizes = [ctypes.c_double(points[k + 1].value - points[k].value) for k in range(steps)]
        mget, mset, mstep = mlib.fmi2GetReal, mlib.fmi2SetReal, mlib.fmi2DoStep
        dget, dset, dstep = dlib.fmi2GetReal, dlib.fmi2SetReal, dlib.fmi2DoStep
        t0 = time.perf_counter()
        for k in range(steps):
            mget(mc, rec, 1, r1)
            mget(mc, m_out, 2, b2)
            dset(dc, d_in, 2, b2)
            dget(dc, d_out, 4, b4)
            mset(mc, m_in, 4, b4)
            if mstep(mc, points[k], sizes[k], 1) > 1 or dstep(dc, points[k], sizes[k], 1) > 1:
                raise RuntimeError(f"the raw loop's doStep failed at step {k}")
        mget(mc, rec, 1, r1)
        best = min(best, time.perf_counter() - t0)
        last = r1[0]
        mlib.fmi2FreeInstance(mc)
        dlib.fmi2FreeInstance(dc)
    return best, last


def harness_wall(fmus: dict, stop: float) -> tuple[float, float]:
    best, last = math.inf, math.nan
    for _ in range(REPEATS):
        with CoSimulation(fmus["GearMeshRattle"], fmus["Driveline"]) as sim:
            t0 = time.perf_counter()
            result = sim.run(stop, [RECORD])
            best = min(best, time.perf_counter() - t0)
        last = result.columns[RECORD][-1]
    return best, last


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


def libcosim_wall(native: dict, stop: float, work: Path, pinned: bool) -> float:
    """Best wall [s] of libcosim running the native pair's SSP (simulate_until, no observer),
    each run in its own process; ``pinned``: on one core (taskset -c 0)."""
    ssp = work / "native.ssp"
    if not ssp.is_file():
        write_ssp(ssp, native["GearMeshRattle"], native["Driveline"], {}, step=1e-4)
    prefix = ["taskset", "-c", "0"] if pinned else []
    best = math.inf
    for _ in range(REPEATS):
        run = subprocess.run([*prefix, sys.executable, "-c", LIBCOSIM_TIMING, str(ssp),
                              repr(stop), "1e-4"], capture_output=True, text=True, timeout=3600)
        if run.returncode != 0:
            raise RuntimeError(f"libcosim failed: {run.stderr[-2000:]}")
        best = min(best, float(run.stdout.strip().splitlines()[-1]))
    return best


def sweep_rows(native_dir: Path, case_seconds: float, n_cases: int,
               window: float = 1.0) -> list[tuple]:
    """Seconds per case per worker (the rows' own wall time: units, run and metrics) with the
    library engine and the native FMUs, and the throughput of 2 workers against 1 with the
    library engine (the cluster started before the clock).  Each case leaves out its first
    ``window`` seconds and measures the rest in windows of ``window`` seconds."""
    from dask.distributed import LocalCluster

    side = max(2, round(math.sqrt(n_cases)))
    cases = grid_design({"GearMeshRattle.gear.backlash": (0.06e-3, 0.18e-3),
                         "Driveline.vehicle.drag": (0.04, 0.15)}, side)
    rows, throughput = [], {}
    for label, fmu_dir in (("library (compiled loop)", None), ("native FMUs (harness)",
                                                               native_dir)):
        for workers in (1, 2) if fmu_dir is None else (1,):
            with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                              dashboard_address=None) as cluster, \
                    tempfile.TemporaryDirectory() as folder:
                out = Path(folder) / "sweep.csv"
                t0 = time.perf_counter()
                counts = run_sweep(cases, out, fmu_dir, stop_time=case_seconds,
                                   scheduler=cluster.scheduler_address, progress=False,
                                   transient=window, window=window)
                wall = time.perf_counter() - t0
                per_case = [r["wall_seconds"] for r in read_results(out)]
            if counts["failed"]:
                raise RuntimeError(f"{counts['failed']} sweep cases failed")
            throughput[label, workers] = len(cases) / wall
            rows.append((label, workers, len(cases), statistics.median(per_case),
                         60.0 * len(cases) / wall))
    ratio = throughput["library (compiled loop)", 2] / throughput["library (compiled loop)", 1]
    rows.append(("library: 2 workers / 1 worker", "", "", "", ratio))
    return rows


def reference_wall(stop: float) -> float:
    best = math.inf
    for _ in range(max(1, REPEATS - 1)):
        t0 = time.perf_counter()
        solve(stop_time=stop)
        best = min(best, time.perf_counter() - t0)
    return best


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="a smoke run: shorter horizons, each run once (its ratios are not "
                         "measurements)")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "benchmarks")
    args = ap.parse_args(argv)
    global REPEATS
    if args.quick:
        REPEATS = 1  # every run still runs: what the smoke run checks is that each completes
    T = 1.0 if args.quick else 10.0
    steps = round(T * 1e9 / STEP_NS)
    report = [f"# Benchmarks ({time.strftime('%Y-%m-%d %H:%M')}, best of {REPEATS}, paper "
              f"scenario, {T:g} s simulated, 1e-4 s step)\n"]

    def emit(title, rows, headers):
        text = f"## {title}\n\n" + markdown_table(rows, headers)
        print(text, flush=True)
        report.append(text)

    phases = Phases("benchmarks")
    with phases.phase("building the model library"):
        build_in_place()
    with tempfile.TemporaryDirectory(prefix="bench_") as tmp:
        work = Path(tmp)
        with phases.phase("building the FMUs of both flavours"):
            fmus = build_fmus(work / "dist")
            native = {p.stem: p for p in build_native(work / "native", use_fmutool=False,
                                                      platforms=("x86_64-linux",))}
        with phases.phase("compiled loop"):
            w_loop, last, run = compiled_loop(steps)
        measured = [("compiled loop: the two units in the library, one call", w_loop, last)]
        with phases.phase("floor (benchmarks/floor.c)"):
            w_floor, floor_last = floor_wall(work, run, steps)
        measured.insert(0, ("floor: the mesh's stepper alone in C (rm_wheel_step)", w_floor,
                            None))
        for name, measure in (
                ("C master on the native FMUs (the harness's calls, no Python)",
                 lambda: c_master_wall(work, native, T)),
                ("raw ctypes Python loop on the native FMUs",
                 lambda: raw_ctypes_wall(work, native, steps)),
                ("fmpy harness, native FMUs", lambda: harness_wall(native, T)),
                ("fmpy harness, pythonfmu FMUs", lambda: harness_wall(fmus, T))):
            with phases.phase(name):
                measured.append((name, *measure()))
        for name, _wall, value in measured:
            if value is not None and value != last:
                raise RuntimeError(f"{name}: last wheel speed {value!r} differs from the "
                                   f"compiled loop's {last!r}")
        if shutil.which("taskset"):
            name = "libcosim, native SSP, pinned to one core (taskset -c 0)"
            with phases.phase(name):
                measured.append((name, libcosim_wall(native, T, work, pinned=True), None))
        name = "libcosim, native SSP, not pinned"
        with phases.phase(name):
            measured.append((name, libcosim_wall(native, T, work, pinned=False), None))
        t_ref = 0.1 if args.quick else 2.0  # LSODA at rtol 1e-9: about 20 s per simulated s
        name = f"monolithic reference (LSODA, rtol 1e-9; {t_ref:g} s)"
        with phases.phase(name):
            measured.append((name, reference_wall(t_ref) * T / t_ref, None))
        emit("Wall time per simulated second, and against the floor (every run's last wheel "
             f"speed equals the compiled loop's, {last!r} rad/s)",
             [(name, wall / T, wall / w_floor) for name, wall, _ in measured],
             ("run", "wall / simulated s", "x floor"))
        if floor_last is not None:
            print(f"(the floor ends at {floor_last!r} rad/s: the same trajectory)")
        # the shortest case: one window of transient, one window measured (the quick form's
        # windows of 0.2 s: it checks that every sweep completes, not what a case costs)
        window = 0.2 if args.quick else 1.0
        case = 2 * window if args.quick else 12.0
        with phases.phase("sweeps (library and native FMU engines, 1 and 2 workers)"):
            sweep = sweep_rows(native["GearMeshRattle"].parent, case, 4 if args.quick else 16,
                               window)
        emit(f"Sweep: seconds per {case:g} s case per worker (median of the rows' own wall "
             "time: units, run, metrics) and cases per minute (cluster started before the "
             "clock)",
             sweep, ("engine", "workers", "cases", "s per case", "cases / min"))
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "report.md").write_text("\n".join(report), encoding="utf-8")
    print(f"wrote {args.out / 'report.md'}")
    phases.done()
    return 0


if __name__ == "__main__":
    sys.exit(main())
