"""The compiled kernel (fmu_src/native/rattle_kernel.c) against the pure-Python stepper: the
same numbers, bit for bit (floats compared by their hex form, so -0.0 != 0.0 and a NaN would
not pass), on every step.

RATTLE_KERNEL_SOURCE=<file.c> compiles that source instead of the shipped one (to check that
these tests catch a changed kernel)."""

import math
import os
import shutil
import time

import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from drive_rattle import MeshParameters, WheelStepper, interface, kernel
from drive_rattle.driveline import DrivelineParameters, EngineOrderKinematics
from drive_rattle.parameters import DEG

from .helpers import pinion_with_order

AGGREGATES = ("tau_wheel_mean", "tau_pinion_mean", "W_peak", "delta_peak", "onsets_drive",
              "onsets_coast", "rhs_evaluations")
W_PINION = 86.92  # rad/s, 830 rpm


@pytest.fixture(scope="module")
def lib(tmp_path_factory):
    if shutil.which("gcc") is None:
        pytest.skip("gcc not found on PATH: the compiled kernel cannot be built here")
    source = os.environ.get("RATTLE_KERNEL_SOURCE") or None
    path = kernel.compile_kernel(tmp_path_factory.mktemp("kernel") / kernel.LIBRARY_NAME,
                                 source=source)
    loaded = kernel.load_kernel(path)
    assert loaded is not None
    return loaded


def bits(x):
    """Exact, type-aware form of a value: floats by their hex representation."""
    if isinstance(x, bool):
        return ("b", x)
    if isinstance(x, float):
        return ("f", x.hex())
    if isinstance(x, int):
        return ("i", x)
    if isinstance(x, dict):
        return tuple((k, bits(v)) for k, v in x.items())
    if isinstance(x, (tuple, list)):
        return tuple(bits(v) for v in x)
    raise TypeError(type(x))


def aggregates(r):
    return tuple(getattr(r, name) for name in AGGREGATES)


def pair(params, init, lib):
    return (WheelStepper(params, *init),
            kernel.CompiledWheelStepper(params, *init, library=lib))


def assert_same(py, cc, k, rp=None, rc=None, outputs=False):
    where = f"step {k}"
    assert bits(cc.wheel_angle_speed()) == bits((py.state.phi, py.state.w)), where
    assert bits(cc.state.as_tuple()) == bits(py.state.as_tuple()), where
    assert bits(cc.pinion) == bits(py.pinion), where
    if rp is not None:
        assert bits(aggregates(rc)) == bits(aggregates(rp)), where
        assert rc.events == [] and cc.last is rc, where
        assert cc.last_event_count == len(rp.events), where
    if outputs:
        assert bits(cc.outputs()) == bits(interface.mesh_outputs(py)), where


def lockstep(params, init, inputs, lib, outputs_every=10):
    """Step both steppers through ``inputs`` ((h, phi_p, w_p, a_p, tau_load) per step),
    comparing everything after every step."""
    py, cc = pair(params, init, lib)
    assert_same(py, cc, -1, outputs=True)
    for k, args in enumerate(inputs):
        rp = py.step(*args)
        rc = cc.step(*args)
        assert_same(py, cc, k, rp, rc, outputs=outputs_every and k % outputs_every == 0)
    return py, cc


def paper_inputs(n=3000, H=1e-4, load=0.17):
    kin = EngineOrderKinematics(DrivelineParameters())
    return (*kin(0.0)[:2], load), [(H, *kin(k * H), load) for k in range(n)]


# ------------------------------------------------------------------ (a), (b), (c)
def test_paper_scenario_bit_for_bit(lib):
    init, inputs = paper_inputs()
    py, _ = lockstep(MeshParameters(), init, inputs, lib)
    assert py.state.impacts_drive > 10  # it rattled


def test_strong_fluctuation_with_coast_impacts_bit_for_bit(lib):
    load, H, freq = 0.2, 1e-4, 2 * 830 / 60
    k0 = pinion_with_order(0.0, W_PINION, 2000.0, freq)
    inputs = [(H, *pinion_with_order(k * H, W_PINION, 2000.0, freq), load)
              for k in range(1500)]
    py, _ = lockstep(MeshParameters(), (k0[0], k0[1], load), inputs, lib)
    assert py.state.impacts_coast > 0 and py.state.impacts_drive > 0


