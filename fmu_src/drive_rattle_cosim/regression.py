"""Regression kit for exported FMUs: reference results in the FMI cross-check layout and a
check that holds any built FMU against them.

For each model ``<Model>`` the committed folder ``regression/<Model>/`` holds

* ``<Model>_in.csv``  -- the inputs at every communication point (from the coupled paper
  scenario with a strong order-2 fluctuation, ``SCENARIO_DRIVELINE``),
* ``<Model>_ref.csv`` -- the reference outputs over the same short, deterministic horizon,
* ``<Model>_ref.opt`` -- StartTime, StopTime, StepSize and the tolerances of the check;

The build (``drive_rattle_build.fmu``) packs the same files into each FMU under
``resources/regression/``.

The check simulates the FMU with fmpy on the reference inputs and requires, for every output
column, ``|y - y_ref| <= RelTol |y_ref| + AbsTol (max y_ref - min y_ref)`` at every point.  The
tolerances (1e-6) are far below what a 1 % change of a physical parameter does over the horizon
(tests/cosim/test_regression.py perturbs backlash, inertia and shaft stiffness by 1 % and shows
the check failing) and far above rounding differences between platforms over 500 steps.

    python -m drive_rattle_cosim.regression check dist/GearMeshRattle.fmu [--reference-dir DIR]
    python -m drive_rattle_cosim.regression generate --fmu-dir dist   # rewrite the references
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from fmpy import read_model_description, simulate_fmu

from drive_rattle.interface import CONNECTIONS, MODELS

from .paths import DIST, REFERENCES

#: The committed references, a folder per model (``paths.REFERENCES``).
REFERENCE_ROOT = REFERENCES
#: Horizon of the references: 500 communication steps of the paper scenario.
START, STOP, STEP = 0.0, 0.05, 1e-4
REL_TOL = 1e-6
ABS_TOL = 1e-6  # relative to each reference column's range
#: The coupled run whose signals are the reference inputs: the paper scenario with a strong
#: order-2 fluctuation, so that the wheel crosses the backlash (coast impacts) within the
#: horizon and the backlash acts on the dynamics, not only on the wheel's angle offset.
SCENARIO_DRIVELINE = {"engine.amplitude[1]": 2000.0}
#: Inputs of each model: the outputs of the other unit in the coupled run.
INPUTS = {model: tuple(c.input for c in CONNECTIONS if c.target == model) for model in MODELS}


@dataclass
class ColumnCheck:
    name: str
    max_error: float
    tolerance: float  # at the worst point
    worst_time: float

    @property
    def passed(self) -> bool:
        return self.max_error <= self.tolerance


def read_opt(path: Path) -> dict[str, float]:
    """Read a cross-check ``.opt`` file (``Key,value`` per line)."""
    out = {}
    for line in Path(path).read_text(encoding="utf-8").splitlines():
        if line.strip():
            key, _, value = line.partition(",")
            out[key.strip()] = float(value)
    return out


def write_opt(path: Path) -> None:
    path.write_text(f"StartTime,{START!r}\nStopTime,{STOP!r}\nStepSize,{STEP!r}\n"
                    f"RelTol,{REL_TOL!r}\nAbsTol,{ABS_TOL!r}\n", encoding="utf-8")


def _read_csv(path: Path) -> np.ndarray:
    with Path(path).open(encoding="utf-8") as f:
        rows = list(csv.reader(f))
    names = [n.strip('"') for n in rows[0]]
    data = np.array([[float(x) for x in r] for r in rows[1:]], dtype=float)
    return np.rec.fromarrays(data.T, names=names)


def _write_csv(path: Path, names: list[str], columns: list) -> None:
    with Path(path).open("w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(names)
        for row in zip(*columns, strict=True):
            w.writerow([repr(float(v)) for v in row])


def _output_names(fmu: Path) -> list[str]:
    md = read_model_description(str(fmu))
    return [v.name for v in md.modelVariables  # FMI 2.0's types and FMI 3.0's
            if v.causality == "output" and v.type in ("Real", "Integer", "Float64", "Int32")]


def simulate_on_inputs(fmu: Path, inputs: np.ndarray, opt: dict, start_values=None):
    """Run ``fmu`` under fmpy on the reference inputs with the options of the .opt file: FMI
    2.0 FMUs with ``simulate_fmu``, FMI 3.0 FMUs with the same loop (:func:`_fmi3_on_inputs`)."""
    if read_model_description(str(fmu)).fmiVersion.startswith("3"):
        return _fmi3_on_inputs(Path(fmu), inputs, opt, start_values or {})
    return simulate_fmu(str(fmu), start_time=opt["StartTime"], stop_time=opt["StopTime"],
                        output_interval=opt["StepSize"], input=inputs,
                        output=_output_names(fmu), start_values=start_values or {})


def _fmi3_on_inputs(fmu: Path, inputs: np.ndarray, opt: dict, start_values: dict):
    """An FMI 3.0 FMU on the reference inputs with fmpy's FMI 2.0 co-simulation loop (its
    ``Input`` and ``Recorder``; points t_k = k h, every step h).  fmpy's own FMI 3.0 loop steps
    by (k + 1) h - k h, which differs from h in the last bits; the outputs stay within the
    references' tolerance there (tests/model/test_conditioning.py holds the model to that),
    but on the FMI 2.0 grid the FMI 3.0 FMUs compute the FMI 2.0 FMUs' numbers bit for bit
    (tests/fmi3), the stronger check."""
    import shutil

    from fmpy import extract, instantiate_fmu
    from fmpy.simulation import (
        Input,
        Recorder,
        apply_start_values,
        settable_in_initialization_mode,
        settable_in_instantiated,
    )

    md = read_model_description(str(fmu))
    unzipdir = extract(str(fmu))
    slave = instantiate_fmu(unzipdir, md, "CoSimulation")
    try:
        t0, stop, h = opt["StartTime"], opt["StopTime"], opt["StepSize"]
        values = dict(start_values)
        values = apply_start_values(slave, md, values, settable=settable_in_instantiated)
        slave.enterInitializationMode(startTime=t0)
        values = apply_start_values(slave, md, values, settable=settable_in_initialization_mode)
        if values:
            raise ValueError(f"start values not settable: {', '.join(values)}")
        source = Input(slave, md, inputs)
        source.apply(t0)
        slave.exitInitializationMode()
        recorder = Recorder(fmu=slave, modelDescription=md, variableNames=_output_names(fmu),
                            interval=h)
        time, n = t0, round(t0 / h)
        while True:
            recorder.sample(time, force=True)
            if time >= stop:
                break
            source.apply(time)
            if time + h <= stop:
                slave.doStep(currentCommunicationPoint=time, communicationStepSize=h)
                n += 1
                time = n * h
            else:
                slave.doStep(currentCommunicationPoint=time, communicationStepSize=stop - time)
                time = stop
        slave.terminate()
        return recorder.result()
    finally:
        slave.freeInstance()
        shutil.rmtree(unzipdir, ignore_errors=True)


def _references_in_fmu(fmu: Path, tmp: Path) -> Path:
    model = read_model_description(str(fmu)).coSimulation.modelIdentifier
    with zipfile.ZipFile(fmu) as z:
        members = [m for m in z.namelist() if m.startswith("resources/regression/")]
        if not members:
            raise FileNotFoundError(
                f"{fmu} contains no resources/regression/ references; pass --reference-dir")
        for m in members:
            (tmp / Path(m).name).write_bytes(z.read(m))
    return tmp / model


def check(fmu: Path, reference_dir: Path | None = None,
          start_values: dict | None = None) -> list[ColumnCheck]:
    """Hold ``fmu`` against its references (the ones packed in the FMU by default).

    ``start_values`` override parameters, to demonstrate what the check catches."""
    fmu = Path(fmu)
    model = read_model_description(str(fmu)).coSimulation.modelIdentifier
    with tempfile.TemporaryDirectory() as tmp:
        if reference_dir is None:
            base = _references_in_fmu(fmu, Path(tmp))
        else:
            base = Path(reference_dir) / model / model
        inputs = _read_csv(Path(f"{base}_in.csv"))
        ref = _read_csv(Path(f"{base}_ref.csv"))
        opt = read_opt(Path(f"{base}_ref.opt"))
    result = simulate_on_inputs(fmu, inputs, opt, start_values)
    if len(result) != len(ref) or not np.array_equal(result["time"], ref["time"]):
        raise ValueError(f"{model}: the run has {len(result)} points, the reference "
                         f"{len(ref)}: not the same time grid")
    checks = []
    for name in ref.dtype.names:
        if name == "time":
            continue
        y, r = np.asarray(result[name], dtype=float), np.asarray(ref[name], dtype=float)
        tol = opt["RelTol"] * np.abs(r) + opt["AbsTol"] * (np.max(r) - np.min(r))
        err = np.abs(y - r)
        excess = err - tol
        k = int(np.argmax(excess))
        checks.append(ColumnCheck(name, float(err[k]), float(tol[k]), float(ref["time"][k])))
    return checks


def generate(fmu_dir: Path, out_root: Path = REFERENCE_ROOT) -> list[Path]:
    """Write the references of both models from the coupled paper scenario (inputs) and the
    FMUs in ``fmu_dir`` (outputs)."""
    from drive_rattle.parameters import DrivelineParameters

    from .system import simulate

    rec = simulate(driveline_params=DrivelineParameters.from_public(SCENARIO_DRIVELINE),
                   stop_time=STOP, step=STEP, start_time=START)
    written = []
    for model in MODELS:
        folder = out_root / model
        folder.mkdir(parents=True, exist_ok=True)
        names = list(INPUTS[model])
        _write_csv(folder / f"{model}_in.csv", ["time", *names],
                   [rec.time, *(rec.signals[n] for n in names)])
        write_opt(folder / f"{model}_ref.opt")
        fmu = Path(fmu_dir) / f"{model}.fmu"
        res = simulate_on_inputs(fmu, _read_csv(folder / f"{model}_in.csv"),
                                 read_opt(folder / f"{model}_ref.opt"))
        outs = [n for n in res.dtype.names if n != "time"]
        _write_csv(folder / f"{model}_ref.csv", ["time", *outs],
                   [res["time"], *(res[n] for n in outs)])
        written += [folder / f"{model}{s}" for s in ("_in.csv", "_ref.csv", "_ref.opt")]
    return written


def reference_files(model: str, root: Path = REFERENCE_ROOT) -> list[Path]:
    """The committed reference files of ``model`` (for packing into the FMU)."""
    return [root / model / f"{model}{s}" for s in ("_in.csv", "_ref.csv", "_ref.opt")]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m drive_rattle_cosim.regression",
                                 description="Regression kit for the drive-rattle FMUs.")
    sub = ap.add_subparsers(dest="command", required=True)
    c = sub.add_parser("check", help="check built FMUs against their references")
    c.add_argument("fmus", nargs="+", type=Path)
    c.add_argument("--reference-dir", type=Path, default=None,
                   help="folder with <Model>/<Model>_{in,ref}.csv, _ref.opt (default: in the FMU)")
    g = sub.add_parser("generate", help="rewrite the committed references from built FMUs")
    g.add_argument("--fmu-dir", type=Path, default=DIST)
    g.add_argument("--out", type=Path, default=REFERENCE_ROOT)
    args = ap.parse_args(argv)
    if args.command == "generate":
        for p in generate(args.fmu_dir, args.out):
            print("wrote", p)
        return 0
    failed = False
    for fmu in args.fmus:
        checks = check(fmu, args.reference_dir)
        bad = [c for c in checks if not c.passed]
        failed |= bool(bad)
        print(f"{fmu}: {'FAIL' if bad else 'pass'} ({len(checks)} outputs)")
        for col in bad:
            ratio = col.max_error / col.tolerance if col.tolerance > 0 else math.inf
            print(f"  {col.name}: error {col.max_error:.3g} at t = {col.worst_time:.4g} s, "
                  f"{ratio:.3g} x the tolerance {col.tolerance:.3g}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
