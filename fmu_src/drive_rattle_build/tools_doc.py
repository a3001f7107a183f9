"""The numbers of docs/tools.md, computed: every ``<!-- BEGIN name -->...<!-- END name -->``
block of the document is the output of ``BLOCKS[name]``, written by
``python build_fmu.py --update-docs`` (``update``) and held against a fresh computation by
tests/cosim/test_tools_doc.py (``stale``).  After a change of the default physics, run that
command and review the diff: the step-accuracy table, the held-input run of each FMU alone, the
messages and the rest follow the model library.

The numbers come from the model library's units (``drive_rattle.units``), which compute what
the FMUs compute bit for bit (tests/cosim/test_masters.py holds ``fmpy simulate`` of each FMU
against these very loops), so no FMU needs to be built here.  It is the build's (``--update-docs``
runs it, as it regenerates docs/fmi.md) and reads the studies' tools (``drive_rattle_cosim``:
the step accuracy, the masters' environments, the time grid, the integer codes).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from importlib import metadata

from drive_rattle import (
    DRIVELINE,
    MESH,
    DrivelineParameters,
    DrivelineUnit,
    MeshParameters,
    MeshUnit,
    ModelError,
    Unit,
    input_starts,
)
from drive_rattle.catalog import UNITS
from drive_rattle.interface import DEFAULT_EXPERIMENT, MESH_OUTPUTS, MODELS
from drive_rattle.parameters import RPM, specs
from drive_rattle_cosim import environments, step_accuracy
from drive_rattle_cosim.harness import time_grid
from drive_rattle_cosim.variants import code_list

#: The masters of the project's environment whose versions the document was measured with
#: (distribution names); gemseo-fmu and cofmupy run in environments of their own
#: (``environments.PINNED``).
MASTERS = ("fmpy", "libcosimpy", "ecospy", "fmu-manipulation-toolbox", "pathsim-fmi")


def _g(x: float, digits: int = 3) -> str:
    return f"{x:.{digits}g}"


def default_step() -> str:
    return f"{DEFAULT_EXPERIMENT['stepSize']:g} s"


def fmpy_default_step(stop: float) -> float:
    """fmpy's ``simulate_fmu`` step for a co-simulation FMU: the default experiment's step,
    doubled until there are at most 1000 steps."""
    step = DEFAULT_EXPERIMENT["stepSize"]
    while stop / step > 1000:
        step *= 2
    return step


def _spec(kind: int, name: str):
    """The spec of parameter ``name`` of the unit kind ``kind`` (``MESH``, ``DRIVELINE``)."""
    model = next(m for m in MODELS if UNITS[m].kind == kind)
    return next(s for _, s in specs(UNITS[model].parameters) if s.name == name)


def solver_limits() -> str:
    """The substeps inside a step and the fastest engine order (why the step matters)."""
    dp = DrivelineParameters()
    orders = [(getattr(dp, f"order_{k}"), getattr(dp, f"amplitude_{k}")) for k in range(1, 5)]
    top = max(o for o, a in orders if a > 0)
    hz = top * dp.w_mean / (2 * math.pi)
    return (f"the mesh with RK4 substeps of at most `solver.h_max` "
            f"({_g(_spec(MESH, 'solver.h_max').default)} s) while teeth touch and exact free "
            f"flight between impacts, the Driveline's output shaft with substeps of at most "
            f"{_g(_spec(DRIVELINE, 'solver.h_max').default)} s. The engine orders reach "
            f"{hz:.0f} Hz (order {top:g} at {dp.w_mean / RPM:.0f} rpm)")


def step_table() -> str:
    return "\n" + step_accuracy.table() + "\n"


def _first_refused() -> float:
    """The shortest step of the step-accuracy table that the coupled system refuses."""
    return next(step for step in step_accuracy.STEPS
                if "refused" in step_accuracy.measure(step))


def step_accuracy_setup() -> str:
    phases = ", ".join(f"{p:g}" for p in step_accuracy.PHASES)
    return (f"the default system over {step_accuracy.STOP_TIME:g} s; each cell: the mean over "
            f"{len(step_accuracy.PHASES)} runs whose engine-order-1 phase differs by {phases} "
            "rad, and in brackets their range")


def input_file_command() -> str:
    """fmpy driving the mesh from the regression inputs, to their last time."""
    path = _regression_inputs()
    with open(path, encoding="utf-8") as f:
        lines = f.read().split()
    columns, last = lines[0], float(lines[-1].split(",")[0])
    relative = f"regression/{path.parent.name}/{path.name}"
    return f"""
<!-- run: fmpy-input-file -->
```sh
fmpy simulate dist/native/GearMeshRattle.fmu --input-file {relative} \\
    --output-interval {DEFAULT_EXPERIMENT['stepSize']:g} --stop-time {last:g} \\
    --output-file mesh_driven.csv
```

