"""Speed of the compiled kernel against the pure-Python stepper (docs/kernel.md), paper scenario.

    python benchmarks/kernel_speed.py [--steps 3000] [--repeats 3]

* mesh alone: the default engine-order pinion (drive_rattle.driveline.EngineOrderKinematics)
  and a constant load of 0.15 N.m at a 1e-4 s step, ``step()`` alone and ``step()`` followed
  by ``outputs()`` (the stepper contract: the same call for both);
* with the driveline: ``drive_rattle_cosim.system.simulate`` (mesh + driveline, recording every
  signal at every point) with ``stepper=WheelStepper`` and ``stepper=kernel.new_stepper``.

Each figure is the best of ``--repeats`` runs (the machines here are shared and noisy); both
steppers end in the same state, bit for bit, which the script checks.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from drive_rattle import MeshParameters, WheelStepper, kernel
from drive_rattle.driveline import DrivelineParameters, EngineOrderKinematics
from drive_rattle_build.kernel import compile_kernel
from drive_rattle_cosim import system

H = 1e-4
LOAD = 0.15  # N.m


def _mesh_alone(make, steps: int, outputs: bool) -> tuple[float, tuple]:
    kin = EngineOrderKinematics(DrivelineParameters())
    inputs = [(H, *kin(k * H), LOAD) for k in range(steps)]
    s = make(MeshParameters(), *kin(0.0)[:2], LOAD)
    out, step = s.outputs, s.step
    t0 = time.perf_counter()
    if outputs:
        for args in inputs:
            step(*args)
            out()
    else:
        for args in inputs:
            step(*args)
    return (time.perf_counter() - t0) / steps * 1e6, s.state.as_tuple()


def _with_driveline(make, steps: int) -> tuple[float, float]:
    t0 = time.perf_counter()
    rec = system.simulate(stop_time=steps * H, step=H, stepper=make)
    return (time.perf_counter() - t0) / steps * 1e6, rec.signals["wheel.phi"][-1]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=3000)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        lib = kernel.load_kernel(compile_kernel(Path(tmp) / kernel.LIBRARY_NAME))

        def compiled(*a):
            return kernel.CompiledWheelStepper(*a, library=lib)

        rows = []
        for label, outputs in (("mesh alone, step()", False),
                               ("mesh alone, step() + outputs", True)):
            py = min(_mesh_alone(WheelStepper, args.steps, outputs)
                     for _ in range(args.repeats))
            cc = min(_mesh_alone(compiled, args.steps, outputs) for _ in range(args.repeats))
            assert [x.hex() if isinstance(x, float) else x for x in py[1]] == [
                x.hex() if isinstance(x, float) else x for x in cc[1]]
            rows.append((label, py[0], cc[0]))
        py = min(_with_driveline(WheelStepper, args.steps) for _ in range(args.repeats))
        cc = min(_with_driveline(compiled, args.steps) for _ in range(args.repeats))
        assert py[1] == cc[1]
        rows.append(("with the driveline (system.simulate)", py[0], cc[0]))
    print(f"paper scenario, {args.steps} steps of {H:g} s, load {LOAD} N.m, best of "
          f"{args.repeats}")
    print("| case | Python [us/step] | compiled [us/step] | ratio |")
    print("|---|---:|---:|---:|")
    for label, t_py, t_c in rows:
        print(f"| {label} | {t_py:.0f} | {t_c:.1f} | {t_py / t_c:.0f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
