"""The FMI 3.0 FMUs in fmpy (``fmpy.fmi3.FMU3Slave``), driven as the FMI 2.0 FMUs are driven
by the tests and the harness, so that their numbers can be compared bit for bit:

* :func:`run_alone` -- one FMU on its regression inputs, the call sequence of
  ``tests/native/test_native_hosts.run_fmpy`` (and of fmu_host.c): start at the first row's
  time, the first row's inputs set in initialization mode, then per row the inputs set and a
  step to the next row's time;
* :class:`Pair` -- both FMUs coupled as ``drive_rattle_cosim.harness.CoSimulation`` couples
  the FMI 2.0 ones: parameters set before initialization, two rounds of output-to-input
  exchange in initialization mode, then per communication point (the harness's
  ``time_grid``) the outputs recorded, the coupling signals exchanged (Jacobi) and both units
  stepped.
"""

from __future__ import annotations

import itertools
import shutil
from pathlib import Path

from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave

from drive_rattle.interface import CONNECTIONS, DRIVELINE, MESH
from drive_rattle_cosim.harness import Result, time_grid

#: fmpy's name of each FMI 3.0 variable type's get/set methods.
ACCESS = {"Float64": "Float64", "Int32": "Int32", "Enumeration": "Int64",
          "Boolean": "Boolean", "String": "String"}
_STATUS = ["OK", "Warning", "Discard", "Error", "Fatal"]


class Unit3:
    """One FMI 3.0 FMU instance in fmpy, with name-based access and its log."""

    def __init__(self, fmu: Path, name: str, logging_on: bool = True):
        md = read_model_description(str(fmu))
        self.name = name
        self.variables = {v.name: v for v in md.modelVariables}
        self.messages: list[tuple[str, str]] = []
        self._dir = extract(str(fmu))
        self.slave = FMU3Slave(guid=md.guid, unzipDirectory=self._dir,
                               modelIdentifier=md.coSimulation.modelIdentifier,
                               instanceName=name)

        def log(env, status, category, message):
            self.messages.append((_STATUS[status] if 0 <= status < 5 else str(status),
                                  message.decode("utf-8", "replace")))

        self.slave.instantiate(loggingOn=logging_on, logMessage=log)

    def set(self, values: dict) -> None:
        for name, value in values.items():
            v = self.variables[name]
            getattr(self.slave, f"set{ACCESS[v.type]}")([v.valueReference], [value])

    def get(self, names) -> list:
        out = []
        for name in names:
            v = self.variables[name]
            out += getattr(self.slave, f"get{ACCESS[v.type]}")([v.valueReference])
        return out

    def outputs(self) -> list[str]:
        return [n for n, v in self.variables.items() if v.causality == "output"]

    def close(self) -> None:
        self.slave.terminate()
        self.slave.freeInstance()
        shutil.rmtree(self._dir, ignore_errors=True)


def run_alone(fmu: Path, rows) -> list[list]:
    """[time, outputs...] at every row of the regression inputs ``rows`` (time, inputs...)."""
    md = read_model_description(str(fmu))
    inputs = [v.name for v in md.modelVariables if v.causality == "input"]
    unit = Unit3(fmu, "fmpy_fmi3")
    try:
        outputs = unit.outputs()
        s = unit.slave
        s.enterInitializationMode(startTime=rows[0][0])
        unit.set(dict(zip(inputs, rows[0][1:], strict=True)))
        s.exitInitializationMode()
        table = [[rows[0][0], *unit.get(outputs)]]
        for row, following in itertools.pairwise(rows):
            unit.set(dict(zip(inputs, row[1:], strict=True)))
            event, terminate, early, _ = s.doStep(row[0], following[0] - row[0])
            assert not (event or terminate or early)
            table.append([following[0], *unit.get(outputs)])
        assert not unit.messages, unit.messages
        return table
    finally:
        unit.close()


class Pair:
    """The FMI 3.0 GearMeshRattle and Driveline coupled along ``CONNECTIONS``."""

    def __init__(self, fmus: dict, parameters: dict | None = None, start_time: float = 0.0,
                 step: float = 1e-4):
        self.start_time, self.step = start_time, step
        self.units = {MESH: Unit3(fmus[MESH], MESH), DRIVELINE: Unit3(fmus[DRIVELINE],
                                                                      DRIVELINE)}
        try:
            per_unit: dict[str, dict] = {u: {} for u in self.units}
            for qualified, value in (parameters or {}).items():
                unit, _, name = qualified.partition(".")
                per_unit[unit][name] = value
            for name, u in self.units.items():
                u.set(per_unit[name])
                u.slave.enterInitializationMode(startTime=start_time)
            for _ in range(2):  # the harness's INIT_ROUNDS
                self._transfer()
            for u in self.units.values():
                u.slave.exitInitializationMode()
        except BaseException:
            self.close()
            raise

    def _transfer(self) -> None:
        """One exchange along CONNECTIONS, sources in unit order (the harness's plan)."""
        for source in self.units:
            for src, out, dst, inp in CONNECTIONS:
                if src == source:
                    self.units[dst].set({inp: self.units[src].get([out])[0]})

    def run(self, stop_time: float, grid: str = "nanoseconds") -> Result:
        """Every output of both units at every communication point, the first one first."""
        names = {u: unit.outputs() for u, unit in self.units.items()}
        result = Result(columns={f"{u}.{n}": [] for u, ns in names.items() for n in ns})
        points, sizes = time_grid(self.start_time, self.step, stop_time, grid)
        for k, t in enumerate(points):
            result.time.append(t)
            for u, unit in self.units.items():
                for n, value in zip(names[u], unit.get(names[u]), strict=True):
                    result.columns[f"{u}.{n}"].append(value)
            if k == len(points) - 1:
                break
            values = {(dst, inp): self.units[src].get([out])[0]
                      for src, out, dst, inp in CONNECTIONS}
            for (dst, inp), value in values.items():
                self.units[dst].set({inp: value})
            for unit in self.units.values():
                event, terminate, early, _ = unit.slave.doStep(t, sizes[k])
                assert not (event or terminate or early)
        return result

    def messages(self) -> list:
        return [m for u in self.units.values() for m in u.messages]

    def close(self) -> None:
        for u in self.units.values():
            u.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
