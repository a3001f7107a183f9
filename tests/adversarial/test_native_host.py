"""A native host: tests/faces/fmu_host.c (its FMI 2.0 adapter), compiled here with gcc, loads
the built pythonfmu GearMeshRattle (libpython preloaded, FMU_HOST_ALLOW_PYTHON set) with dlopen
as system-simulation tools do, runs the paper scenario for 0.1 s with kinematic inputs and must
match the fmpy run of the same inputs bit for bit (docs/native_host.md)."""

from __future__ import annotations

import itertools
import os
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest
from fmpy import read_model_description

from drive_rattle.parameters import DrivelineParameters
from drive_rattle_build.shim import fmi2_headers
from drive_rattle_cosim.harness import Unit
from drive_rattle_cosim.system import communication_points

from ..fmu.closed_forms import engine_orders

HOST_SOURCE = Path(__file__).resolve().parents[1] / "faces" / "fmu_host.c"
STOP, STEP = 0.1, 1e-4
INPUTS = ("pinion.phi", "pinion.w", "pinion.a", "wheel.tau_load")
OUTPUTS = {  # recorded output -> FMI type
    "wheel.phi": "Real", "wheel.w": "Real", "wheel.tau_mesh": "Real",
    "pinion.tau_mesh": "Real", "mesh.W": "Real", "mesh.W_peak": "Real",
    "mesh.delta_peak": "Real", "mesh.v_impact": "Real", "mesh.impacts_drive": "Integer",
}
GCC_FLAGS = ["-std=c99", "-O2", "-Wall", "-Wextra", "-pedantic", "-Werror"]
# Non-ASCII and a space in the unpack folder: the resource URI is percent-encoded, as tools
# pass it, and the host runs under LANG=C.UTF-8 (docs/fmi.md, "Running the FMUs").
UNPACK_DIR = "GearMeshRattle unpacked ä"


def libpython() -> Path | None:
    """The shared libpython of the running interpreter, None for a static build."""
    libdir, soname = sysconfig.get_config_var("LIBDIR"), sysconfig.get_config_var("INSTSONAME")
    if not libdir or not soname:
        return None
    path = Path(os.path.join(libdir, soname))
    return path if path.is_file() and ".so" in path.name else None


BINDIR = Path(sys.executable).parent
# Marks, not fixture skips: they are evaluated before the session fixture builds the FMUs.
pytestmark = [
    pytest.mark.skipif(shutil.which("gcc") is None,
                       reason="gcc is not installed: the native host cannot be compiled"),
    pytest.mark.skipif(libpython() is None,
                       reason=f"no shared libpython for {sys.executable} (static build?): a "
                       "native host cannot load a pythonfmu FMU with it"),
    pytest.mark.skipif(not (BINDIR / "python3").exists(),
                       reason=f"{BINDIR} has no python3: the FMU's embedded interpreter would "
                       "take its prefix from another Python on PATH"),
]


def scenario_inputs() -> list[tuple[float, ...]]:
    """(t_k, pinion.phi, pinion.w, pinion.a, wheel.tau_load) on the integer-ns grid: the
    paper scenario's engine-order kinematics (default DrivelineParameters) and its constant
    drag.  The default amplitudes give dozens of drive-flank impacts in 0.1 s (asserted below),
    so no larger order amplitude is needed."""
    p = DrivelineParameters()
    kinematics = engine_orders(p)
    points = communication_points(0.0, STEP, STOP)
    assert points == [(k * 100_000) / 1e9 for k in range(len(points))]
    return [(t, *kinematics(t), p.drag) for t in points]


def write_inputs(path: Path, rows) -> None:
    with path.open("w", encoding="ascii", newline="") as f:
        f.write(",".join(("time", *INPUTS)) + "\n")
        for row in rows:
            f.write(",".join(repr(float(x)) for x in row) + "\n")


