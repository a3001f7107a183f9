"""Bit for bit on linux64: the native FMUs against the pythonfmu FMUs and the Python core
(the same libm in this process).  Every float is compared with ==/hex, never a tolerance:
rattle is chaotic, and one ulp of difference would grow into another impact sequence.

* the model the C builds from the parameters (geometry, contact-law fit, Hunt-Crossley
  factor: kernel_layout.pack_model's array) and its start state, against the Python core,
  for parameter sets drawn by hypothesis -- invalid ones refused with Python's message;
* the Driveline's engine orders and output shaft (RK4 and its exact branch) against the
  Python core;
* every output of both FMUs on the regression inputs, and the FMU state (its JSON), against
  the pythonfmu FMUs;
* the coupled paper scenario under the harness, with other contact laws, friction forms,
  dissipation, a free start and a measured speed table, against the pythonfmu pair.
"""

from __future__ import annotations

import ctypes
import math
import types
import zipfile

import pytest
from hypothesis import HealthCheck, event, example, given, settings
from hypothesis import strategies as st

from drive_rattle import MeshModel, MeshParameters, WheelStepper
from drive_rattle.driveline import DrivelineModel, DrivelineParameters
from drive_rattle.interface import MODELS
from drive_rattle.kernel_layout import MODEL_SIZE, pack_model
from drive_rattle.parameters import specs
from drive_rattle_cosim.harness import CoSimulation
from drive_rattle_cosim.regression import _read_csv, read_opt, reference_files, simulate_on_inputs

from ..adversarial.raw_fmi import OK, Model, state_payload, unpack

H = 1e-4


def bits(x) -> str:
    return x.hex() if isinstance(x, float) else repr(x)


# ------------------------------------------------------------------ the model array
@pytest.fixture(scope="module")
def mesh_library(native_fmus, tmp_path_factory):
    """The native GearMeshRattle's linux64 binary, loaded here (it needs no Python)."""
    folder = tmp_path_factory.mktemp("native_mesh_library")
    with zipfile.ZipFile(native_fmus["GearMeshRattle"]) as z:
        path = folder / "GearMeshRattle.so"
        path.write_bytes(z.read("binaries/linux64/GearMeshRattle.so"))
    lib = ctypes.CDLL(str(path))
    lib.rattle_native_pack_model.restype = ctypes.c_int
    return lib


#: The unit's parameters in value-reference order (attribute names).
PARAMETERS = [attr for attr, _ in specs(MeshParameters)]
DEFAULTS = {attr: getattr(MeshParameters(), attr) for attr in PARAMETERS}


def native_pack(lib, changes: dict) -> tuple[list[float] | None, str]:
    """The C unit's model array for the defaults with ``changes`` (attribute names), or its
    refusal's message."""
    given = {**DEFAULTS, **changes}
    values = (ctypes.c_double * len(PARAMETERS))(*(float(given[a]) for a in PARAMETERS))
    out = (ctypes.c_double * MODEL_SIZE)()
    err = ctypes.create_string_buffer(2048)
    n = lib.rattle_native_pack_model(values, out, err, len(err))
    return (list(out) if n == MODEL_SIZE else None), err.value.decode()


def python_pack(params: MeshParameters) -> list[float]:
    mesh = MeshModel(params)
    return pack_model(types.SimpleNamespace(params=params, mesh=mesh, geometry=mesh.geometry))


GEOMETRY = {
    "z_pinion": st.integers(8, 60), "z_wheel": st.integers(8, 150),
    "m_n": st.floats(0.5e-3, 8e-3), "alpha_n": st.floats(0.18, 0.6),
    "beta": st.one_of(st.just(0.0), st.floats(0.0, 0.78)), "addendum": st.floats(0.6, 1.4),
    "b": st.floats(2e-3, 0.08), "backlash": st.floats(0.0, 1e-3),
    "crowning": st.floats(1e-6, 1e-3), "hertz_law": st.sampled_from([0, 1]),
    "dissipation": st.sampled_from([0, 1, 2]), "restitution": st.floats(0.05, 1.0),
    "restitution_speed": st.floats(1e-4, 1.0), "damping": st.floats(0.0, 1000.0),
    "E_wheel": st.floats(5e10, 4e11), "nu_pinion": st.floats(0.1, 0.45),
}


@settings(max_examples=150, deadline=None, suppress_health_check=list(HealthCheck))
@given(st.fixed_dictionaries({}, optional=GEOMETRY))
# found by hypothesis: the compiler folded pow(x, 2.0) into x * x, which glibc's pow (Python's
# x ** 2) rounds differently here (s_start, then the whole contact-law fit)
@example(changes={"z_pinion": 12, "z_wheel": 84, "alpha_n": 0.5, "beta": 0.0, "b": 0.0625,
                  "addendum": 1.341866295794147, "m_n": 0.007151094753194949,
                  "crowning": 0.001, "backlash": 0.0})
