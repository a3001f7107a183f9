"""fmusim, the C master of the Reference-FMUs (v0.0.39, the last release that has it), runs each
FMI 3.0 FMU alone (fmusim simulates one FMU; it cannot couple two).  The tests may not use the
network, so fmusim is not fetched here: they run when ``RATTLE_FMUSIM`` names an fmusim
executable (docs/fmi3.md says how it was built) and are skipped otherwise.

* On the regression inputs with their times put on fmusim's grid (``t_k = start + k h``,
  where fmusim interpolates nothing), fmusim's outputs equal tests/faces/fmu_host.c's run of
  the same inputs at every point to the 16 significant digits fmusim writes (``%.16g``);
* on the committed inputs as they are (fmusim interpolates them linearly at its own points,
  an ulp away from theirs), its outputs pass the regression references' tolerances;
* an Enumeration is set by name with ``--start-value``, and a code that is not one of its
  choices is refused with the library's message;
* fmusim's ``--final-fmu-state-file`` passes the FMU state where FMI 3.0 asks for its
  address to fmi3FreeFMUState (a defect of fmusim 0.0.39): refused with a message, no crash.
"""

from __future__ import annotations

import csv
import os
import shutil
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest

from drive_rattle.interface import MESH, MODELS
from drive_rattle_cosim.regression import read_opt, reference_files

from ..faces.hosts import compile_host, host_arguments

STOP, INTERVAL = 0.05, 1e-4  # the references' horizon and step


def fmusim_path() -> str | None:
    path = os.environ.get("RATTLE_FMUSIM")
    return shutil.which(path) if path else None


pytestmark = pytest.mark.skipif(fmusim_path() is None, reason=(
    "RATTLE_FMUSIM does not name an fmusim executable (fmusim is not fetched by the tests: "
    "docs/fmi3.md, 'fmusim')"))


@pytest.fixture(scope="module")
def fmusim() -> str:
    return fmusim_path()


@pytest.fixture(scope="module")
def host(tmp_path_factory) -> Path:
    return compile_host(tmp_path_factory.mktemp("fmu_host_fmusim") / "fmu_host", "3.0")


def run_fmusim(fmusim: str, fmu: Path, inputs: Path, out: Path, *options: str):
    return subprocess.run([fmusim, "--interface-type", "cs", "--stop-time", repr(STOP),
                           "--output-interval", repr(INTERVAL), "--input-file", str(inputs),
                           "--output-file", str(out), *options, str(fmu)],
                          capture_output=True, text=True, timeout=300)


def read_csv(path: Path) -> tuple[list[str], list[list[str]]]:
    with Path(path).open(encoding="utf-8") as f:
        rows = list(csv.reader(f))
    return [n.strip('"') for n in rows[0]], rows[1:]


@pytest.mark.parametrize("model", MODELS)
def test_fmusim_alone_is_the_c_host(fmusim, host, fmi3_fmus, model, tmp_path):
    fmu = fmi3_fmus[model]
    names, rows = read_csv(reference_files(model)[0])
    grid = tmp_path / f"{model}_in.csv"  # the same inputs at fmusim's points
    grid.write_text(",".join(names) + "\n" + "".join(
        ",".join([repr(k * INTERVAL), *row[1:]]) + "\n" for k, row in enumerate(rows)),
        encoding="utf-8")
    run = run_fmusim(fmusim, fmu, grid, tmp_path / "fmusim.csv")
    assert run.returncode == 0 and not run.stdout.strip(), run.stdout + run.stderr
    unpacked = tmp_path / "unpacked"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(unpacked)
    platform = "x86_64-linux"
    args = host_arguments(fmu, str(unpacked / "binaries" / platform / f"{model}.so"),
                          f"{unpacked / 'resources'}/", str(grid), str(tmp_path / "host.csv"))
    assert subprocess.run([str(host), *args], capture_output=True, timeout=300).returncode == 0
    sim_names, sim = read_csv(tmp_path / "fmusim.csv")
    host_names, mine = read_csv(tmp_path / "host.csv")
    assert sorted(sim_names) == sorted(host_names) and len(sim) == len(mine) == len(rows)
    for k, (a, b) in enumerate(zip(mine, sim, strict=True)):
        for name, value in zip(sim_names, b, strict=True):
            ours = a[host_names.index(name)]
            ours = ours if "." not in ours and "e" not in ours else f"{float(ours):.16g}"
            assert value == ours, (k, name, value, ours)


@pytest.mark.parametrize("model", MODELS)
def test_fmusim_on_the_references_inputs_passes_them(fmusim, fmi3_fmus, model, tmp_path):
    inputs, ref_csv, opt_file = reference_files(model)
    run = run_fmusim(fmusim, fmi3_fmus[model], inputs, tmp_path / "fmusim.csv")
    assert run.returncode == 0, run.stdout + run.stderr
    names, sim = read_csv(tmp_path / "fmusim.csv")
    ref_names, ref = read_csv(ref_csv)
    opt = read_opt(opt_file)
    y, r = np.array(sim, dtype=float), np.array(ref, dtype=float)
    assert y.shape == r.shape
    for k, name in enumerate(ref_names[1:], start=1):
        col, refcol = y[:, names.index(name)], r[:, k]
        tol = opt["RelTol"] * np.abs(refcol) + opt["AbsTol"] * (refcol.max() - refcol.min())
        assert np.all(np.abs(col - refcol) <= tol), name


def test_fmusim_sets_enumerations_and_shows_the_library_refusal(fmusim, fmi3_fmus, tmp_path):
    inputs = reference_files(MESH)[0]
    run = run_fmusim(fmusim, fmi3_fmus[MESH], inputs, tmp_path / "a.csv", "--start-value",
                     "contact.dissipation", "2", "--start-value", "contact.damping", "300")
    assert run.returncode == 0, run.stdout + run.stderr
    run = run_fmusim(fmusim, fmi3_fmus[MESH], inputs, tmp_path / "b.csv", "--start-value",
                     "contact.dissipation", "7")
    assert run.returncode != 0
    assert ("[Error] exitInitializationMode: parameter 'contact.dissipation' = 7 is not one of "
            "its choices; allowed: one of 0 (none") in run.stdout + run.stderr


def test_fmusim_state_file_defect_refused_not_crashed(fmusim, fmi3_fmus, tmp_path):
    run = run_fmusim(fmusim, fmi3_fmus[MESH], reference_files(MESH)[0], tmp_path / "a.csv",
                     "--final-fmu-state-file", str(tmp_path / "state.bin"))
    assert run.returncode > 0, run  # an error, not a signal
    assert ("[Error] fmi3FreeFMUState: FMUState points to an FMU state, not to the host's "
            "variable that holds one") in run.stdout + run.stderr
