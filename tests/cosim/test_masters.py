"""The default system (dist/DriveRattle.ssp, 0.5 s) in other FMI 2.0 masters, against the harness.

Every master here is Jacobi at a fixed step, like the harness, and places its communication
points with its own arithmetic; the harness run on the same points (``harness.time_grid``) is
the reference, and the comparison is bit for bit: the same computation gives the same numbers,
and rattle is chaotic, so any other difference (a first step fed other inputs, a step size
off by one ulp) grows to whole rad/s within the 0.5 s (docs/tools.md has the measured spread).
Each master runs in its own process (run_master.py).  Workarounds of the masters' own defects
are in drive_rattle_cosim.masters.
"""

import math
import zipfile

import pytest
from fmpy import read_model_description

from drive_rattle import DRIVELINE, MESH, DrivelineUnit, MeshUnit, Unit, input_starts
from drive_rattle.interface import CONNECTIONS
from drive_rattle.interface import DRIVELINE as DRIVELINE_NAME
from drive_rattle.interface import MESH as MESH_NAME
from drive_rattle.parameters import DrivelineParameters, MeshParameters, specs
from drive_rattle.units import coupled_start_inputs
from drive_rattle_build import write_system
from drive_rattle_cosim.harness import CoSimulation, CoSimulationError, steps_between, time_grid
from drive_rattle_cosim.masters import COUPLING, MASTER_GRIDS
from drive_rattle_cosim.ssp import (
    PARAMETER_SET,
    SSD_NAME,
    consistent_input_starts,
    validate_ssd,
)

from .master_process import finish, run_master, start_master

STOP, STEP = 0.5, 1e-4
@pytest.fixture(scope="module")
def system_ssp(fmus):
    """dist/DriveRattle.ssp as `python build_fmu.py` writes it, next to this session's FMUs."""
    return write_system(list(fmus.values()), fmus["GearMeshRattle"].parent)


@pytest.fixture(scope="module")
def gemseo_run(fmus):
    """gemseo-fmu, the slowest master (about 35 s with its import), on the second core while
    the other tests run."""
    process = start_master("gemseo", mesh=str(fmus["GearMeshRattle"]),
                           driveline=str(fmus["Driveline"]), stop=STOP, step=STEP)
    yield process
    if process.poll() is None:
        process.kill()
        process.communicate()


_REFERENCES: dict = {}


def harness(fmus, grid: str) -> dict:
    """The harness on a master's grid: ``{"time": [...], "columns": {...}}`` from t = 0."""
    if grid not in _REFERENCES:
        with CoSimulation(fmus["GearMeshRattle"], fmus["Driveline"], {}, step=STEP) as sim:
            r = sim.run(STOP, COUPLING, grid=grid)
        _REFERENCES[grid] = {"time": r.time, "columns": r.columns}
    return _REFERENCES[grid]


def assert_identical(result: dict, reference: dict, first: int) -> None:
    """The master's points are the reference's from index ``first``; every coupling signal
    equal bit for bit (the first differing point is named)."""
    assert "error" not in result, result["error"]
    n = len(result["time"])
    assert n >= int(STOP / STEP) - 1
    assert result["time"] == reference["time"][first:first + n]
    for name in COUPLING:
        got, want = result["columns"][name], reference["columns"][name][first:first + n]
        diff = next((k for k, (a, b) in enumerate(zip(got, want, strict=True)) if a != b), None)
        assert diff is None, (f"{name} differs from t = {result['time'][diff]} s: "
                              f"{got[diff]!r} != {want[diff]!r}")