def test_model_array_bit_for_bit(mesh_library, changes):
    """Geometry, contact law (exact elliptical Hertz fit or equivalent sphere), Hunt-Crossley
    factor, arms and constants: the C array equals kernel_layout.pack_model's, bit for bit;
    a geometry Python refuses is refused with the same message."""
    try:
        params = MeshParameters(**changes)
        reference = python_pack(params)
    except ValueError as err:  # undercut, tip interference, eps_alpha < 1, pair slots, or
        # an exact law that cannot be tabulated
        native, message = native_pack(mesh_library, changes)
        assert native is None and message == str(err)
        event(f"refused: {str(err)[:30]}")
        return
    event(f"built: law {params.hertz_law}, dissipation {params.dissipation}")
    native, message = native_pack(mesh_library, changes)
    assert native is not None, message
    assert [bits(x) for x in native] == [bits(x) for x in reference]


# ------------------------------------------------------------------ start and outputs
@pytest.fixture(scope="module")
def unpacked(native_fmus, tmp_path_factory):
    return {name: Model(unpack(fmu, tmp_path_factory.mktemp(f"eq_{name}")))
            for name, fmu in native_fmus.items()}


def initialized(model: Model, values: dict):
    inst = model.instantiate(b"equivalence")
    assert inst.setup(0.0) == OK and inst.enter() == OK
    assert inst.set_named(values) == OK, inst.log
    return inst, inst.exit()


START = {
    "z_pinion": st.integers(15, 40), "b": st.floats(5e-3, 0.04),
    "backlash": st.floats(1e-5, 3e-4), "hertz_law": st.sampled_from([0, 1]),
    "friction_form": st.sampled_from([0, 1, 2]), "shear_speed": st.sampled_from([0, 1]),
    "init_in_contact": st.booleans(), "phi_start": st.floats(-2e-3, 2e-3),
    "w_start": st.floats(0.0, 60.0), "tau_s": st.floats(0.0, 5e8),
}


@settings(max_examples=80, deadline=None, suppress_health_check=list(HealthCheck))
@given(st.fixed_dictionaries({}, optional=START), st.floats(-3.0, 3.0), st.floats(0.0, 200.0),
       st.floats(-2.0, 2.0))
def test_mesh_start_and_outputs_bit_for_bit(unpacked, changes, phi_p, w_p, tau_load):
    """The static flank equilibrium (or the free start with its check) and every output at
    the start, against WheelStepper.outputs(); a refused start has Python's
    message."""
    model = unpacked["GearMeshRattle"]
    try:
        params = MeshParameters(**changes)
    except ValueError:
        return  # the geometry checks: test_model_array_bit_for_bit
    values = {**params.to_public(), "pinion.phi": phi_p, "pinion.w": w_p,
              "wheel.tau_load": tau_load}
    inst, status = initialized(model, values)
    try:
        python = WheelStepper(params, phi_p, w_p, tau_load)
    except ValueError as err:
        assert status == 3 and inst.messages() == [f"exitInitializationMode: {err}"]
        event("start refused")
        inst.free()
        return
    event(f"started, in contact: {params.init_in_contact}, flank {python.state.flank}")
    assert status == OK, inst.log
    expected = python.outputs()
    for name, value in expected.items():
        assert bits(inst.get_named(name)) == bits(value), name
    inst.free()


@settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck))
@given(st.fixed_dictionaries({
    "k_shaft": st.sampled_from([1e-3, 0.2, 50.0, 1e9]),
    "c_shaft": st.sampled_from([0.0, 0.005, 3.0, 1e6]),
    "J_vehicle": st.sampled_from([1e-6, 0.01, 5.0]),
    "drag_viscous": st.sampled_from([0.0, 0.1, 1e5]),
    "drag": st.floats(-1.0, 1.0), "h_max": st.sampled_from([1e-6, 3e-5, 1e-4, 1e-3]),
    "a_over_step": st.booleans(), "amplitude_4": st.sampled_from([0.0, 500.0]),
    "phase_2": st.floats(-6.0, 6.0)}), st.floats(-1.0, 1.0), st.floats(0.0, 100.0),
    st.sampled_from([1e-4, 3e-4, 2e-3]))
def test_driveline_bit_for_bit(unpacked, changes, phi_w, w_w, h):
    """Engine orders, the output shaft (RK4, or exact where its time scales are far below the
    substep) and the step's outputs against drive_rattle.driveline, over 20 steps."""
    params = DrivelineParameters(**changes)
    model = unpacked["Driveline"]
    inst, status = initialized(model, {**params.to_public(), "wheel.phi": phi_w,
                                       "wheel.w": w_w})
    assert status == OK, inst.log
    python = DrivelineModel(params, 0.0, phi_w, w_w)
    for k in range(20):
        for name, value in python.outputs().items():
            assert bits(inst.get_named(name)) == bits(value), (k, name)
        phi = phi_w + w_w * k * h
        inst.set_named({"wheel.phi": phi})
        status = inst.step(k * h, h)
        try:
            python.step(h, phi, w_w, t=k * h)
        except ValueError as err:
            assert status == 3 and inst.messages(status=3)[-1] == f"doStep: {err}"
            event("step refused")
            break
        assert status == OK, inst.log[-2:]
    inst.free()