(`{relative}` holds the regression inputs, {last:g} s; its columns are `{columns}`.)
"""


def first_refused_step() -> str:
    return f"{_first_refused():g} s"


def h_comm_max() -> str:
    return f"{_spec(MESH, 'solver.h_comm_max').default:g} s"


def _mesh_alone() -> MeshUnit:
    s = input_starts(MESH)
    return MeshUnit(MeshParameters(), s["pinion.phi"], s["pinion.w"], s["wheel.tau_load"],
                    s["pinion.a"])


def _refusal(call: Callable[[], object]) -> str:
    try:
        call()
    except ModelError as err:
        return str(err)
    raise AssertionError("the call was not refused")


def _fmpy_longest_run() -> tuple[float, float]:
    """(the longest stop time whose fmpy default step the units accept, the step fmpy takes
    beyond it)."""
    limit = _spec(MESH, "solver.h_comm_max").default
    longest = 1000 * fmpy_default_step(1000 * limit)
    while fmpy_default_step(longest) > limit:
        longest /= 2
    return longest, fmpy_default_step(2 * longest)


def fmpy_steps() -> str:
    """What fmpy's defaults choose, and where fmpy's step is refused."""
    stop = DEFAULT_EXPERIMENT["stopTime"]
    longest, refused = _fmpy_longest_run()
    s = input_starts(MESH)
    mesh = _mesh_alone()
    message = _refusal(lambda: mesh.step(refused, s["pinion.phi"], s["pinion.w"], 0.0,
                                         s["wheel.tau_load"]))
    return (f"{1e3 * fmpy_default_step(stop):g} ms for the default {stop:g} s, "
            f"{1e3 * fmpy_default_step(10.0):g} ms for `--stop-time 10`, "
            f"{fmpy_default_step(longest):g} s up to `--stop-time {longest:g}`; beyond, fmpy's "
            f"{refused:g} s step is refused (`{message}`)")


def held_mesh() -> str:
    """``fmpy simulate dist/GearMeshRattle.fmu``: the mesh alone with held inputs at fmpy's
    default step (the loop of tests/cosim/test_masters.py)."""
    stop = DEFAULT_EXPERIMENT["stopTime"]
    step = fmpy_default_step(stop)
    s = input_starts(MESH)
    mp = MeshParameters()
    mesh = _mesh_alone()
    _, sizes = time_grid(0.0, step, stop, "fmpy")
    phi, w = s["pinion.phi"], s["pinion.w"]
    rows = [mesh.outputs()]
    for h in sizes:
        mesh.step(h, phi, w, 0.0, s["wheel.tau_load"])
        phi += w * h
        rows.append(mesh.outputs())
    ratio = mp.z_pinion / mp.z_wheel
    wheel = [r["wheel.w"] for r in rows]
    loads = [r[f"pair[{k}].W"] for r in rows[1:] for k in range(8) if r[f"pair[{k}].W"] > 0]
    pairs = [r["mesh.n_contact"] for r in rows[1:]]
    torque = sum(r["wheel.tau_mesh"] for r in rows[1:]) / (len(rows) - 1)
    impacts = rows[-1]["mesh.impacts_drive"] + rows[-1]["mesh.impacts_coast"]
    return (f"the pinion turns at its start speed ({w:.1f} rad/s, {w / RPM:.0f} rpm) under the "
            f"start load torque ({s['wheel.tau_load']:g} N·m); the wheel, started in its flank "
            f"equilibrium, follows at the ratio ({ratio * w:.2f} rad/s, within "
            f"{max(abs(x - ratio * w) for x in wheel):.1g} rad/s), the mean mesh torque is "
            f"{torque:.4g} N·m, {min(pairs)}–{max(pairs)} pairs share "
            f"{min(loads):.2g}–{max(loads):.2g} N as they enter and leave the mesh (at the mesh "
            f"frequency, {mp.z_pinion * w / (2 * math.pi):.0f} Hz), and there "
            f"{'is no impact' if impacts == 0 else f'are {impacts} impacts'} "
            f"({stop:g} s at fmpy's {1e3 * step:g} ms step)")


def held_driveline() -> str:
    """``fmpy simulate dist/Driveline.fmu``: the engine's orders, the shaft torque."""
    stop = DEFAULT_EXPERIMENT["stopTime"]
    step = fmpy_default_step(stop)
    dp = DrivelineParameters()
    d = input_starts(DRIVELINE)
    drive = DrivelineUnit(dp, d["wheel.phi"], d["wheel.w"])
    times, sizes = time_grid(0.0, step, stop, "fmpy")
    phi, w = d["wheel.phi"], d["wheel.w"]
    torque = [drive.outputs()["wheel.tau_load"]]
    for t, h in zip(times, sizes, strict=False):
        drive.step(h, phi, w, at=t)
        phi += w * h
        torque.append(drive.outputs()["wheel.tau_load"])
    orders = ", ".join(f"{getattr(dp, f'order_{k}'):g}" for k in range(1, 5)
                       if getattr(dp, f"amplitude_{k}") > 0)
    return (f"the engine's input-shaft kinematics (engine orders {orders}) and a vehicle driven "
            f"at the wheel's start speed ({w:.2f} rad/s): the shaft torque stays at the drag "
            f"({dp.drag:g} N·m, within {max(abs(x - dp.drag) for x in torque):.1g} N·m)")