@pytest.mark.parametrize("form", [0, 1, 2])
@pytest.mark.parametrize("shear_speed", [0, 1])
def test_friction_forms_in_mixed_lubrication_bit_for_bit(lib, form, shear_speed):
    # A smooth surface (sigma 0.1 um): the strong fluctuation runs through boundary, mixed
    # (0 < psi < 1) and full-film lubrication, where the friction forms differ.
    p = MeshParameters(friction_form=form, shear_speed=shear_speed, sigma=1e-7)
    load, H, freq = 0.2, 1e-4, 2 * 830 / 60
    k0 = pinion_with_order(0.0, W_PINION, 2000.0, freq)
    inputs = [(H, *pinion_with_order(k * H, W_PINION, 2000.0, freq), load)
              for k in range(800)]
    py, _ = lockstep(p, (k0[0], k0[1], load), inputs, lib, outputs_every=1)
    assert py.state.impacts_coast > 0


@pytest.mark.parametrize("form", [1, 2])
@pytest.mark.parametrize("backlash", [0.0, 0.5e-6])
@pytest.mark.parametrize("load", [0.0, 0.05])
def test_spur_friction_forms_damping_free_bouncing_wheel(lib, form, backlash, load):
    p = MeshParameters(friction_form=form, shear_speed=1, damping=50.0,
                       length_weighting=False, beta=0.0, backlash=backlash,
                       init_in_contact=False, phi_start=0.0, w_start=0.4)
    assert p.beta == 0.0  # spur: contact lines span no roll coordinate
    py, _ = lockstep(p, (0.0, 0.0, 0.0), [(1e-4, 0.0, 0.0, 0.0, load)] * 400, lib,
                     outputs_every=1)
    n = py.state.impacts_drive + py.state.impacts_coast
    assert n > (10 if form == 2 else 0)  # form 1's friction on the apparent area sticks


def test_spur_gears_with_rotating_pinion_cross_stiffness_jumps(lib):
    # length_weighting false: pairs enter and leave with a jump in stiffness (breakpoints).
    p = MeshParameters(beta=0.0, length_weighting=False, friction_form=2, damping=5.0)
    H = 1e-4
    inputs = [(H, 30.0 * k * H, 30.0, 0.0, 1.0) for k in range(400)]
    lockstep(p, (0.0, 30.0, 1.0), inputs, lib)


def test_state_changed_in_place_and_assigned(lib):
    init, inputs = paper_inputs(n=60)
    py, cc = pair(MeshParameters(), init, lib)
    for k, args in enumerate(inputs):
        if k == 20:
            for s in (py.state, cc.state):
                s.phi += 2e-6
                s.w -= 0.5
        if k == 40:
            py.state = py.state.from_tuple(py.state.as_tuple())
            cc.state = py.state.from_tuple(py.state.as_tuple())
        assert_same(py, cc, k, py.step(*args), cc.step(*args), outputs=True)


def neumaier_sum(values):
    """sum() of floats as CPython >= 3.12 computes it (Neumaier's compensated sum)."""
    total = comp = 0.0
    for x in values:
        t = total + x
        comp += (total - t) + x if abs(total) >= abs(x) else (x - t) + total
        total = t
    return total + comp if comp and math.isfinite(comp) else total


def test_kernel_reproduces_the_compensated_float_sum_of_python_3_12(lib):
    # MeshModel.stiffness_sum uses sum(); the kernel follows the running Python's algorithm
    # (here forced to 3.12's, with the Python side patched to match).
    load, H, freq = 0.2, 1e-4, 2 * 830 / 60
    k0 = pinion_with_order(0.0, W_PINION, 2000.0, freq)
    py, cc = pair(MeshParameters(), (k0[0], k0[1], load), lib)
    mesh, g = py.mesh, py.geometry
    mesh.stiffness_sum = lambda flank, phi_p: neumaier_sum(
        mesh._pair_stiffness(s, frac)[2] for _, s, frac in g.pairs(flank, phi_p))
    cc._model[kernel.MODEL_FIELDS.index("sum_mode")] = 1.0
    for k in range(600):
        args = (H, *pinion_with_order(k * H, W_PINION, 2000.0, freq), load)
        assert_same(py, cc, k, py.step(*args), cc.step(*args))


