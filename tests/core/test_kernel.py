"""The compiled kernel (fmu_src/native/rattle_kernel.c) against the pure-Python stepper: the
same numbers, bit for bit (floats compared by their hex form, so -0.0 != 0.0 and a NaN would
not pass), on every step, and the same refusals with the same messages.

RATTLE_KERNEL_SOURCE=<file.c> compiles that source instead of the shipped one (to check that
these tests catch a changed kernel)."""

import collections
import math
import os
import re
import shutil
from dataclasses import fields, replace

import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from drive_rattle import (
    COAST,
    DRIVE,
    MeshParameters,
    StepResult,
    WheelState,
    WheelStepper,
    interface,
    kernel,
    kernel_layout,
    stepper,
)
from drive_rattle.driveline import DrivelineParameters, EngineOrderKinematics
from drive_rattle.parameters import DEG
from drive_rattle_build import kernel as build_kernel

from .helpers import pinion_with_order

AGGREGATES = tuple(f.name for f in fields(StepResult) if f.name != "events")
W_PINION = 86.92  # rad/s, 830 rpm
H = 1e-4


@pytest.fixture(scope="module")
def lib(tmp_path_factory):
    if shutil.which("gcc") is None:
        pytest.skip("gcc not found on PATH: the compiled kernel cannot be built here")
    source = os.environ.get("RATTLE_KERNEL_SOURCE") or None
    path = build_kernel.compile_kernel(tmp_path_factory.mktemp("kernel") / kernel.LIBRARY_NAME,
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


def pair(params, init, lib, state=None):
    """A Python and a compiled stepper from the same start; ``state`` (a WheelState tuple)
    replaces the start state of both."""
    py, cc = (WheelStepper(params, *init),
              kernel.CompiledWheelStepper(params, *init, library=lib))
    if state is not None:
        for s in (py, cc):
            s.restore(replace(s.snapshot(), state=WheelState.from_tuple(state)))
    return py, cc


def assert_same(py, cc, k, rp=None, rc=None, outputs=False):
    where = f"step {k}"
    assert bits(cc.wheel_angle_speed()) == bits((py.state.phi, py.state.w)), where
    assert bits(cc.state.as_tuple()) == bits(py.state.as_tuple()), where
    assert bits(cc.pinion) == bits(py.pinion), where
    if rp is not None:
        assert bits(aggregates(rc)) == bits(aggregates(rp)), where
        assert rc.events == [] and cc.last_result is rc, where
        assert cc.last_event_count == len(rp.events), where
    if outputs:
        assert bits(cc.outputs()) == bits(py.outputs()), where


class Run:
    """What a lockstep run saw on the Python side: event kinds, contact substeps and the
    output values compared."""

    def __init__(self, py):
        self.py = py
        self.events = collections.Counter()
        self.substeps = 0
        self.outputs = []


def lockstep(params, init, inputs, lib, outputs_every=10, state=None):
    """Step both steppers through ``inputs`` ((h, phi_p, w_p, a_p, tau_load) per step),
    comparing everything after every step (and the outputs every ``outputs_every`` steps)."""
    py, cc = pair(params, init, lib, state)
    assert_same(py, cc, -1, outputs=True)
    run = Run(py)
    for k, args in enumerate(inputs):
        rp = py.step(*args)
        rc = cc.step(*args)
        run.events.update(ev.kind for ev in rp.events)
        run.substeps += rp.contact_substeps
        check = bool(outputs_every) and k % outputs_every == 0
        assert_same(py, cc, k, rp, rc, outputs=check)
        if check:
            run.outputs.append(py.outputs())
    return run


def paper_inputs(n, load=0.15):
    """The paper's engine orders (default driveline) at a 1e-4 s step, constant load."""
    kin = EngineOrderKinematics(DrivelineParameters())
    return (*kin(0.0)[:2], load), [(H, *kin(k * H), load) for k in range(n)]


def fluctuation_inputs(n, load=0.2, amp=2000.0):
    """A strong order-2 speed fluctuation (coast impacts) around 830 rpm."""
    freq = 2 * 830 / 60
    k0 = pinion_with_order(0.0, W_PINION, amp, freq)
    return ((k0[0], k0[1], load),
            [(H, *pinion_with_order(k * H, W_PINION, amp, freq), load) for k in range(n)])


def approaching(params, v, flank=DRIVE, gap=20e-9):
    """Start state: pinion at rest at phi_p = 0, wheel ``gap`` short of ``flank`` approaching
    it at normal speed ``v`` [m/s] (as helpers.approach_stepper)."""
    s = WheelStepper(params, 0.0, 0.0, 0.0)
    phi = s._wheel_angle(flank, 0.0, -gap)
    return WheelState(phi, -flank * v / s.mesh.arm_wheel).as_tuple()


def touching_angle(s, flank, phi_p):
    """A wheel angle at which ``flank`` has penetration exactly 0.0 against ``phi_p``."""
    phi = s._wheel_angle(flank, phi_p, 0.0)
    for _ in range(64):
        pen = s.mesh.penetration(flank, phi_p, phi)
        if pen == 0.0:
            return phi
        # d(pen)/d(phi_w) = -flank arm_w: step the wheel angle by one ulp towards zero
        phi = math.nextafter(phi, (flank if pen > 0.0 else -flank) * math.inf)
    pytest.fail(f"no wheel angle with exactly zero penetration near {phi!r}")


# ------------------------------------------------------------------ the layout
def test_layout_header_is_current_and_the_hash_covers_names_and_order():
    assert build_kernel.header_is_current(), (
        "fmu_src/native/rattle_kernel_layout.h is stale: python build_fmu.py "
        "--update-kernel-header, and commit it")
    # The arrays follow the Python declarations, in order.
    state_names = tuple(f.name for f in fields(WheelState))
    assert state_names == kernel_layout.STATE_FIELDS
    sample = WheelState(*range(len(state_names)))
    assert sample.as_tuple() == tuple(getattr(sample, n) for n in state_names)
    output_names = tuple(s.name for s in interface.MESH_OUTPUTS)
    assert output_names == kernel_layout.OUTPUT_FIELDS
    assert tuple(WheelStepper(MeshParameters()).outputs()) == output_names
    model = kernel_layout.pack_model(WheelStepper(MeshParameters()))
    assert len(model) == kernel_layout.MODEL_SIZE
    # Swapping two names (same count) changes the header and its hash.
    body = kernel_layout._body()
    assert "S_V_IMPACT_DRIVE = 3," in body and "S_V_IMPACT_COAST = 4," in body
    swapped = body.replace("S_V_IMPACT_DRIVE = 3,", "S_V_IMPACT_COAST = 3,", 1).replace(
        "S_V_IMPACT_COAST = 4,", "S_V_IMPACT_DRIVE = 4,", 1)
    assert swapped != body
    compiled_in = kernel_layout.LAYOUT_HASH
    assert kernel_layout.layout_hash(body) == compiled_in
    assert kernel_layout.layout_hash(swapped) != compiled_in


def test_a_library_of_another_layout_is_not_loaded(lib, tmp_path, monkeypatch):
    path = shutil.copy(lib._name, tmp_path / kernel.LIBRARY_NAME)  # not loaded yet
    monkeypatch.setattr(kernel_layout, "LAYOUT_HASH", kernel_layout.LAYOUT_HASH ^ 1)
    assert kernel.load_kernel(path) is None
    monkeypatch.undo()
    assert kernel.load_kernel(path) is not None
    # and a model array of another layout is refused on the call, nothing changed
    cc = kernel.CompiledWheelStepper(MeshParameters(), 0.0, 87.0, 0.1, library=lib)
    before = bits(cc.state.as_tuple())
    cc._model[1] += 1.0  # the layout hash entry
    with pytest.raises(RuntimeError, match="layout mismatch"):
        cc.step(H, 0.0, 87.0, 0.0, 0.1)
    assert bits(cc.state.as_tuple()) == before


def test_a_stale_header_stops_the_build(monkeypatch, tmp_path):
    monkeypatch.setattr(kernel_layout, "render_header", lambda: "/* other */\n")
    with pytest.raises(RuntimeError, match="update-kernel-header"):
        build_kernel.compile_kernel(tmp_path / "x.so")
    assert not (tmp_path / "x.so").exists()


def test_the_kernel_holds_no_message_text():
    """Every refusal's text is written once, in Python (kernel.refusal and the functions the
    Python core raises from): the only string literals of the C source are its includes."""
    code = re.sub(r"/\*.*?\*/", "", build_kernel.SOURCE.read_text(encoding="utf-8"),
                  flags=re.S)
    literals = [line.strip() for line in code.splitlines() if '"' in line]
    assert literals == ['#include "rattle_kernel_layout.h"',
                        '#define EXPORT __attribute__((visibility("default")))']


# ------------------------------------------------------------------ scenarios
def test_paper_scenario_bit_for_bit(lib):
    init, inputs = paper_inputs(3000)
    run = lockstep(MeshParameters(), init, inputs, lib)
    assert run.py.state.impacts_drive > 10  # it rattled
    assert run.events["reversal"] > 5  # pairs' friction reversed at the pitch point
    assert run.events["pair"] > 5  # crowned pairs started or stopped carrying load
    assert run.py.state.rattle_index > 0.0


def test_strong_fluctuation_with_coast_impacts_bit_for_bit(lib):
    init, inputs = fluctuation_inputs(1500)
    # (a rattle time constant other than the default 1 s, where dividing by it is exact)
    run = lockstep(MeshParameters(rattle_time=0.3), init, inputs, lib)
    assert run.py.state.impacts_coast > 0 and run.py.state.impacts_drive > 0
    assert run.events["reversal"] > 0


@pytest.mark.parametrize("form", [0, 1, 2])
@pytest.mark.parametrize("shear_speed", [0, 1])
def test_friction_forms_in_mixed_lubrication_bit_for_bit(lib, form, shear_speed):
    # A smooth surface (sigma 0.1 um): the strong fluctuation runs through boundary, mixed
    # (0 < psi < 1) and full-film lubrication, where the friction forms differ.
    p = MeshParameters(friction_form=form, shear_speed=shear_speed, sigma=1e-7)
    init, inputs = fluctuation_inputs(250)
    run = lockstep(p, init, inputs, lib, outputs_every=1)
    assert run.py.state.impacts_coast > 0
    assert any(0.0 < o["mesh.psi"] < 1.0 for o in run.outputs)  # the mixed regime


@pytest.mark.parametrize("law", [0, 1])
@pytest.mark.parametrize("beta", [0.0, 27.75 * DEG])
def test_hertz_laws_helical_and_spur_bit_for_bit(lib, law, beta):
    # Spur gears (beta 0): contact lines span no roll coordinate, no crown offsets; pairs
    # enter and leave with a jump in stiffness at the breakpoints.
    p = MeshParameters(hertz_law=law, beta=beta)
    init, inputs = fluctuation_inputs(300)
    run = lockstep(p, init, inputs, lib, outputs_every=5)
    assert run.py.state.impacts_drive + run.py.state.impacts_coast > 0


@pytest.mark.parametrize("law", [0, 1])
def test_short_strongly_crowned_face_where_r_y_crosses_r_x(lib, law):
    # A 2 mm face with 90 um of crowning: r_y (6.2 mm) lies inside the range of r_x along the
    # path of contact (4.1-7.9 mm), so the larger radius R switches from r_y to r_x.
    p = MeshParameters(hertz_law=law, b=2e-3, crowning=9e-5)
    g = WheelStepper(p).geometry
    r_x = [g.normal_radii(s)[2] for s in (g.s_start, g.s_end)]
    assert min(r_x) < g.r_y < max(r_x)
    init, inputs = fluctuation_inputs(300)
    run = lockstep(p, init, inputs, lib, outputs_every=5)
    assert run.py.state.impacts_drive + run.py.state.impacts_coast > 0


def test_spur_gears_loaded_rolling_with_reversals(lib):
    p = MeshParameters(beta=0.0, friction_form=2, dissipation=2, damping=5.0)
    run = lockstep(p, (0.0, 30.0, 1.0), [(H, 30.0 * k * H, 30.0, 0.0, 1.0) for k in range(250)],
                   lib, outputs_every=5)
    assert run.events["reversal"] > 0


@pytest.mark.parametrize("dissipation, damping", [(0, 0.0), (1, 0.0), (2, 50.0)])
def test_dissipation_models_bit_for_bit(lib, dissipation, damping):
    p = MeshParameters(dissipation=dissipation, damping=damping)
    init, inputs = fluctuation_inputs(300)
    lockstep(p, init, inputs, lib, outputs_every=5)


@pytest.mark.parametrize("v", [0.4, 2.0])
@pytest.mark.parametrize("flank", [DRIVE, COAST])
def test_extreme_legal_damping_where_the_substeps_are_subdivided(lib, v, flank):
    # contact.damping = 1000 s/m at 0.4-2 m/s: the contact's time scales are far below the
    # 10 us grid, so the substeps are subdivided (issue 10, item 6).
    p = MeshParameters(init_in_contact=False, dissipation=2, damping=1000.0,
                       friction_enabled=flank == DRIVE)
    run = lockstep(p, (0.0, 0.0, 0.0), [(H, 0.0, 0.0, 0.0, 0.0)] * 3, lib, outputs_every=1,
                   state=approaching(p, v, flank))
    assert run.substeps > 3 * 10 * 2  # well beyond the 10 grid substeps per step
    assert run.events["onset"] == 1


def test_substep_cap_refusal_same_message(lib, monkeypatch):
    # A whole 10 ms step on one substep of the grid, into the contact at 2 m/s.
    p = MeshParameters(init_in_contact=False, dissipation=2, damping=1000.0, h_max=1e-2)
    py, cc = pair(p, (0.0, 0.0, 0.0), lib, approaching(p, 2.0))
    before = _snapshot(cc)
    messages = []
    for s in (py, cc):
        with pytest.raises(ValueError, match="too stiff to resolve") as exc:
            s.step(1e-2, 0.0, 0.0, 0.0, 0.0)
        messages.append(str(exc.value))
    assert messages[0] == messages[1]
    assert _snapshot(cc) == before
    # The cap counts the substeps of the whole step (MAX_CONTACT_SUBSTEPS is passed to the
    # kernel when the stepper is built): an impact that needs ~300 of them.
    monkeypatch.setattr(stepper, "MAX_CONTACT_SUBSTEPS", 200)
    p = MeshParameters(init_in_contact=False, dissipation=2, damping=1000.0)
    py, cc = pair(p, (0.0, 0.0, 0.0), lib, approaching(p, 2.0))
    messages = []
    for s in (py, cc):
        with pytest.raises(ValueError, match="more than 200 substeps") as exc:
            s.step(H, 0.0, 0.0, 0.0, 0.0)
        messages.append(str(exc.value))
    assert messages[0] == messages[1]
    assert_same(py, cc, 0)


# ------------------------------------------------------------------ exact touch
@pytest.mark.parametrize("flank", [DRIVE, COAST])
def test_exact_touch_approaching_is_an_onset_at_t0(lib, flank):
    p = MeshParameters(init_in_contact=False)
    s = WheelStepper(p, 0.0, 0.0, 0.0)
    state = WheelState(touching_angle(s, flank, 0.0), -flank * 0.1 / s.mesh.arm_wheel)
    py, cc = pair(p, (0.0, 0.0, 0.0), lib, state.as_tuple())
    rp, rc = py.step(H, 0.0, 0.0, 0.0, 0.0), cc.step(H, 0.0, 0.0, 0.0, 0.0)
    assert rp.events[0].kind == "onset" and rp.events[0].time == 0.0
    assert_same(py, cc, 0, rp, rc, outputs=True)
    for k in range(1, 6):
        assert_same(py, cc, k, py.step(H, 0.0, 0.0, 0.0, 0.0), cc.step(H, 0.0, 0.0, 0.0, 0.0),
                    outputs=True)


@pytest.mark.parametrize("a_p, tau_load", [(500.0, 0.0), (0.0, 0.3)])
@pytest.mark.parametrize("flank", [0, DRIVE])
def test_exact_touch_at_rest_accelerated_into_contact(lib, a_p, tau_load, flank):
    # Wheel and pinion at rest, touching; the pinion's acceleration or the load drives the
    # drive flank into contact: from flight (flank 0) an onset at t = 0 at zero speed, in
    # contact (flank +1) the contact simply continues.
    p = MeshParameters(init_in_contact=False)
    s = WheelStepper(p, 0.0, 0.0, 0.0)
    state = WheelState(touching_angle(s, DRIVE, 0.0), 0.0, flank)
    inputs = [(H, 0.5 * a_p * (k * H) ** 2, a_p * k * H, a_p, tau_load) for k in range(20)]
    py, cc = pair(p, (0.0, 0.0, tau_load), lib, state.as_tuple())
    rp, rc = py.step(*inputs[0]), cc.step(*inputs[0])
    assert_same(py, cc, 0, rp, rc, outputs=True)
    onsets = [e.time for e in rp.events if e.kind == "onset"]
    assert onsets == ([0.0] if flank == 0 else [])
    assert py.state.flank == DRIVE
    for k, args in enumerate(inputs[1:], 1):
        assert_same(py, cc, k, py.step(*args), cc.step(*args), outputs=True)


@pytest.mark.parametrize("v, penetrates", [(1e-4, True), (1e-5, False)])
def test_grazing_contact_from_exact_touch(lib, v, penetrates):
    # Exactly touching, approaching at v [m/s] while the load pulls the wheel back off the
    # drive flank at ~30 m/s^2: the flank is left within the first 10 us substep.  At 1e-4 m/s
    # a sample of the substep penetrates (the release is then located by Brent's method); at
    # 1e-5 m/s the contact is over before the first sample (a grazing contact).
    p = MeshParameters(init_in_contact=False)
    s = WheelStepper(p, 0.0, 0.0, 0.0)
    state = WheelState(touching_angle(s, DRIVE, 0.0), -v / s.mesh.arm_wheel)
    inputs = [(H, 0.0, 0.0, 0.0, -1.0)] * 3
    run = lockstep(p, (0.0, 0.0, -1.0), inputs, lib, outputs_every=1, state=state.as_tuple())
    assert run.events["onset"] == 1 and run.events["release"] == 1
    # the penetrations at the samples of the first substep (free motion: the contact force
    # at these sub-nanometre penetrations is negligible)
    h, k, a = p.h_max, stepper.GRAZING_SAMPLES, s.mesh.arm_wheel * 1.0 / p.J_wheel
    samples = [v * (h * i / k) - 0.5 * a * (h * i / k) ** 2 for i in range(1, k)]
    assert any(x > 0.0 for x in samples) == penetrates


def test_flank_reached_exactly_at_a_communication_point(lib):
    # Free flight towards the drive flank; the next step's pinion angle puts the flank exactly
    # at zero penetration at the step start (the pinion input may jump between steps).
    p = MeshParameters(init_in_contact=False, w_start=-5.0)
    py, cc = pair(p, (0.0, 0.0, 0.0), lib)
    rp, rc = py.step(H, 0.0, 0.0, 0.0, 0.0), cc.step(H, 0.0, 0.0, 0.0, 0.0)
    assert_same(py, cc, 0, rp, rc)
    assert py.state.flank == 0
    # pinion angle with exactly zero drive penetration against the wheel's angle
    m, phi_w = py.mesh, py.state.phi
    phi_p = (m.arm_wheel * phi_w + py.geometry.half_backlash) / m.arm_pinion
    for _ in range(64):
        pen = m.penetration(DRIVE, phi_p, phi_w)
        if pen == 0.0:
            break
        phi_p = math.nextafter(phi_p, -math.inf if pen > 0.0 else math.inf)
    assert m.penetration(DRIVE, phi_p, phi_w) == 0.0
    rp, rc = py.step(H, phi_p, 0.0, 0.0, 0.0), cc.step(H, phi_p, 0.0, 0.0, 0.0)
    assert rp.events[0].kind == "onset" and rp.events[0].time == 0.0
    assert_same(py, cc, 1, rp, rc, outputs=True)


def test_zero_load_equilibrium_start_with_accelerating_pinion(lib):
    # init.in_contact with wheel.tau_load = 0: the wheel starts exactly touching the drive
    # flank (flank 0); an accelerating pinion makes that an onset.
    p = MeshParameters()
    inputs = [(H, 0.5 * 300.0 * (k * H) ** 2, 300.0 * k * H, 300.0, 0.0) for k in range(30)]
    run = lockstep(p, (0.0, 0.0, 0.0), inputs, lib, outputs_every=1)
    assert run.py.state.impacts_drive >= 1


# ------------------------------------------------------------------ state handling
def test_state_changed_between_steps_through_restore(lib):
    init, inputs = paper_inputs(60)
    py, cc = pair(MeshParameters(), init, lib)
    for k, args in enumerate(inputs):
        if k == 20:  # a changed state, set in each stepper
            for s in (py, cc):
                st = s.state
                changed = replace(st, phi=st.phi + 2e-6, w=st.w - 0.5, rattle_index=1e-3)
                s.restore(replace(s.snapshot(), state=changed))
        if k == 40:  # the Python stepper's snapshot set in both
            snapshot = py.snapshot()
            py.restore(snapshot)
            cc.restore(snapshot)
        assert_same(py, cc, k, py.step(*args), cc.step(*args), outputs=True)
    with pytest.raises(AttributeError):  # a state is a value: no change in place
        cc.state.phi = 0.0  # type: ignore[misc]


# ------------------------------------------------------------------ refused steps
def _snapshot(s):
    return bits((s.state.as_tuple(), s.pinion, aggregates(s.last_result)))


@pytest.mark.parametrize("args, match", [
    ((H, math.nan, 87.0, 0.0, 0.1), "phi_p"),
    ((H, 0.0, math.inf, 0.0, 0.1), "w_p"),
    ((H, 0.0, 87.0, -math.inf, 0.1), "a_p"),
    ((H, 0.0, 87.0, 0.0, math.nan), "tau_load"),
    ((H, None, 87.0, 0.0, 0.1), "phi_p"),
    ((0.0, 0.0, 87.0, 0.0, 0.1), "step size"),
    ((-H, 0.0, 87.0, 0.0, 0.1), "step size"),
    ((math.nan, 0.0, 87.0, 0.0, 0.1), "step size"),
    ((math.inf, 0.0, 87.0, 0.0, 0.1), "step size"),
    ((2e-2, 0.0, 87.0, 0.0, 0.1), "h_comm_max"),
    # the pinion jumps 12 mrad (~250 um) into the flank: beyond the validity of the Hertz
    # contact (a 1 us step: the substeps this penetration needs stay few)
    ((1e-6, 87.0 * 5 * H + 0.012, 87.0, 0.0, 0.1), "penetrate"),
    ((H, 0.0, 0.0, 0.0, 1e308), "diverged"),
])
def test_refused_steps_raise_the_same_message_and_leave_the_state(lib, args, match):
    p = MeshParameters(init_in_contact=False, h_comm_max=1e-2)  # below the default 1 s
    py, cc = pair(p, (0.0, 87.0, 0.1), lib)
    for k in range(5):  # some history first
        assert_same(py, cc, k, py.step(H, 87.0 * k * H, 87.0, 0.0, 0.1),
                    cc.step(H, 87.0 * k * H, 87.0, 0.0, 0.1))
    before_py, before_cc = _snapshot(py), _snapshot(cc)
    assert before_py == before_cc
    last_cc = cc.last_result
    with pytest.raises(ValueError, match=match) as exc_py:
        py.step(*args)
    with pytest.raises(ValueError, match=match) as exc_cc:
        cc.step(*args)
    assert str(exc_cc.value) == str(exc_py.value)
    assert _snapshot(py) == before_py
    assert _snapshot(cc) == before_cc and cc.last_result is last_cc
    # and both continue identically
    args = (H, 87.0 * 5 * H, 87.0, 0.0, 0.1)
    assert_same(py, cc, 5, py.step(*args), cc.step(*args), outputs=True)


@pytest.mark.parametrize("phi_offset, w", [(1e-7, -math.inf), (math.inf, 0.0), (1e-7, 1e300)])
def test_a_refusal_inside_a_library_call_is_pythons_own(lib, phi_offset, w):
    """States a step cannot follow (a restored FMU state may hold anything finite or not):
    Python fails inside math.ceil / int() (OverflowError); the kernel reports which call
    failed with its argument, and kernel.refusal makes that call, so the exception and its
    text are Python's own, and nothing changes."""
    p = MeshParameters(init_in_contact=False)
    probe = WheelStepper(p)
    phi = (probe._wheel_angle(DRIVE, 0.0, phi_offset) if math.isfinite(phi_offset)
           else phi_offset)
    state = WheelState(phi, w, DRIVE)
    errors = []
    for s in (WheelStepper.from_state(p, state),
              kernel.CompiledWheelStepper.from_state(p, state, library=lib)):
        before = s.snapshot()
        with pytest.raises(ArithmeticError) as exc:
            s.step(H, 0.0, 0.0, 0.0, 0.0)
        assert bits(s.snapshot().state.as_tuple()) == bits(before.state.as_tuple())
        errors.append((type(exc.value), str(exc.value)))
    assert errors[0] == errors[1]


def test_h_comm_max_parameter_is_honoured(lib):
    p = MeshParameters(h_comm_max=1e-4)
    py, cc = pair(p, (0.0, 87.0, 0.1), lib)
    for s in (py, cc):
        with pytest.raises(ValueError, match="h_comm_max"):
            s.step(1.5e-4, 0.0, 87.0, 0.0, 0.1)
    assert_same(py, cc, 0, py.step(1e-4, 0.0, 87.0, 0.0, 0.1),
                cc.step(1e-4, 0.0, 87.0, 0.0, 0.1))


# ------------------------------------------------------------------ property based
parameters = st.fixed_dictionaries({
    "friction_enabled": st.booleans(),
    "friction_form": st.integers(0, 2),
    "shear_speed": st.integers(0, 1),
    "hertz_law": st.integers(0, 1),
    "dissipation": st.integers(0, 2),
    "restitution": st.floats(0.5, 1.0),  # d up to ~300 s/m at the default 4 mm/s
    "damping": st.one_of(st.just(0.0), st.floats(0.0, 1000.0)),
    "crowning": st.floats(1e-6, 1e-4),
    # (a helix angle below ~1e-150 rad makes geometry divide by an underflowed zero)
    "beta": st.one_of(st.just(0.0), st.floats(0.5 * DEG, 30.0 * DEG)),
    "backlash": st.one_of(st.just(0.0), st.floats(0.0, 2e-4)),
    "h_max": st.floats(2e-6, 5e-5),
    "sigma": st.floats(2e-8, 2e-6),
    "rattle_time": st.floats(1e-3, 10.0),
    "init_in_contact": st.booleans(),
    "w_start": st.floats(-50.0, 50.0),
})
series = st.lists(
    st.tuples(st.floats(-2000.0, 2000.0),  # pinion acceleration [rad/s^2]
              st.floats(-20.0, 20.0),  # pinion speed offset [rad/s]
              st.floats(-1.0, 2.0),  # load torque [N.m]
              st.sampled_from([1e-4, 1e-4, 5e-5, 2.5e-4, 1e-3])),  # step
    min_size=30, max_size=30)


#: Contact substeps allowed in one step of the property-based test.
HYPOTHESIS_SUBSTEP_CAP = 2000


# No shrinking: a bit-for-bit difference shows on the first example that differs, and
# shrinking long chaotic runs takes minutes without making the example clearer.
@settings(max_examples=60, deadline=None, phases=(Phase.explicit, Phase.reuse, Phase.generate),
          suppress_health_check=[HealthCheck.too_slow])
@given(changes=parameters, steps=series, w0=st.floats(0.0, 150.0))
def test_random_parameters_and_inputs_bit_for_bit(lib, changes, steps, w0):
    # A lower cap on the contact substeps of a step bounds the Python stepper's cost (up to
    # 30 s for one step under the default cap) and makes the cap's refusal part of the test.
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(stepper, "MAX_CONTACT_SUBSTEPS", HYPOTHESIS_SUBSTEP_CAP)
        _random_run(lib, changes, steps, w0)


def _random_run(lib, changes, steps, w0):
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
            with pytest.raises(ValueError) as exc_cc:
                cc.step(*args)
            assert str(exc_cc.value) == str(exc)
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
        build_kernel.compile_kernel(tmp_path / "bad.so", source=bad)
    assert not (tmp_path / "bad.so").exists()
    with pytest.raises(RuntimeError, match="compiler"):
        build_kernel.compile_kernel(tmp_path / "x.so", cc=str(tmp_path / "no-such-cc"))
    # new_stepper: the library next to kernel.py when present, else the Python stepper
    p = MeshParameters()
    monkeypatch.setattr(kernel, "default_library_path", lambda: tmp_path / "missing.so")
    assert type(kernel.new_stepper(p, 0.0, 87.0, 0.1)) is WheelStepper
    lib_path = shutil.copy(lib._name, tmp_path / kernel.LIBRARY_NAME)
    monkeypatch.setattr(kernel, "default_library_path", lambda: lib_path)
    assert type(kernel.new_stepper(p, 0.0, 87.0, 0.1)) is kernel.CompiledWheelStepper
    assert type(kernel.new_stepper(p, 0.0, 87.0, 0.1, prefer_compiled=False)) is WheelStepper
