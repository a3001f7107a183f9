"""The in-process twin of an FMU of any face: a unit of the model library
(``drive_rattle.units``, the library every face wraps) driven through the calls a host makes of
the FMU (the C host that makes them of the FMU's binary: tests/faces/fmu_host.c,
tests/faces/hosts.py). Tables are compared as the hexadecimal text of every float: bit for bit,
never with a tolerance (rattle is chaotic). Shared by the face suite, tests/sanitize, tests/fmu
and tests/fmi3."""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from fmpy import read_model_description

from drive_rattle.library import DRIVELINE, MESH
from drive_rattle.units import Unit
from drive_rattle_cosim.regression import read_opt, reference_files

KINDS = {"GearMeshRattle": MESH, "Driveline": DRIVELINE}


def bits(table) -> list[list[str]]:
    return [[x.hex() if isinstance(x, float) else str(x) for x in row] for row in table]


def interface(fmu: Path) -> tuple[str, str, list[str], list[tuple[str, str, int]]]:
    """(model identifier, GUID, input names, [(output name, type, vr)]) of an FMU."""
    md = read_model_description(str(fmu))
    inputs = [v.name for v in md.modelVariables if v.causality == "input"]
    outputs = [(v.name, v.type, v.valueReference) for v in md.modelVariables
               if v.causality == "output"]
    return md.coSimulation.modelIdentifier, md.guid, inputs, outputs


def input_rows(model: str) -> list[list[float]]:
    """The committed regression inputs of ``model``: [time, inputs...] per communication
    point."""
    lines = reference_files(model)[0].read_text(encoding="utf-8").splitlines()
    return [[float(x) for x in line.split(",")] for line in lines[1:]]


def twin_run(model: str, rows: Sequence[Sequence[float]], names: Sequence[str]) -> list[list]:
    """fmu_host.c's call sequence on a unit of the model library: setup at the first time,
    initialization with the first row's inputs, then per row the inputs set and a step to the
    next time; [time, outputs...] at every point (Integer outputs as int)."""
    with Unit(KINDS[model], initialize=False) as unit:
        unit.call("rm_setup", float(rows[0][0]))
        unit.call("rm_enter_initialization")
        unit.set(dict(zip(names, rows[0][1:], strict=True)))
        unit.call("rm_exit_initialization")
        table = [[rows[0][0], *unit.outputs().values()]]
        for row, following in itertools.pairwise(rows):
            unit.set(dict(zip(names, row[1:], strict=True)))
            unit.call("rm_do_step", row[0], following[0] - row[0])
            table.append([following[0], *unit.outputs().values()])
        assert not unit.warnings, unit.warnings
        return table


def assert_passes_references(model: str, table, columns: Sequence[str]) -> None:
    """A host's [time, outputs...] ``table`` (``columns``: its header) against the committed
    references of ``model`` with the regression kit's check (drive_rattle_cosim.regression):
    the same times and, in every column at every point, |y - y_ref| <= RelTol |y_ref| +
    AbsTol (max y_ref - min y_ref)."""
    table = np.array(table, dtype=float)
    _, ref_csv, opt_file = reference_files(model)
    opt = read_opt(opt_file)
    lines = ref_csv.read_text(encoding="utf-8").splitlines()
    names = lines[0].split(",")
    ref = np.array([[float(x) for x in line.split(",")] for line in lines[1:]])
    columns = list(columns)
    assert table.shape == ref.shape and sorted(names) == sorted(columns)
    assert np.allclose(table[:, 0], ref[:, 0], rtol=1e-12, atol=0.0)  # fmpy sums its times
    for k, name in enumerate(names[1:], start=1):
        r, y = ref[:, k], table[:, columns.index(name)]
        tol = opt["RelTol"] * np.abs(r) + opt["AbsTol"] * (r.max() - r.min())
        assert np.all(np.abs(y - r) <= tol), (name, float(np.max(np.abs(y - r) - tol)))