def run_fmpy(fmu: Path, rows) -> list[list]:
    """The same call sequence as fmu_host.c, through fmpy in this process."""
    unit = Unit(fmu, "fmpy_reference")
    try:
        s = unit.slave
        real = [unit.var(n).vr for n, kind in OUTPUTS.items() if kind == "Real"]
        ints = [unit.var(n).vr for n, kind in OUTPUTS.items() if kind == "Integer"]

        def record(t: float) -> list:
            reals = iter(unit.call("getReal", s.getReal, real))
            integers = iter(unit.call("getInteger", s.getInteger, ints))
            return [t] + [next(reals) if kind == "Real" else next(integers)
                          for kind in OUTPUTS.values()]

        unit.call("setupExperiment", s.setupExperiment, None, rows[0][0])
        unit.call("enterInitializationMode", s.enterInitializationMode)
        unit.set(dict(zip(INPUTS, rows[0][1:], strict=True)))
        unit.call("exitInitializationMode", s.exitInitializationMode)
        table = [record(rows[0][0])]
        for row, following in itertools.pairwise(rows):
            t = row[0]
            unit.set(dict(zip(INPUTS, row[1:], strict=True)))
            unit.call(f"doStep at t = {t!r}", s.doStep, t, following[0] - t)
            table.append(record(following[0]))
        assert not unit.messages, unit.messages
        return table
    finally:
        unit.close()


def read_host_table(path: Path) -> list[list]:
    lines = path.read_text(encoding="utf-8").splitlines()
    assert lines[0] == ",".join(("time", *OUTPUTS))
    table = []
    for line in lines[1:]:
        fields = line.split(",")
        assert len(fields) == 1 + len(OUTPUTS), line
        table.append([float(fields[0])] + [float(x) if kind == "Real" else int(x)
                                           for x, kind in zip(fields[1:], OUTPUTS.values(),
                                                              strict=True)])
    return table


def bits(table) -> list[list[str]]:
    """Exact, comparable form: float.hex tells -0.0 from 0.0 and compares NaN to itself."""
    return [[x.hex() if isinstance(x, float) else str(x) for x in row] for row in table]


@pytest.fixture(scope="module")
def host(tmp_path_factory) -> Path:
    exe = tmp_path_factory.mktemp("fmu_host") / "fmu_host"
    cc = subprocess.run([shutil.which("gcc"), *GCC_FLAGS, "-I", str(fmi2_headers()), "-o",
                         str(exe), str(HOST_SOURCE), "-ldl"],
                        capture_output=True, text=True, timeout=120)
    assert cc.returncode == 0, f"gcc failed:\n{cc.stderr}"
    return exe


@pytest.fixture(scope="module")
def native_env() -> dict:
    # What a system-simulation tool's process has: no PYTHONPATH/PYTHONHOME, nothing inherited.
    return {"PATH": f"{BINDIR}:/usr/bin:/bin", "LD_PRELOAD": str(libpython()),
            "LANG": "C.UTF-8", "FMU_HOST_ALLOW_PYTHON": "1"}


@pytest.fixture(scope="module")
def runs(host, native_env, fmus, tmp_path_factory):
    fmu = fmus["GearMeshRattle"]
    tmp = tmp_path_factory.mktemp("native_run")
    unpacked = tmp / UNPACK_DIR
    with zipfile.ZipFile(fmu) as z:
        z.extractall(unpacked)
    md = read_model_description(str(fmu))
    variables = {v.name: v for v in md.modelVariables}
    for name in INPUTS:
        assert variables[name].causality == "input" and variables[name].type == "Real"
    for name, kind in OUTPUTS.items():
        assert variables[name].causality == "output" and variables[name].type == kind, name
    identifier = md.coSimulation.modelIdentifier

    rows = scenario_inputs()
    inputs_csv, outputs_csv = tmp / "inputs.csv", tmp / "outputs.csv"
    write_inputs(inputs_csv, rows)
    command = [
        str(host),
        str(unpacked / "binaries" / "linux64" / f"{identifier}.so"),
        (unpacked / "resources").as_uri(),
        md.guid,
        str(inputs_csv),
        str(outputs_csv),
        ",".join(str(variables[n].valueReference) for n in INPUTS),
        *(f"{kind[0]}:{variables[n].valueReference}:{n}" for n, kind in OUTPUTS.items()),
    ]
    run = subprocess.run(command, env=native_env, capture_output=True, text=True, timeout=600)
    host_table = read_host_table(outputs_csv) if outputs_csv.is_file() else None
    return rows, run, host_table, run_fmpy(fmu, rows)


def test_native_host_runs_cleanly(runs):
    rows, run, host_table, _ = runs
    assert run.returncode == 0, f"native host failed (rc {run.returncode}):\n{run.stderr}"
    logged = [line for line in run.stderr.splitlines() if line.startswith("[")]
    assert not logged, "the FMU logged messages:\n" + "\n".join(logged)
    assert host_table is not None and len(host_table) == len(rows) == 1001
    assert [r[0] for r in host_table] == [r[0] for r in rows]


