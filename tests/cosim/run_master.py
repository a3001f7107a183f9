"""Run the system in one master, in this process, and print the result as JSON on the last line.

    python run_master.py <master> '<json arguments>'

Each master runs in its own process (tests/cosim/test_masters.py): libcosim and fmpy in one
process can abort at exit, and a master's crash must not take the test session with it.
"""

import json
import sys
import traceback
from pathlib import Path

from drive_rattle_cosim import masters, variants
from drive_rattle_cosim.ssp import run_libcosim


def run(kind: str, args: dict) -> dict:
    outputs = args.get("outputs")
    if args.get("integer_codes"):  # libcosim and ecos ignore Enumeration variables
        target = Path(args["dir"]) / f"integer_codes_{Path(args['ssp']).name}"
        args = {**args, "ssp": str(variants.integer_codes(Path(args["ssp"]), target))}
    if kind == "libcosim":
        result = run_libcosim(Path(args["ssp"]), args["stop"], outputs or masters.COUPLING)
    elif kind == "fmpy.ssp":
        result = masters.run_fmpy_ssp(Path(args["ssp"]), args["stop"], args["step"],
                                      args["workaround"], args.get("bindings", True), outputs)
    elif kind == "container":
        build = masters.build_container if args.get("bindings", True) \
            else masters.build_container_cli
        container = build(Path(args["ssp"]), Path(args["dir"]))
        result = masters.run_container(container, args["stop"], args["step"], log=print,
                                       outputs=outputs)
    elif kind == "ecos":
        result = masters.run_ecos(Path(args["ssp"]), args["stop"], args["step"], outputs,
                                  args.get("parameter_set", masters.PARAMETER_SET))
    elif kind == "gemseo":
        result = masters.run_gemseo(Path(args["mesh"]), Path(args["driveline"]), args["stop"],
                                    args["step"], args.get("parameters"))
    elif kind == "cofmupy-real-outputs":  # only that workaround
        with masters.cofmupy_real_outputs():
            return run("cofmupy", args)
    elif kind == "cofmupy":
        result = masters.run_cofmupy(Path(args["mesh"]), Path(args["driveline"]), args["stop"],
                                     args["step"], args.get("parameters"),
                                     args.get("workarounds", True),
                                     args.get("fixed_point", False))
    elif kind == "pathsim":
        copies = Path(args["dir"]) if args.get("real_outputs", True) else None
        result = masters.run_pathsim(Path(args["mesh"]), Path(args["driveline"]), args["stop"],
                                     args["step"], args.get("parameters"), copies)
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
