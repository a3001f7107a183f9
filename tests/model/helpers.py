"""Shared set-ups of the model tests: the library's probes (``rm_probe_*``) as Python calls, a
mesh unit started free against a pinion at rest, pinion kinematics with one order, the
parameter sets held against the oracle, the default forcing and its separation load, and
the check that a refused call changes nothing."""

from __future__ import annotations

import ctypes
import math
from dataclasses import replace
from typing import NamedTuple

import pytest

from drive_rattle import DRIVE, DrivelineParameters, MeshParameters, MeshUnit, ModelError, Unit
from drive_rattle.library import MESH
from drive_rattle.parameters import DEG
from tests.oracle.mesh import MeshModel

#: Doubles per pair row of rm_probe_loads, in its order (rattle_model.h).
PAIR_FIELDS = ("slot", "s", "offset", "r_x", "K", "delta", "W", "F", "sliding_speed",
               "entrainment_speed", "h", "film_parameter", "dry_fraction", "delta_max_eq7")
TOTAL_FIELDS = ("delta", "tau_wheel", "tau_pinion", "W", "F")
#: Doubles per pair row of rm_probe_pair_laws, in its order (rattle_model.h).
PAIR_LAW_FIELDS = ("slot", "s", "length", "r_x", "r_y", "K", "ka", "kz", "W_r", "c_t")
MAX_PAIRS = 16


class Loads(NamedTuple):
    """rm_probe_loads: the flank's totals and one dict per pair in the zone of action."""

    delta: float
    tau_wheel: float
    tau_pinion: float
    W: float
    F: float
    pairs: list[dict]


class Probe:
    """The model's laws at given arguments, through the library's probes, for a parameter set
    (a GearMeshRattle unit holding it, not initialized)."""

    def __init__(self, params: MeshParameters | None = None):
        self.params = params or MeshParameters()
        self.unit = Unit(MESH, self.params, initialize=False)
        self.derived = self.unit.describe()

    def close(self) -> None:
        self.unit.close()

    def contact_law(self, r_x: float) -> tuple[float, float, float, float]:
        out = (ctypes.c_double * 4)()
        self.unit.call("rm_probe_contact_law", float(r_x), out)
        return tuple(out)

    def exact_ellipse(self, rho: float) -> tuple[float, float, float, float]:
        out = (ctypes.c_double * 4)()
        self.unit.call("rm_probe_exact_ellipse", float(rho), out)
        return tuple(out)

    def restitution(self, alpha: float) -> float:
        out = ctypes.c_double()
        self.unit.call("rm_probe_restitution", float(alpha), ctypes.byref(out))
        return out.value

    def damping_factor(self, e: float, v: float) -> float:
        out = ctypes.c_double()
        self.unit.call("rm_probe_damping_factor", float(e), float(v), ctypes.byref(out))
        return out.value

    def pairs(self, flank: int, phi_p: float) -> list[tuple[int, float, float, float]]:
        out = (ctypes.c_double * (4 * MAX_PAIRS))()
        n = ctypes.c_size_t()
        self.unit.call("rm_probe_pairs", int(flank), float(phi_p), out, MAX_PAIRS,
                       ctypes.byref(n))
        assert n.value <= MAX_PAIRS
        return [(int(out[4 * i]), out[4 * i + 1], out[4 * i + 2], out[4 * i + 3])
                for i in range(n.value)]

    def pair_laws(self, flank: int, phi_p: float) -> list[dict]:
        """rm_probe_pair_laws: one dict per pair in the zone (PAIR_LAW_FIELDS)."""
        width = len(PAIR_LAW_FIELDS)
        out = (ctypes.c_double * (width * MAX_PAIRS))()
        n = ctypes.c_size_t()
        self.unit.call("rm_probe_pair_laws", int(flank), float(phi_p), out, MAX_PAIRS,
                       ctypes.byref(n))
        assert n.value <= MAX_PAIRS
        rows = [dict(zip(PAIR_LAW_FIELDS, out[width * i: width * (i + 1)], strict=True))
                for i in range(n.value)]
        for r in rows:
            r["slot"] = int(r["slot"])
        return rows

    def approach(self, K: float, W_r: float, kz: float, pen: float, c_t: float = 0.0
                 ) -> tuple[float, float, float, float, float]:
        """rm_probe_approach: (W, dW/d(pen), energy, area, the flanks' own approach) of the
        parameters' law with the teeth's compliance c_t in series (0: rigid teeth)."""
        out = (ctypes.c_double * 5)()
        self.unit.call("rm_probe_approach", float(K), float(W_r), float(c_t), float(kz),
                       float(pen), out)
        return tuple(out)

    def loads(self, flank: int, phi_p: float, w_p: float, phi_w: float, w_w: float,
              v_impact: float) -> Loads:
        width = len(PAIR_FIELDS)
        totals = (ctypes.c_double * 5)()
        rows = (ctypes.c_double * (width * MAX_PAIRS))()
        n = ctypes.c_size_t()
        self.unit.call("rm_probe_loads", int(flank), float(phi_p), float(w_p), float(phi_w),
                       float(w_w), float(v_impact), totals, rows, MAX_PAIRS, ctypes.byref(n))
        assert n.value <= MAX_PAIRS
        pairs = [dict(zip(PAIR_FIELDS, rows[width * i: width * (i + 1)], strict=True))
                 for i in range(n.value)]
        for p in pairs:
            p["slot"] = int(p["slot"])
        return Loads(*totals, pairs)