def test_native_host_matches_fmpy_bit_for_bit(runs):
    _, run, host_table, reference = runs
    assert run.returncode == 0, run.stderr
    assert len(host_table) == len(reference)
    for k, (mine, theirs) in enumerate(zip(bits(host_table), bits(reference), strict=True)):
        assert mine == theirs, (
            f"row {k} (t = {host_table[k][0]!r} s) differs:\n"
            + "\n".join(f"  {name}: native {a} != fmpy {b}"
                        for name, a, b in zip(("time", *OUTPUTS), mine, theirs, strict=True)
                        if a != b))


def test_horizon_contains_impacts(runs):
    _, _, host_table, reference = runs
    column = 1 + list(OUTPUTS).index("mesh.impacts_drive")
    assert host_table[-1][column] > 0
    assert reference[-1][column] == host_table[-1][column]


# ------------------------------------------------------------------ a wrong python3 on PATH
def wrong_python(folder: Path, with_stdlib: bool) -> Path:
    """A prefix with a ``python3`` that does not belong to the preloaded libpython: with
    ``with_stdlib`` its lib/pythonX.Y holds the real standard library but an empty
    lib-dynload (the interpreter starts; the slave's imports of extension modules fail), else
    only the landmark os.py (the interpreter cannot find "encodings" and cannot start)."""
    version = f"python{sys.version_info.major}.{sys.version_info.minor}"
    lib = folder / "lib" / version
    (lib / "lib-dynload").mkdir(parents=True)
    (folder / "bin").mkdir()
    python3 = folder / "bin" / "python3"
    python3.write_text("#!/bin/sh\nexit 1\n")
    python3.chmod(0o755)
    if with_stdlib:
        stdlib = Path(sysconfig.get_paths()["stdlib"])
        for entry in stdlib.iterdir():
            if entry.name != "lib-dynload":
                (lib / entry.name).symlink_to(entry)
    else:
        (lib / "os.py").write_text("")
    return folder / "bin"


@pytest.mark.parametrize("case, reasons", [
    ("cannot import the slave", ["Fatal py exception", "ModuleNotFoundError",
                                 "pythonfmu could not create the slave",
                                 "python3 first on PATH", "must belong to the loaded"]),
    ("cannot start", ["the embedded Python interpreter", "cannot start",
                      "encoding", "python3 first on PATH", "put the python3 of the loaded"]),
])
def test_native_host_never_fails_silently(case, reasons, host, native_env, fmus,
                                          tmp_path):
    """With a wrong python3 first on PATH the embedded interpreter cannot
    start or cannot import the slave; with logging off the host's logger still gets the
    reason, fmi2Instantiate returns NULL, and the host process ends normally."""
    stdlib = Path(sysconfig.get_paths()["stdlib"])
    if not (stdlib / "encodings").is_dir() or not (stdlib / "lib-dynload").is_dir():
        pytest.skip(f"unexpected standard-library layout at {stdlib}")
    fmu = fmus["GearMeshRattle"]
    unpacked = tmp_path / "fmu"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(unpacked)
    md = read_model_description(str(fmu))
    variables = {v.name: v for v in md.modelVariables}
    inputs_csv = tmp_path / "inputs.csv"
    write_inputs(inputs_csv, scenario_inputs()[:3])
    bindir = wrong_python(tmp_path / "wrong-python", with_stdlib=case != "cannot start")
    env = {**native_env, "PATH": f"{bindir}:/usr/bin:/bin"}
    command = [
        str(host), str(unpacked / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"),
        (unpacked / "resources").as_uri(), md.guid, str(inputs_csv), str(tmp_path / "out.csv"),
        ",".join(str(variables[n].valueReference) for n in INPUTS),
        f"R:{variables['wheel.w'].valueReference}:wheel.w",
    ]
    run = subprocess.run(command, env=env, capture_output=True, text=True, timeout=300)
    assert run.returncode == 1, (run.returncode, run.stderr[-3000:])
    assert "fmu_host: fmi2Instantiate returned NULL" in run.stderr
    # What the host's logger printed ("[Fatal] <category>: <message>", messages may span lines)
    logged = run.stderr.split("fmu_host: fmi2Instantiate returned NULL")[0]
    logged = logged[logged.index("[Fatal]"):]
    for reason in reasons:
        assert reason in logged, (reason, run.stderr[-3000:])
    assert str(bindir / "python3") in logged
