"""Shared set-ups for core tests."""

import math
from dataclasses import replace

from drive_rattle import DRIVE, MeshParameters, WheelStepper


def set_state(stepper, **changes):
    """Change fields of ``stepper``'s wheel state (through ``restore``: a state is a value)."""
    stepper.restore(replace(stepper.snapshot(), state=replace(stepper.state, **changes)))


def approach_stepper(v, flank=DRIVE, gap=20e-9, **changes):
    """Pinion at rest at phi_p = 0, wheel ``gap`` short of ``flank`` and approaching it at
    normal speed ``v`` [m/s]; no load, friction off unless given."""
    changes.setdefault("friction_enabled", False)
    p = MeshParameters(init_in_contact=False, **changes)
    st = WheelStepper(p, 0.0, 0.0, 0.0)
    m = st.mesh
    phi_w = st._wheel_angle(flank, 0.0, -gap)
    w_w = -flank * v / m.arm_wheel
    set_state(st, phi=phi_w, w=w_w)
    return st


def pinion_with_order(t, w0, amp, freq):
    """Pinion kinematics with a speed fluctuation of angular-acceleration amplitude ``amp``
    [rad/s^2] at ``freq`` [Hz]: a = amp cos(W t), w = w0 + amp/W sin(W t)."""
    om = 2 * math.pi * freq
    return (w0 * t + amp / om**2 * (1 - math.cos(om * t)),
            w0 + amp / om * math.sin(om * t), amp * math.cos(om * t))