# ------------------------------------------------------------------ (d) refused steps
def _snapshot(s):
    return bits((s.state.as_tuple(), s.pinion, aggregates(s.last)))


@pytest.mark.parametrize("args, match", [
    ((1e-4, math.nan, 87.0, 0.0, 0.1), "phi_p"),
    ((1e-4, 0.0, math.inf, 0.0, 0.1), "w_p"),
    ((1e-4, 0.0, 87.0, -math.inf, 0.1), "a_p"),
    ((1e-4, 0.0, 87.0, 0.0, math.nan), "tau_load"),
    ((1e-4, None, 87.0, 0.0, 0.1), "phi_p"),
    ((0.0, 0.0, 87.0, 0.0, 0.1), "step size"),
    ((-1e-4, 0.0, 87.0, 0.0, 0.1), "step size"),
    ((math.nan, 0.0, 87.0, 0.0, 0.1), "step size"),
    ((math.inf, 0.0, 87.0, 0.0, 0.1), "step size"),
    ((2e-2, 0.0, 87.0, 0.0, 0.1), "h_comm_max"),
    ((1e-2, 0.0, 0.0, 0.0, -1e5), "penetrate"),  # beyond the validity of the Hertz contact
    ((1e-4, 0.0, 0.0, 0.0, 1e308), "diverged"),
])
def test_refused_steps_raise_and_leave_the_state(lib, args, match):
    p = MeshParameters(init_in_contact=False, h_comm_max=1e-2)  # below the default 1 s
    H = 1e-4
    py, cc = pair(p, (0.0, 87.0, 0.1), lib)
    for k in range(5):  # some history first
        assert_same(py, cc, k, py.step(H, 87.0 * k * H, 87.0, 0.0, 0.1),
                    cc.step(H, 87.0 * k * H, 87.0, 0.0, 0.1))
    before_py, before_cc = _snapshot(py), _snapshot(cc)
    assert before_py == before_cc
    last_cc = cc.last
    with pytest.raises(ValueError, match=match):
        py.step(*args)
    with pytest.raises(ValueError, match=match):
        cc.step(*args)
    assert _snapshot(py) == before_py
    assert _snapshot(cc) == before_cc and cc.last is last_cc
    # and both continue identically
    args = (H, 87.0 * 5 * H, 87.0, 0.0, 0.1)
    assert_same(py, cc, 5, py.step(*args), cc.step(*args), outputs=True)


def test_h_comm_max_parameter_is_honoured(lib):
    p = MeshParameters(h_comm_max=1e-4)
    py, cc = pair(p, (0.0, 87.0, 0.1), lib)
    for s in (py, cc):
        with pytest.raises(ValueError, match="h_comm_max"):
            s.step(1.5e-4, 0.0, 87.0, 0.0, 0.1)
    assert_same(py, cc, 0, py.step(1e-4, 0.0, 87.0, 0.0, 0.1),
                cc.step(1e-4, 0.0, 87.0, 0.0, 0.1))


# ------------------------------------------------------------------ (e) property based
parameters = st.fixed_dictionaries({
    "friction_enabled": st.booleans(),
    "friction_form": st.integers(0, 2),
    "shear_speed": st.integers(0, 1),
    "damping": st.one_of(st.just(0.0), st.floats(0.0, 100.0)),
    "length_weighting": st.booleans(),
    "beta": st.one_of(st.just(0.0), st.floats(0.0, 30.0 * DEG)),
    "backlash": st.one_of(st.just(0.0), st.floats(0.0, 2e-4)),
    "h_max": st.floats(2e-6, 5e-5),
    "sigma": st.floats(2e-8, 2e-6),
    "init_in_contact": st.booleans(),
    "w_start": st.floats(-50.0, 50.0),
})
series = st.lists(
    st.tuples(st.floats(-2000.0, 2000.0),  # pinion acceleration [rad/s^2]
              st.floats(-20.0, 20.0),  # pinion speed offset [rad/s]
              st.floats(-1.0, 2.0),  # load torque [N.m]
              st.sampled_from([1e-4, 1e-4, 5e-5, 2.5e-4, 1e-3])),  # step
    min_size=50, max_size=50)