def outputs_count() -> str:
    return str(sum(len(UNITS[m].outputs) for m in MODELS))


def integer_codes() -> str:
    """Every integer-coded parameter of both units (a spec with ``choices``): its unit, name,
    default and codes with their item names (the specs' ``choice_names``), in the form the
    SSD's bindings and the integer-coded copies give them (``variants.code_list``)."""
    rows = ["| unit | parameter | default | codes |", "|---|---|---|---|"]
    for model in MODELS:
        for _, spec in specs(UNITS[model].parameters):
            if spec.choices:
                rows.append(f"| {model} | `{spec.name}` | {spec.default} | "
                            f"{code_list(spec.choice_names.items())} |")
    return "\n" + "\n".join(rows) + "\n"


def versions() -> str:
    def version(name: str) -> str:
        try:
            return metadata.version(name)
        except metadata.PackageNotFoundError:
            return "not installed"

    listed = ", ".join(f"{name} {version(name)}" for name in MASTERS)
    own = "; ".join(" with ".join(p.replace("==", " ") for p in pins)
                    for pins in environments.PINNED.values())
    return (f"{listed}; {own}, each in an environment of its own, since they pin an older "
            "fmpy (`python -m drive_rattle_cosim.environments`)")


def messages() -> str:
    """The library's messages for the situations a tool user meets, with cause and remedy."""
    s, d = input_starts(MESH), input_starts(DRIVELINE)
    h = DEFAULT_EXPERIMENT["stepSize"]
    rows = []

    refused = _first_refused()
    too_long = "doStep: " + step_accuracy.refusal_reason(
        step_accuracy.measure(refused)["refused"])
    rows.append((too_long, f"a communication step of {refused:g} s is too long for the coupled "
                 "system", f"use {h:g} s"))

    mesh = _mesh_alone()
    drive = DrivelineUnit(DrivelineParameters(), d["wheel.phi"], d["wheel.w"])
    mesh.step(h, 0.0, 0.0, 0.0, 0.0)
    drive.step(h, 0.0, 0.0, at=0.0)
    settled = mesh.warnings[-1]
    o = drive.outputs()
    rows.append((_refusal(lambda: mesh.step(h, o["pinion.phi"], o["pinion.w"], o["pinion.a"],
                                            o["wheel.tau_load"])),
                 "at the second step, after the first step's warning below: a master fed zeros "
                 "to every input at the first step (fmpy's SSP runner, cofmupy)",
                 "the workaround of that master below"))
    rows.append((settled, "(fmi2Warning) the master exchanged nothing during initialization and "
                 "the inputs of the first step are not the start values", "nothing if they are "
                 "the partner's outputs at the start (the unit settled); bind consistent start "
                 "values to silence it"))

    mesh = _mesh_alone()
    step = _fmpy_longest_run()[1]
    rows.append((_refusal(lambda: mesh.step(step, s["pinion.phi"], s["pinion.w"], 0.0,
                                            s["wheel.tau_load"])),
                 "a step above `solver.h_comm_max` (fmpy's default step on a long `--stop-time`)",
                 "a smaller step (`--output-interval` in fmpy)"))
    mesh = _mesh_alone()
    mesh.step(h, s["pinion.phi"], s["pinion.w"], 0.0, s["wheel.tau_load"])
    rows.append((_refusal(lambda: mesh.call("rm_do_step", 5 * h, h)),
                 "the master's time skips or repeats a step", "report it to the master"))
    mesh = _mesh_alone()
    rows.append((_refusal(lambda: mesh.step(h, s["pinion.phi"], math.nan, 0.0,
                                            s["wheel.tau_load"])),
                 "a connection delivers nothing or garbage", "check the connections"))
    unit = Unit(MESH, {"gear.backlash": -1.0}, initialize=False)
    rows.append((_refusal(unit.initialize), "an invalid parameter",
                 "fix it and call exitInitializationMode again"))
    mesh = _mesh_alone()
    rows.append((_refusal(lambda: mesh.set({"gear.backlash": 2e-4})),
                 "a parameter set after initialization (gemseo-fmu sets every input of a "
                 "discipline before every step)", "`masters.gemseo_system(..., parameters=)`"))
    mesh = _mesh_alone()
    integer = next(x.name for x in MESH_OUTPUTS if x.fmi_type == "Integer")
    rows.append((_get_integer_as_real(mesh, integer),
                 "the master reads an Integer output with fmi2GetReal (gemseo-fmu, cofmupy, "
                 "pathsim-fmi)", "*Masters that read every output as a float* (above)"))
    mesh = _mesh_alone()
    rows.append((_refusal(lambda: mesh.call("rm_setup", 0.0)),
                 "setupExperiment on a running FMU (cofmupy's fixed-point initialization)",
                 "leave `fixed_point_init` off"))
    out = ["| message | cause | what to do |", "|---|---|---|"]
    out += [f"| `{m}` | {c} | {w} |" for m, c, w in rows]
    return "\n" + "\n".join(out) + "\n"


