"""Shared set-ups of the model tests: the library's probes (``rm_probe_*``) as Python calls, a
mesh unit started free against a pinion at rest, and pinion kinematics with one order."""

from __future__ import annotations

import ctypes
import math
from dataclasses import replace
from typing import NamedTuple

from drive_rattle import DRIVE, MeshParameters, MeshUnit, Unit
from drive_rattle.library import MESH

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