# ------------------------------------------------------------------ against pythonfmu
@pytest.mark.parametrize("model", MODELS)
def test_regression_inputs_every_output_bit_for_bit(fmus, native_fmus, model):
    inputs, _, opt = reference_files(model)
    table, options = _read_csv(inputs), read_opt(opt)
    python = simulate_on_inputs(fmus[model], table, options)
    native = simulate_on_inputs(native_fmus[model], table, options)
    assert python.dtype.names == native.dtype.names
    for name in python.dtype.names:
        same = [bits(float(x)) for x in native[name]] == [bits(float(x)) for x in python[name]]
        assert same, name
    if model == "GearMeshRattle":
        assert native["mesh.impacts_coast"][-1] > 0 and native["mesh.impacts_drive"][-1] > 0


@pytest.mark.parametrize("model", MODELS)
def test_fmu_states_are_the_pythonfmu_fmus(fmus, native_fmus, model, tmp_path):
    """The serialized FMU state's content (JSON, format 3) is the pythonfmu FMU's byte for
    byte at every step of the regression inputs, and every variable too; a state restored
    into a fresh instance continues identically."""
    inputs, _, _ = reference_files(model)
    rows = _read_csv(inputs)
    names = [n for n in rows.dtype.names if n != "time"]
    runs = {}
    for flavour, fmu in (("pythonfmu", fmus[model]), ("native", native_fmus[model])):
        m = Model(unpack(fmu, tmp_path / flavour))
        inst, status = initialized(m, {n: float(rows[n][0]) for n in names})
        assert status == OK, inst.log
        trace = []
        for k in range(len(rows) - 1):
            inst.set_named({n: float(rows[n][k]) for n in names})
            t, t_next = float(rows["time"][k]), float(rows["time"][k + 1])
            assert inst.step(t, t_next - t) == OK
            if k % 50 == 0 or k > len(rows) - 5:
                trace.append((inst.snapshot(), state_payload(inst.serialized())))
        blob = inst.serialized()
        other = m.instantiate(b"restored")
        status, state = other.deserialize(blob)
        assert status == OK and other.set_state(state) == OK, other.log
        assert other.snapshot() == inst.snapshot()
        runs[flavour] = trace
        inst.free()
        other.free()
    assert runs["native"] == runs["pythonfmu"]


PAPER = 0.3  # s of the coupled paper scenario: 3000 steps, some 50 impacts
VARIANTS = {
    "defaults": {},
    "sphere law, apparent-area friction on sliding speed, strong order 2": {
        "GearMeshRattle.contact.hertz_law": 1, "GearMeshRattle.friction.form": 1,
        "GearMeshRattle.friction.shear_speed": 1, "Driveline.engine.amplitude[1]": 2000.0},
    "spur gears, damping factor, printed friction": {
        "GearMeshRattle.gear.beta": 0.0, "GearMeshRattle.contact.dissipation": 2,
        "GearMeshRattle.contact.damping": 300.0, "GearMeshRattle.friction.form": 2},
    "free start, no friction, stiff shaft": {
        "GearMeshRattle.init.in_contact": False, "GearMeshRattle.wheel.w_start": 40.0,
        "GearMeshRattle.friction.enabled": False, "Driveline.shaft.k": 50.0,
        "Driveline.pinion.a_over_step": False},
}


def coupled(fmus, params, stop):
    with CoSimulation(fmus["GearMeshRattle"], fmus["Driveline"], params) as sim:
        return sim.run(stop)


@pytest.mark.parametrize("variant", list(VARIANTS))
def test_coupled_paper_scenario_bit_for_bit(fmus, native_fmus, variant):
    params = VARIANTS[variant]
    stop = PAPER if variant == "defaults" else 0.1
    python, native = coupled(fmus, params, stop), coupled(native_fmus, params, stop)
    assert native.time == python.time
    for name in python.columns:
        assert [bits(x) for x in native[name]] == [bits(x) for x in python[name]], name
    impacts = native["GearMeshRattle.mesh.impacts_drive"][-1]
    assert impacts > 0 and math.isfinite(native["GearMeshRattle.mesh.W_peak"][-1])


def test_coupled_with_a_speed_table_bit_for_bit(fmus, native_fmus, tmp_path):
    table = tmp_path / "speed run-up.csv"
    rows = [(k * 0.01, 80.0 + 15.0 * math.sin(40.0 * k * 0.01)) for k in range(11)]
    table.write_text("time [s],speed [rad/s]\n"
                     + "".join(f"{t!r},{w!r}\n" for t, w in rows), encoding="utf-8")
    params = {"Driveline.engine.speed_table": str(table)}
    python, native = coupled(fmus, params, 0.12), coupled(native_fmus, params, 0.12)
    for name in python.columns:
        assert [bits(x) for x in native[name]] == [bits(x) for x in python[name]], name