def _get_integer_as_real(unit: Unit, name: str) -> str:
    import ctypes

    vrs = (ctypes.c_uint32 * 1)(unit.variables[name].vr)
    out = (ctypes.c_double * 1)()
    return _refusal(lambda: unit.call("rm_get_real", vrs, 1, out))


def native_host_command() -> str:
    """The command block that runs the native GearMeshRattle in tests/faces/fmu_host.c on the
    regression inputs (value references from the model library's tables)."""
    from drive_rattle.units import table

    variables = table(MESH)
    with open(_regression_inputs(), encoding="utf-8") as f:
        columns = f.readline().strip().split(",")[1:]
    inputs = ",".join(str(variables[c].vr) for c in columns)
    outputs = " ".join(f"R:{variables[n].vr}:{n}" for n in ("wheel.w", "mesh.W"))
    return f"""
<!-- run: native-host -->
```sh
work=$(mktemp -d)
unzip -q dist/native/GearMeshRattle.fmu -d "$work/GearMeshRattle"
gcc -std=c99 -O2 -I "$work/GearMeshRattle/sources" -o "$work/fmu_host" tests/faces/fmu_host.c -ldl
guid=$(grep -o 'guid="[^"]*"' "$work/GearMeshRattle/modelDescription.xml" | cut -d'"' -f2)
env -i "$work/fmu_host" "$work/GearMeshRattle/binaries/linux64/GearMeshRattle.so" \\
    "file://$work/GearMeshRattle/resources" "$guid" \\
    regression/GearMeshRattle/GearMeshRattle_in.csv "$work/outputs.csv" \\
    {inputs} {outputs}
```
"""


def _regression_inputs():
    from drive_rattle_cosim.regression import reference_files

    return next(f for f in reference_files(MODELS[0]) if f.name.endswith("_in.csv"))


#: name -> function giving the block's text (a text with no newline stays inline).
BLOCKS: dict[str, Callable[[], str]] = {
    "default step": default_step,
    "solver limits": solver_limits,
    "step accuracy setup": step_accuracy_setup,
    "step accuracy": step_table,
    "input file command": input_file_command,
    "first refused step": first_refused_step,
    "h_comm_max": h_comm_max,
    "fmpy steps": fmpy_steps,
    "held mesh": held_mesh,
    "held driveline": held_driveline,
    "outputs count": outputs_count,
    "integer codes": integer_codes,
    "versions": versions,
    "messages": messages,
    "native host command": native_host_command,
}
_BLOCK = re.compile(r"<!-- BEGIN (?P<name>[^>]+?) -->(?P<body>.*?)<!-- END (?P=name) -->", re.S)


def blocks_in(text: str) -> dict[str, str]:
    return {m["name"]: m["body"] for m in _BLOCK.finditer(text)}


def update(text: str, computed: dict[str, str] | None = None) -> str:
    """``text`` with every block's body replaced by its computed text; KeyError for a block
    name that ``BLOCKS`` lacks, ValueError when a block of ``BLOCKS`` is missing."""
    computed = computed if computed is not None else compute(text)
    missing = sorted(set(BLOCKS) - set(blocks_in(text)))
    if missing:
        raise ValueError(f"docs/tools.md lacks the blocks {', '.join(missing)}")
    return _BLOCK.sub(lambda m: f"<!-- BEGIN {m['name']} -->{computed[m['name']]}"
                                f"<!-- END {m['name']} -->", text)


def compute(text: str) -> dict[str, str]:
    """The computed text of every block in ``text`` (each function run once)."""
    return {name: BLOCKS[name]() for name in dict.fromkeys(blocks_in(text))}


def stale(text: str, skip: tuple[str, ...] = ()) -> list[str]:
    """The names of the blocks of ``text`` (but ``skip``) whose body differs from a fresh
    computation."""
    bodies = {k: v for k, v in blocks_in(text).items() if k not in skip}
    return [name for name, body in bodies.items() if body != BLOCKS[name]()]
