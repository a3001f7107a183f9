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

import csv
import io
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


class ReferenceFileError(ValueError):
    """A reference file that cannot be trusted: the message names the file (and the row and
    column where one is wrong), the value and what is allowed."""


#: The keys of a ``.opt`` file, each a finite number.
OPT_KEYS = ("StartTime", "StopTime", "StepSize", "RelTol", "AbsTol")


def _text(path: Path, label: str) -> str:
    """The UTF-8 text of a reference file."""
    data = Path(path).read_bytes()
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise ReferenceFileError(
            f"reference {label} is not UTF-8 text (byte {data[err.start]:#04x} at offset "
            f"{err.start}); allowed: a CSV file of numbers under a header row") from None


def read_opt(path: Path, label: str | None = None) -> dict[str, float]:
    """Read a cross-check ``.opt`` file (``Key,value`` per line, every key of ``OPT_KEYS``
    with a finite number); ReferenceFileError naming the file and line otherwise."""
    label = label or str(path)
    out = {}
    for k, line in enumerate(_text(path, label).splitlines(), start=1):
        if line.strip():
            key, _, value = line.partition(",")
            try:
                number = float(value)
            except ValueError:
                number = math.nan
            if not math.isfinite(number):
                raise ReferenceFileError(f"reference {label} line {k}: {line!r} is not "
                                         "Key,number; allowed: a finite number per key")
            out[key.strip()] = number
    missing = [key for key in OPT_KEYS if key not in out]
    if missing:
        raise ReferenceFileError(f"reference {label} lacks {', '.join(missing)}; allowed: a "
                                 f"line Key,number for each of {', '.join(OPT_KEYS)}")
    return out


def write_opt(path: Path) -> None:
    path.write_text(f"StartTime,{START!r}\nStopTime,{STOP!r}\nStepSize,{STEP!r}\n"
                    f"RelTol,{REL_TOL!r}\nAbsTol,{ABS_TOL!r}\n", encoding="utf-8")


def _read_csv(path: Path, label: str | None = None, columns=None) -> np.recarray:
    """A reference CSV: ``time`` and further columns of distinct names (each one of
    ``columns`` when given: the FMU's inputs or outputs), every cell a finite number.
    ReferenceFileError naming the file, and the row (its line) and column where one is
    wrong, for an empty file, a file that is not UTF-8 text, a header that does not match, a
    row of another length (a file cut short) and a cell that is not a finite number (a NaN
    would pass every comparison unnoticed)."""
    label = label or str(path)
    reader = csv.reader(io.StringIO(_text(path, label)))
    names, data = None, []
    try:
        for row in reader:
            if not row:
                continue
            if names is None:
                names = [n.strip().strip('"') for n in row]
                _check_header(names, label, columns)
                continue
            if len(row) != len(names):
                raise ReferenceFileError(
                    f"reference {label} row {reader.line_num} has {len(row)} fields, the "
                    f"header {len(names)}; allowed: one number per column (a shorter last "
                    "row is a file cut short)")
            data.append([_cell(cell, label, reader.line_num, name)
                         for cell, name in zip(row, names, strict=True)])
    except csv.Error as err:  # a NUL byte, an open quote: not a CSV file
        raise ReferenceFileError(f"reference {label} line {reader.line_num} is not CSV "
                                 f"({err}); allowed: a CSV file of numbers under a header "
                                 "row") from None
    if names is None:
        raise ReferenceFileError(f"reference {label} is empty; allowed: a header row and "
                                 "rows of numbers")
    if not data:
        raise ReferenceFileError(f"reference {label} has a header and no rows; allowed: a "
                                 "row of numbers per communication point")
    return np.rec.fromarrays(np.array(data, dtype=float).T, names=names)


def _check_header(names: list[str], label: str, columns) -> None:
    wrong = [n for n in names[1:] if columns is not None and n not in columns]
    if names[0] != "time" or len(set(names)) != len(names) or wrong:
        what = (f"{wrong[0]!r} is not one of the FMU's variables of that kind" if wrong else
                f"the first column is {names[0]!r}" if names[0] != "time" else
                "a column name repeats")
        raise ReferenceFileError(f"reference {label} has the header {','.join(names)[:200]!r}, "
                                 f"whose {what}; allowed: time, then distinct names of the "
                                 "FMU's variables")


def _cell(text: str, label: str, line: int, name: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = None
    if value is None or not math.isfinite(value):
        raise ReferenceFileError(f"reference {label} row {line}, column {name!r}: {text!r} is "
                                 "not a finite number; allowed: finite numbers")
    return value


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
    references' tolerance there (tests/model/test_stepper.py holds the model to that),
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
    md = read_model_description(str(fmu))
    model = md.coSimulation.modelIdentifier
    causality = {v.name: v.causality for v in md.modelVariables}
    with tempfile.TemporaryDirectory() as tmp:
        if reference_dir is None:
            base = _references_in_fmu(fmu, Path(tmp))
        else:
            base = Path(reference_dir) / model / model

        def label(suffix: str) -> str:
            name = f"{model}{suffix}"
            return (f"{fmu} (resources/regression/{name})" if reference_dir is None
                    else f"{base}{suffix}")

        inputs = _read_csv(Path(f"{base}_in.csv"), label("_in.csv"),
                           [n for n, c in causality.items() if c == "input"])
        ref = _read_csv(Path(f"{base}_ref.csv"), label("_ref.csv"),
                        [n for n, c in causality.items() if c == "output"])
        opt = read_opt(Path(f"{base}_ref.opt"), label("_ref.opt"))
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
    from .cli import Parser

    ap = Parser(prog="python -m drive_rattle_cosim.regression",
                description="Regression kit for the drive-rattle FMUs.",
                epilog="Exit status of check: 0 every FMU passed, 1 an FMU failed its "
                       "references, 2 a request refused before the check (a reference file "
                       "that is missing or cannot be trusted: one line naming it).")
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
        try:
            checks = check(fmu, args.reference_dir)
        except (ReferenceFileError, FileNotFoundError) as err:
            ap.error(str(err))
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