def free_parameters(v: float, flank: int = DRIVE, gap: float = 20e-9, **changes
                    ) -> MeshParameters:
    """Parameters of a wheel started free (init.in_contact false) ``gap`` [m] short of
    ``flank`` and approaching it at normal speed ``v`` [m/s] while the pinion rests at
    phi_p = 0; friction off unless given."""
    changes.setdefault("friction_enabled", False)
    p = MeshParameters(init_in_contact=False, **changes)
    d = p.derived()
    return replace(p, phi_start=-flank * (d["half_backlash"] - gap) / d["arm_wheel"],
                   w_start=-flank * v / d["arm_wheel"])


def approach_unit(v: float, flank: int = DRIVE, gap: float = 20e-9, **changes) -> MeshUnit:
    """A mesh unit whose wheel approaches ``flank`` (see :func:`free_parameters`) with the
    pinion at rest and no load."""
    return MeshUnit(free_parameters(v, flank, gap, **changes), 0.0, 0.0, 0.0)


def rest_step(unit: MeshUnit, h: float):
    """One step of ``h`` [s] with the pinion at rest at phi_p = 0 and no load: its report."""
    return unit.step(h, 0.0, 0.0, 0.0, 0.0)


def run_impact(unit: MeshUnit, h: float = 1e-5, t_max: float = 3e-2):
    """Step a wheel approaching a pinion at rest until its first release: ``(events as
    (time, event), peak penetration [m], peak normal force [N])``."""
    events, d_peak, W_peak = [], 0.0, 0.0
    k = 0
    while k * h < t_max:
        report = rest_step(unit, h)
        out = unit.get(("mesh.delta_peak", "mesh.W_peak"))
        events += [(k * h + e.time, e) for e in report.events]
        d_peak, W_peak = max(d_peak, out["mesh.delta_peak"]), max(W_peak, out["mesh.W_peak"])
        k += 1
        if any(e.kind == "release" for _, e in events):
            break
    return events, d_peak, W_peak


def restitution(v: float, flank: int = DRIVE, h: float = 1e-4, gap: float = 20e-9,
                **changes) -> float:
    """Coefficient of restitution of one impact of the free wheel at normal speed ``v``:
    release speed over approach speed."""
    with approach_unit(v, flank, gap, **changes) as unit:
        events, _, _ = run_impact(unit, h=h)
    release = [e for _, e in events if e.kind == "release"]
    assert release, "no release within the horizon"
    return -release[0].speed / v


def pinion_with_order(t: float, w0: float, amp: float, freq: float):
    """Pinion kinematics with a speed fluctuation of angular-acceleration amplitude ``amp``
    [rad/s^2] at ``freq`` [Hz]: a = amp cos(W t), w = w0 + amp/W sin(W t)."""
    om = 2 * math.pi * freq
    return (w0 * t + amp / om**2 * (1 - math.cos(om * t)),
            w0 + amp / om * math.sin(om * t), amp * math.cos(om * t))


# ------------------------------------------------ communication step, pinion speed, contact options
#: The communication step of the model tests [s].
H = 1e-4
W_PINION = 86.92  # rad/s, 830 rpm
SPUR = {"beta": 0.0, "b": 20e-3}  # no crown offsets: every pair touches at the same approach
#: The contact options: the paper's (every pair in the zone loaded) and the line contact.
PAPER = {"contact_geometry": 1, "tooth_compliance": 0}  # the paper's model as printed
LINE = {"contact_geometry": 2}