# ------------------------------------------------------------------ the shipped system
def test_input_start_values_are_what_the_partner_outputs_at_start(fmus):
    """In the built FMUs, every input starts at its partner's output at t = 0 in the harness
    (which exchanges during initialization), computed from the core's defaults."""
    starts = {}
    for unit, path in fmus.items():
        for v in read_model_description(str(path)).modelVariables:
            if v.causality == "input":
                starts[f"{unit}.{v.name}"] = float(v.start)
    mesh_inputs, driveline_inputs = coupled_start_inputs()
    assert starts == {**{f"GearMeshRattle.{k}": v for k, v in mesh_inputs.items()},
                      **{f"Driveline.{k}": v for k, v in driveline_inputs.items()}}
    at_start = harness(fmus, "nanoseconds")["columns"]
    for src, out, dst, inp in CONNECTIONS:
        assert at_start[f"{src}.{out}"][0] == starts[f"{dst}.{inp}"], (src, out)


def test_shipped_ssp_binds_every_parameter_and_consistent_input_starts(system_ssp, tmp_path):
    assert system_ssp.name == "DriveRattle.ssp"
    with zipfile.ZipFile(system_ssp) as z:
        assert set(z.namelist()) == {SSD_NAME, "resources/GearMeshRattle.fmu",
                                     "resources/Driveline.fmu"}
        z.extract(SSD_NAME, tmp_path)
    validate_ssd(tmp_path / SSD_NAME)
    from fmpy.ssp.ssd import read_ssd

    ssd = read_ssd(str(system_ssp), validate=True)
    assert [c.name for c in ssd.system.elements] == ["Driveline", "GearMeshRattle"]
    assert len(ssd.system.connections) == 6
    text = (tmp_path / SSD_NAME).read_text()
    # one parameter set per component (parameters and input starts), of one name
    assert text.count(f'<ssv:ParameterSet version="1.0" name="{PARAMETER_SET}">') == 2
    # every parameter (the specs hold the two input-handling ones of each unit), every input
    n_parameters = len(list(specs(MeshParameters))) + len(list(specs(DrivelineParameters)))
    assert text.count("<ssv:Parameter ") == n_parameters + 6
    for qualified, value in consistent_input_starts().items():
        assert f'<ssv:Parameter name="{qualified.split(".", 1)[1]}"><ssv:Real value="{value!r}"' \
            in text


# ------------------------------------------------------------------ masters
@pytest.mark.slow
def test_libcosim_runs_the_shipped_system(fmus, system_ssp):
    """libcosim (native C++, OSP): exchanges during initialization, integer-nanosecond grid;
    records from the first point after the start."""
    result, printed = run_master("libcosim", ssp=str(system_ssp), stop=STOP)
    assert MASTER_GRIDS["libcosim"] == "nanoseconds"
    assert_identical(result, harness(fmus, "nanoseconds"), first=1)
    assert "[warning]" not in printed, printed  # it loads the SSP's integer codes


def test_ecos_runs_the_shipped_system(fmus, system_ssp):
    """ecos (Vico, native C++): exchanges during initialization, accumulated time; records
    from the start.  Its parameter set is named (masters.PARAMETER_SET); here the SSP binds
    the defaults, so the run is the default one either way."""
    result, printed = run_master("ecos", ssp=str(system_ssp), stop=STOP, step=STEP)
    assert_identical(result, harness(fmus, MASTER_GRIDS["ecos"]), first=0)
    assert "[warning]" not in printed, printed


@pytest.mark.slow
def test_fmpy_ssp_runner_with_its_first_step_worked_around(fmus, system_ssp):
    """fmpy.ssp feeds 0 to every input at the first step; with the workaround (the first step
    keeps the start values) it computes the harness's run on its accumulated time."""
    result, _ = run_master("fmpy.ssp", ssp=str(system_ssp), stop=STOP, step=STEP,
                           workaround=True)
    assert_identical(result, harness(fmus, MASTER_GRIDS["fmpy.ssp"]), first=1)