# No shrinking: a bit-for-bit difference shows on the first example that differs, and
# shrinking long chaotic runs takes minutes without making the example clearer.
@settings(max_examples=40, deadline=None, phases=(Phase.explicit, Phase.reuse, Phase.generate),
          suppress_health_check=[HealthCheck.too_slow])
@given(changes=parameters, steps=series, w0=st.floats(0.0, 150.0))
def test_random_parameters_and_inputs_bit_for_bit(lib, changes, steps, w0):
    try:
        p = MeshParameters(**changes)
        py, cc = pair(p, (0.0, w0, steps[0][2]), lib)
    except ValueError:
        return  # refused parameter set or start state (the Python constructor decides)
    phi = 0.0
    for k, (a, dw, load, h) in enumerate(steps):
        w = w0 + dw
        args = (h, phi, w, a, load)
        try:
            rp = py.step(*args)
        except ValueError as exc:
            before = _snapshot(cc)
            with pytest.raises(ValueError):
                cc.step(*args)
            assert _snapshot(cc) == before
            assert bits(cc.state.as_tuple()) == bits(py.state.as_tuple()), str(exc)
            return
        assert_same(py, cc, k, rp, cc.step(*args), outputs=True)
        phi += h * w  # the next step's pinion: consistent in angle, jumps in speed


# ------------------------------------------------------------------ loading, fallback
def test_load_kernel_absent_and_compile_errors(tmp_path, lib, monkeypatch):
    assert kernel.load_kernel(tmp_path / "missing.so") is None
    (tmp_path / "junk.so").write_text("not a library")
    assert kernel.load_kernel(tmp_path / "junk.so") is None
    bad = tmp_path / "bad.c"
    bad.write_text("int f(void) { return syntax error; }\n")
    with pytest.raises(RuntimeError, match=r"bad\.c"):
        kernel.compile_kernel(tmp_path / "bad.so", source=bad)
    assert not (tmp_path / "bad.so").exists()
    with pytest.raises(RuntimeError, match="compiler"):
        kernel.compile_kernel(tmp_path / "x.so", cc=str(tmp_path / "no-such-cc"))
    # new_stepper: the library next to kernel.py when present, else the Python stepper
    p = MeshParameters()
    monkeypatch.setattr(kernel, "default_library_path", lambda: tmp_path / "missing.so")
    assert type(kernel.new_stepper(p, 0.0, 87.0, 0.1)) is WheelStepper
    lib_path = kernel.compile_kernel(tmp_path / kernel.LIBRARY_NAME)
    monkeypatch.setattr(kernel, "default_library_path", lambda: lib_path)
    assert type(kernel.new_stepper(p, 0.0, 87.0, 0.1)) is kernel.CompiledWheelStepper
    assert type(kernel.new_stepper(p, 0.0, 87.0, 0.1, prefer_compiled=False)) is WheelStepper


# ------------------------------------------------------------------ speed (printed only)
def test_speed_ratio_paper_scenario(lib, capsys):
    init, inputs = paper_inputs()
    p = MeshParameters()

    def run(stepper, outputs):
        step = stepper.step
        out = (stepper.outputs if isinstance(stepper, kernel.CompiledWheelStepper)
               else lambda: interface.mesh_outputs(stepper))
        t0 = time.perf_counter()
        if outputs:
            for args in inputs:
                step(*args)
                out()
        else:
            for args in inputs:
                step(*args)
        return (time.perf_counter() - t0) / len(inputs) * 1e6, stepper

    lines = []
    for outputs in (False, True):
        t_py, py = min((run(WheelStepper(p, *init), outputs) for _ in range(2)),
                       key=lambda r: r[0])
        t_c, cc = min((run(kernel.CompiledWheelStepper(p, *init, library=lib), outputs)
                       for _ in range(5)), key=lambda r: r[0])
        assert bits(cc.state.as_tuple()) == bits(py.state.as_tuple())
        label = "step()+outputs()" if outputs else "step()"
        lines.append(f"{label}: python {t_py:.1f} us/step, compiled {t_c:.2f} us/step, "
                     f"ratio {t_py / t_c:.1f}")
    with capsys.disabled():
        print("\n[kernel speed, paper scenario, 3000 steps of 0.1 ms] " + "; ".join(lines))
