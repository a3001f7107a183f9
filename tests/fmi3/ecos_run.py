"""Vico's ecos (pip ``ecospy``; Debian's ``libtbb12``) running the FMI 3.0 pair, in a process
of its own (ecos can abort its process): the FMUs added as a structure, connected along
``CONNECTIONS``, parameters as one named parameter set, a fixed step; every output of both
units recorded from the start time after initialization and after every step.

    python -m tests.fmi3.ecos_run FMU_DIR STOP STEP PARAMETERS_JSON RESULT_JSON

Writes {"time": [...], "columns": {"<Unit>.<output>": [...]}, "log": "<ecos's stderr>"} with
floats as hexadecimal text."""

from __future__ import annotations

import json
import sys
from pathlib import Path


def main(argv: list[str]) -> int:
    from ecospy import EcosLib, EcosSimulation, EcosSimulationStructure
    from fmpy import read_model_description

    from drive_rattle.interface import CONNECTIONS, MODELS

    folder, stop, step = Path(argv[0]), float(argv[1]), float(argv[2])
    parameters, out = json.loads(argv[3]), Path(argv[4])
    EcosLib.set_log_level("warn")
    structure = EcosSimulationStructure()
    outputs = {}
    for model in MODELS:
        fmu = folder / f"{model}.fmu"
        structure.add_model(model, str(fmu))
        outputs[model] = [(v.name, v.type) for v in read_model_description(str(fmu)).modelVariables
                          if v.causality == "output"]
    for src, output, dst, inp in CONNECTIONS:
        structure.make_real_connection(f"{src}::{output}", f"{dst}::{inp}")
    if parameters:
        structure.add_parameter_set("parameters", {k.replace(".", "::", 1): v
                                                   for k, v in parameters.items()})
    sim = EcosSimulation(structure=structure, step_size=step)
    if not sim.init(parameter_set="parameters" if parameters else None):
        raise RuntimeError(f"ecos: init failed: {EcosLib.get_last_error()}")
    result = {"time": [], "columns": {f"{m}.{n}": [] for m, outs in outputs.items()
                                      for n, _ in outs}}
    time = sim.get_time()
    while True:
        result["time"].append(float(time).hex())
        for model, outs in outputs.items():
            for name, kind in outs:
                get = sim.get_integer if kind == "Int32" else sim.get_real
                value = get(f"{model}::{name}")
                result["columns"][f"{model}.{name}"].append(
                    float(value).hex() if kind == "Float64" else str(int(value)))
        if time >= stop:
            break
        time = sim.step(1)
    sim.terminate()
    sim.free()
    out.write_text(json.dumps(result), encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