def test_fmpy_ssp_runner_without_the_workaround_fails_loudly(system_ssp):
    """Without it: the units settle against the zeros of the first step (and say so), then the
    next step drives the teeth into each other and is refused with the reason."""
    result, printed = run_master("fmpy.ssp", ssp=str(system_ssp), stop=0.01, step=STEP,
                                 workaround=False)
    assert "fmi2DoStep failed" in result["error"]
    assert "pinion.w = 0 rad/s" in printed and "init.settle_first_step" in printed
    assert "the flanks would penetrate" in printed


def test_fmucontainer_container_in_fmpy(fmus, system_ssp, tmp_path):
    """fmu-manipulation-toolbox's container built from the shipped SSP, run in fmpy: it
    initializes the Driveline first (first in the SSD) on zero links, so the Driveline settles
    its shaft at the first step (fmi2Warning) and the run is the harness's from t = 0."""
    result, printed = run_master("container", ssp=str(system_ssp), dir=str(tmp_path),
                                 stop=STOP, step=STEP)
    assert_identical(result, harness(fmus, MASTER_GRIDS["container"]), first=0)
    assert "Driveline.fmu: doStep at the first step" in printed


@pytest.mark.slow  # gemseo in its own environment: about 15 s
def test_gemseo_fmu_time_stepping_system(fmus, gemseo_run):
    """gemseo-fmu (inputs and outputs limited to the Real coupling signals): no exchange during
    initialization, the start values serve the first step."""
    result, _ = finish(gemseo_run)
    assert_identical(result, harness(fmus, MASTER_GRIDS["gemseo"]), first=1)


@pytest.mark.slow
def test_cofmupy_with_its_workarounds(fmus):
    """cofmupy (in an environment of its own: it pins an old fmpy): Jacobi on accumulated
    time, no exchange during initialization; with only the Real outputs read and every
    coupling input in "initialization" it computes the harness's run."""
    result, _ = run_master("cofmupy", mesh=str(fmus["GearMeshRattle"]),
                           driveline=str(fmus["Driveline"]), stop=STOP, step=STEP)
    assert_identical(result, harness(fmus, MASTER_GRIDS["cofmupy"]), first=1)


@pytest.mark.parametrize("variant, message", [
    ({"workarounds": False}, "getReal: no Real variable with value reference"),
    ({"workarounds": False, "outputs": "real"}, "the flanks would penetrate"),
    ({"fixed_point": True}, "setupExperiment is not allowed in mode 'stepping'"),
])
@pytest.mark.slow
def test_cofmupy_without_them_fails_with_the_units_reason(fmus, variant, message):
    """Its three defects for these FMUs, as docs/tools.md describes them: Integer outputs
    read as Real; zeros written to every input before initialization (then the units settle
    against the zeros and the second step drives the teeth into each other); the fixed-point
    initialization's fmi2SetupExperiment on running units."""
    args = {k: v for k, v in variant.items() if k != "outputs"}
    kind = "cofmupy-real-outputs" if variant.get("outputs") else "cofmupy"
    result, printed = run_master(kind, mesh=str(fmus["GearMeshRattle"]),
                                 driveline=str(fmus["Driveline"]), stop=0.01, step=STEP, **args)
    assert "error" in result
    assert message in printed


# ------------------------------------------------------------------ pathsim-fmi
#: Parameters set through pathsim-fmi's start values, an integer code among them.
PATHSIM_PARAMETERS = {"GearMeshRattle.gear.backlash": 2e-4,
                      "GearMeshRattle.contact.dissipation": 0, "Driveline.vehicle.drag": 0.12}