# ------------------------------------------------------- the parameter sets held against the oracle
#: The tolerances against the oracle are those of two implementations of the same formulas
#: in a different order of operations (relative 1e-12 on a quantity, 1e-12 of the sum of
#: magnitudes on a signed sum); the measured agreement is tighter (most quantities agree to
#: the last bit).
REL = 1e-12
PARAMETER_SETS = [
    {},
    {"beta": 0.0},
    {"hertz_law": 1},
    {"b": 2e-3, "crowning": 9e-5},  # r_y inside the range of r_x along the path of contact
    {"z_pinion": 30, "z_wheel": 45, "beta": 0.5, "backlash": 0.0},
    {"z_pinion": 18, "z_wheel": 80, "m_n": 5e-3, "alpha_n": 25 * DEG, "addendum": 1.2,
     "dissipation": 2, "damping": 300.0},
    # the contact options: the paper's geometry, the line contact, rough flanks
    {"contact_geometry": 1},
    {"contact_geometry": 1, "hertz_law": 1, "beta": 0.0},
    {"contact_geometry": 2},
    {"contact_geometry": 2, "beta": 0.0, "b": 2e-3},
    {"roughness": 1},
    {"contact_geometry": 1, "roughness": 1, "sigma": 1e-7},
    {"contact_geometry": 2, "roughness": 1, "z_pinion": 30, "z_wheel": 45, "beta": 0.5,
     "asperity_density": 3e10},
    {"dissipation": 3, "viscous_law": 1, "shear_speed": 1, "sigma": 5e-8, "film": 1},
    {"dissipation": 4, "beta": 0.0, "friction_form": 2},
]


def oracle_derived(m: MeshModel) -> dict[str, float]:
    """What rm_describe reports, from the oracle."""
    g = m.geometry
    names = ("ratio", "alpha_t", "beta_b", "centre_distance", "r_pinion", "r_wheel",
             "rb_pinion", "rb_wheel", "ra_pinion", "ra_wheel", "line_length", "s_start",
             "s_end", "s_pitch", "base_pitch", "eps_alpha", "eps_beta", "eps_gamma",
             "max_pairs", "r_y", "crown_factor", "half_backlash", "normal_factor")
    out = {n: float(getattr(g, n)) for n in names}
    out.update(E_star=m.E_star, arm_wheel=m.arm_wheel, arm_pinion=m.arm_pinion,
               normal_mass=m.normal_mass, damping=m.damping,
               penetration_limit=0.05 * m.params.m_n,
               law_terms=float(len(m.law.kappa)), r_y_eq6_pitch=g.radius_y_eq6(g.s_pitch),
               palmgren_constant=m.approach.palmgren,
               asperity_pressure=m.approach.asperity_pressure,
               tooth_stiffness_pitch=1.0 / m.tooth.pitch if m.tooth else math.inf,
               tooth_terms=float(len(m.tooth.coefficients)) if m.tooth else 0.0)
    return out


def close(a: float, b: float, rel: float = REL, abs_: float = 0.0) -> bool:
    return a == b or abs(a - b) <= max(rel * abs(b), abs_)


# ------------------------------------------------------------------ the default forcing
PARAMS = MeshParameters()
RATIO = PARAMS.z_pinion / PARAMS.z_wheel
#: Deepest deceleration of the default pinion (orders 2/4/6 at 300/200/150 rad/s^2), and the
#: load below which it separates the default wheel quasi-statically (MODEL_NOTES section 3).
DEEPEST_DECELERATION = 250.0
M_STAR = PARAMS.J_wheel * RATIO * DEEPEST_DECELERATION
#: One period of the default forcing: orders 2, 4, 6 and the mesh (order 20) of 830 rpm
#: repeat every half revolution.
PERIOD = 0.5 * 2 * math.pi / DrivelineParameters().w_mean


# ------------------------------------------------------------------ refused calls
def history(p=None):
    unit = MeshUnit(p or MeshParameters(init_in_contact=False, h_comm_max=1e-2), 0.0, 87.0, 0.1)
    for k in range(5):
        unit.step(H, 87.0 * k * H, 87.0, 0.0, 0.1)
    return unit


def assert_refused_and_unchanged(unit, call, *args, match):
    """Call ``call`` of the library on ``unit``: refused (message matching ``match``) with the
    unit's record, phase and (once stepping) outputs and time unchanged; the message."""

    def state():
        stepping = unit.phase == "stepping"
        return (unit.save(), unit.phase, unit.outputs() if stepping else None,
                unit.time if stepping else None)

    before = state()
    with pytest.raises(ModelError, match=match) as err:
        unit.call(call, *args)
    assert state() == before
    return str(err.value)
