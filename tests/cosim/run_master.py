"""Run the system in one master, in this process, and print the result as JSON on the last line.

    python run_master.py <master> '<json arguments>'

Each master runs in its own process (tests/cosim/test_masters.py): libcosim and fmpy in one
process can abort at exit, and a master's crash must not take the test session with it.
"""

import json
import sys
import traceback
from pathlib import Path

from drive_rattle_cosim import masters
from drive_rattle_cosim.ssp import run_libcosim


def run(kind: str, args: dict) -> dict:
    if kind == "libcosim":
        result = run_libcosim(Path(args["ssp"]), args["stop"], masters.COUPLING)
    elif kind == "fmpy.ssp":
        result = masters.run_fmpy_ssp(Path(args["ssp"]), args["stop"], args["step"],
                                      args["workaround"])
    elif kind == "container":
        container = masters.build_container(Path(args["ssp"]), Path(args["dir"]))
        result = masters.run_container(container, args["stop"], args["step"], log=print)
    elif kind == "gemseo":
        result = masters.run_gemseo(Path(args["mesh"]), Path(args["driveline"]), args["stop"],
                                    args["step"])
    elif kind == "alone":
        result, step = masters.run_alone(Path(args["fmu"]), args["stop"])
        return {"time": result.time, "columns": result.columns, "step": step}
    else:
        raise ValueError(f"unknown master {kind!r}")
    return {"time": result.time, "columns": result.columns}


def main(argv) -> int:
    try:
        out = run(argv[1], json.loads(argv[2]))
    except Exception as err:
        traceback.print_exc()
        out = {"error": f"{type(err).__name__}: {err}"}
    sys.stdout.flush()
    print("\n" + json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