def gauss_seidel(parameters: dict, steps: int, step: float) -> dict:
    """``{"<Unit>.<output>": [...]}``: the coupling signals after each of ``steps`` steps of the
    model library's units stepped one after the other at ``t_k = k step`` (pathsim's schedule,
    ``t_start + k t_period``), the mesh from the Driveline's outputs at ``t_k``, the Driveline
    from the mesh's at ``t_k + step``: what a Gauss-Seidel master computes, mesh first.  Each
    unit is initialized alone on its inputs' start values, as a master that exchanges nothing
    during initialization leaves it."""
    units = {}
    for name, kind in ((MESH_NAME, MESH), (DRIVELINE_NAME, DRIVELINE)):
        own = {k.partition(".")[2]: v for k, v in parameters.items()
               if k.partition(".")[0] == name}
        units[name] = Unit(kind, own, inputs=input_starts(kind))
    outputs = {name: unit.outputs() for name, unit in units.items()}
    columns = {name: [] for name in [*COUPLING, f"{MESH_NAME}.mesh.impacts_drive"]}
    for k in range(steps):
        for name, unit in units.items():
            unit.advance(step, {inp: outputs[src][out] for src, out, dst, inp in CONNECTIONS
                                if dst == name}, at=k * step)
            outputs[name] = unit.outputs()
        for qualified, values in columns.items():
            owner, _, output = qualified.partition(".")
            values.append(outputs[owner][output])
    return columns


@pytest.mark.parametrize("face", ["native_fmus", "fmi3_fmus"])
@pytest.mark.slow
def test_pathsim_fmi_runs_the_real_outputs_copies(face, request, tmp_path):
    """pathsim-fmi (reads every output as a float) on the ``real-outputs`` copies of the native
    FMI 2.0 and of the FMI 3.0 FMUs, with parameters and an integer code set as its start
    values: the library's units stepped in its (Gauss-Seidel) order, bit for bit, with impacts,
    and not the default run."""
    fmus = request.getfixturevalue(face)
    result, _ = run_master("pathsim", mesh=str(fmus[MESH_NAME]),
                           driveline=str(fmus[DRIVELINE_NAME]), stop=0.1, step=STEP,
                           parameters=PATHSIM_PARAMETERS, dir=str(tmp_path))
    assert "error" not in result, result["error"]
    steps = len(result["time"])
    assert steps == 1001  # the points 0 .. 0.1 s, each with its step
    reference = gauss_seidel(PATHSIM_PARAMETERS, steps, STEP)
    for name in COUPLING:
        got, want = result["columns"][name], reference[name]
        diff = next((k for k, (a, b) in enumerate(zip(got, want, strict=True)) if a != b), None)
        assert diff is None, f"{name} differs at step {diff}: {got[diff]!r} != {want[diff]!r}"
    assert reference[f"{MESH_NAME}.mesh.impacts_drive"][-1] >= 3
    default = gauss_seidel({}, steps, STEP)
    assert result["columns"][f"{MESH_NAME}.wheel.w"] != default[f"{MESH_NAME}.wheel.w"]


def test_pathsim_fmi_cannot_construct_a_unit_with_integer_outputs(native_fmus):
    """Why the copies: on the FMUs as built, pathsim-fmi reads the mesh's counters with
    fmi2GetReal when it constructs the block, and stops."""
    result, printed = run_master("pathsim", mesh=str(native_fmus[MESH_NAME]),
                                 driveline=str(native_fmus[DRIVELINE_NAME]), stop=0.01,
                                 step=STEP, real_outputs=False)
    assert "fmi2GetReal failed with status 3" in result["error"]
    assert "getReal: no Real variable with value reference" in printed


# ------------------------------------------------------------------ one FMU alone
def fmpy_default_step(stop: float) -> float:
    """fmpy's simulate_fmu: the default experiment's step, doubled to at most 1000 steps."""
    step = 1e-4
    while stop / step > 1000:
        step *= 2
    return step


@pytest.mark.slow
def test_mesh_alone_under_fmpy_defaults_is_loaded_drive_at_a_constant_pinion_speed(fmus, tmp_path):
    """`fmpy simulate GearMeshRattle.fmu --stop-time 10`: fmpy takes a 12.8 ms step and sets no
    input; the pinion runs at its held start speed and the run is that of the core stepped
    with a constant-speed pinion, bit for bit."""
    stop = 10.0
    result, _ = run_master("alone", fmu=str(fmus["GearMeshRattle"]), stop=stop)
    assert "error" not in result, result["error"]
    step = fmpy_default_step(stop)
    assert result["step"] == step == 0.0128
    starts = input_starts(MESH)
    tau = starts["wheel.tau_load"]
    core = MeshUnit(MeshParameters(), starts["pinion.phi"], starts["pinion.w"], tau)
    times = result["time"]  # fmpy's points, and its steps between them
    assert times == pytest.approx(time_grid(0.0, step, stop, "fmpy")[0], rel=1e-12)
    sizes = steps_between(times)
    columns = result["columns"]
    phi, w = starts["pinion.phi"], starts["pinion.w"]
    for k in range(len(times)):
        if k:  # the held pinion runs on at its start speed, set explicitly here
            core.step(sizes[k - 1], phi, w, 0.0, tau)
            phi += w * sizes[k - 1]
        for name, value in core.outputs().items():
            assert columns[name][k] == value, (name, times[k])
    # Loaded drive at a constant pinion speed: the wheel follows the pinion on average,
    # rippled by the load passing between the crowned pairs at the mesh frequency.  With the
    # teeth's compliance in series the light start load (2 N on the tooth normal) no longer
    # holds the flanks together through that ripple: they part and meet again about once per
    # mesh cycle on the drive flank, never on the coast flank (measured: 2788 impacts in
    # 10 s, 2767 mesh cycles; speed ripple 3.9e-4 peak to peak, where rigid teeth stayed in
    # contact with 1.7e-4).
    w_wheel = columns["wheel.w"]
    assert max(w_wheel) - min(w_wheel) < 1e-3 * w_wheel[0]
    assert sum(w_wheel) / len(w_wheel) == pytest.approx(w_wheel[0], rel=2e-5)
    mesh_cycles = stop * MeshParameters().z_pinion * starts["pinion.w"] / (2 * math.pi)
    assert columns["mesh.impacts_coast"][-1] == 0
    assert columns["mesh.impacts_drive"][-1] == pytest.approx(mesh_cycles, rel=0.02)


def test_driveline_alone_under_fmpy_defaults_drives_the_vehicle_steadily(fmus):
    stop = 10.0
    result, _ = run_master("alone", fmu=str(fmus["Driveline"]), stop=stop)
    assert "error" not in result, result["error"]
    step = result["step"]
    starts = input_starts(DRIVELINE)
    phi_w, w_w = starts["wheel.phi"], starts["wheel.w"]
    core = DrivelineUnit(DrivelineParameters(), phi_w, w_w)
    times = result["time"]  # fmpy's points, and its steps between them
    assert times == pytest.approx(time_grid(0.0, step, stop, "fmpy")[0], rel=1e-12)
    sizes = steps_between(times)
    for k, t in enumerate(times):
        if k:
            # fmpy's points are k * step, not the sum of the steps: the engine's firing
            # sees the point passed
            core.step(sizes[k - 1], phi_w, w_w, at=times[k - 1])
            phi_w += w_w * sizes[k - 1]  # the held wheel runs on at constant speed
        for name, value in core.outputs().items():
            assert result["columns"][name][k] == value, (name, t)
    # steady: the shaft torque stays at the drag (taken literally, the held wheel angle would
    # swing it by tens of N.m, see tests/model/test_unit.py)
    tau = result["columns"]["wheel.tau_load"]
    assert max(tau) - min(tau) < 1e-6 * DrivelineParameters().drag


def test_a_step_the_coupled_system_cannot_take_names_the_step_to_use(fmus):
    with CoSimulation(fmus["GearMeshRattle"], fmus["Driveline"], {}, step=1e-2) as sim, \
            pytest.raises(CoSimulationError,
                          match=r"Reduce the communication step to at most 0\.0001 s"):
        sim.run(STOP)
