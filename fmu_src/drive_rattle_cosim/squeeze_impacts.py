"""Single impacts of the squeeze-film law (contact.dissipation = 3, docs/model.md section 3.3)
through the model library: the free wheel started 20 nm short of the drive flank at normal
speed v, the pinion at rest at phi_p = 0, no load, friction off; its restitution (speed after
the flanks part over the approach speed) beside the law's e(v) = e_dry (1 - v_c/v) as the
library's onset sets it (``rm_probe_squeeze``).

The library is the FMU's code: tests/fmu/test_squeeze_restitution.py steps the built FMU
through the same impacts at the same speeds (``speeds``) and holds its restitutions against
these and against the readable law of tests/oracle/dissipation.py; docs/model.md's table is
``table()`` (``python -m drive_rattle_cosim.model_doc --update``).
"""

from __future__ import annotations

import ctypes
from dataclasses import replace

from drive_rattle import DRIVE, MeshParameters, MeshUnit
from drive_rattle.library import MESH
from drive_rattle.units import Unit

from . import probe_rows

#: The speeds of the table: multiples of the critical speed v_c (three below it, sticking;
#: four just above it), then fixed speeds [m/s] up to 100 mm/s.
CRITICAL_MULTIPLES = (0.3, 0.6, 0.95, 1.02, 1.2, 1.6, 2.5)
FIXED_SPEEDS = (8e-3, 15e-3, 30e-3, 60e-3, 100e-3)
#: The gap [m] the wheel starts short of the flank, and the step [s] (the FMU test's).
GAP = 20e-9
STEP = 1e-4
#: Steps before an impact must have released.
MAX_STEPS = 2000


def free_parameters(v: float, gap: float = GAP, **changes) -> MeshParameters:
    """The defaults with the squeeze-film law (or ``changes``' dissipation), the wheel started
    free ``gap`` short of the drive flank approaching it at normal speed ``v`` [m/s] (pinion at
    rest at phi_p = 0), friction off."""
    p = MeshParameters(**{"init_in_contact": False, "friction_enabled": False,
                          "dissipation": 3, **changes})
    d = p.derived()
    return replace(p, phi_start=-DRIVE * (d["half_backlash"] - gap) / d["arm_wheel"],
                   w_start=-DRIVE * v / d["arm_wheel"])


def law(v: float, params: MeshParameters | None = None, phi_p: float = 0.0
        ) -> tuple[float, float]:
    """(the law's restitution e(v), the critical speed v_c [m/s]) at pinion angle ``phi_p``
    on the drive flank, as the library's onset sets them: v_c = St_c v / St."""
    p = params or free_parameters(v)
    return _squeeze(p, [phi_p], v)[0][1:]


def _squeeze(p: MeshParameters, angles, v: float = 1e-3) -> list[tuple[float, float, float]]:
    """(the squeeze-film area A [m^2], the law's e(v), v_c [m/s]) on the drive flank at each
    pinion angle of ``angles`` (``rm_probe_squeeze``)."""
    unit = Unit(MESH, p, initialize=False)
    try:
        out, rows = (ctypes.c_double * 5)(), []
        for phi_p in angles:
            unit.call("rm_probe_squeeze", int(DRIVE), float(phi_p), float(v), out)
            area, stokes, e = out[0], out[1], out[2]
            rows.append((area, e, p.stokes_critical * v / stokes))
        return rows
    finally:
        unit.close()


def library_critical_speed() -> float:
    """The default pair's critical speed v_c [m/s] at phi_p = 0."""
    return law(1e-3)[1]


def critical_speeds(changes: dict, angles=(0.0,)) -> list[float]:
    """The squeeze-film law's critical speed v_c [m/s] of the defaults changed by ``changes``
    at each pinion angle of ``angles`` (the library's onset)."""
    return [v_c for _, _, v_c in _squeeze(MeshParameters(**{"dissipation": 3, **changes}),
                                           angles)]


def squeeze_area(phi_p: float = 0.0) -> float:
    """The default flank's squeeze-film area A [m^2] at pinion angle ``phi_p``: the pairs
    whose crown offset is within sigma of the smallest (the library's onset)."""
    return _squeeze(MeshParameters(), [phi_p])[0][0]


def pitch_point_damper() -> float:
    """The film damping [N s/m] of a sticking contact on the pair whose contact point is the
    pitch point (pinion angle -p_bt/(4 r_bp), slot 0): the change of that pair's load with
    the penetration rate, on the library's loads at 0.1 um of penetration and an onset at
    half the critical speed (it sticks)."""
    p = MeshParameters()
    d = p.derived()
    phi_p = -d["base_pitch"] / (4.0 * d["rb_pinion"])
    delta, rate = 0.1e-6, 1e-4
    phi_w = (d["arm_pinion"] * phi_p - delta - d["half_backlash"]) / d["arm_wheel"]
    v_stick = 0.5 * critical_speeds({}, [phi_p])[0]
    unit = Unit(MESH, p, initialize=False)
    try:
        load = {}
        for w_w in (0.0, -rate / d["arm_wheel"]):
            (at_pitch,) = [r for r in probe_rows.loads(unit, phi_p, 0.0, phi_w, w_w, v_stick)
                           if abs(r["s"] - d["s_pitch"]) < 1e-9 * d["s_pitch"]]
            load[w_w] = at_pitch["W"]
        static, moving = load.values()
        return (moving - static) / rate
    finally:
        unit.close()


def hunt_crossley(e: float = 0.8, v_ref: float = 4e-3, at=(1e-3, 20e-3, 100e-3)
                  ) -> tuple[float, list[float]]:
    """(the Hunt-Crossley factor d [s/m] that gives restitution ``e`` at ``v_ref`` [m/s], its
    restitution at each speed of ``at``): the library's inversion and relation."""
    unit = Unit(MESH, MeshParameters(), initialize=False)
    try:
        out = ctypes.c_double()
        unit.call("rm_probe_damping_factor", float(e), float(v_ref), ctypes.byref(out))
        d = out.value
        found = []
        for v in at:
            unit.call("rm_probe_restitution", float(d * v), ctypes.byref(out))
            found.append(out.value)
        return d, found
    finally:
        unit.close()


def speeds(v_c: float | None = None) -> list[float]:
    """The table's approach speeds [m/s], ascending."""
    v_c = library_critical_speed() if v_c is None else v_c
    return [m * v_c for m in CRITICAL_MULTIPLES] + list(FIXED_SPEEDS)


def measured_restitution(v: float, **changes) -> float:
    """Release speed over approach speed of one impact at normal speed ``v`` [m/s] (of the
    defaults with the squeeze-film law changed by ``changes``): stepped by STEP until the
    impact has happened and the flanks have parted (load and approach 0; the wheel then
    flies at a constant speed)."""
    p = free_parameters(v, **changes)
    with MeshUnit(p, 0.0, 0.0, 0.0) as unit:
        for _ in range(MAX_STEPS):
            unit.step(STEP, 0.0, 0.0, 0.0, 0.0)
            out = unit.get(("wheel.w", "mesh.W", "mesh.delta", "mesh.impacts_drive"))
            if out["mesh.impacts_drive"] and out["mesh.W"] == 0.0 and out["mesh.delta"] == 0.0:
                return out["wheel.w"] / -p.w_start
    raise RuntimeError(f"no release within {MAX_STEPS * STEP} s at {v} m/s")


def results() -> tuple[float, list[tuple[float, float, float]]]:
    """(v_c, [(v, the law's e, the measured e)] over ``speeds()``)."""
    v_c = library_critical_speed()
    return v_c, [(v, law(v)[0], measured_restitution(v)) for v in speeds(v_c)]


def _v(v: float) -> str:
    return f"{v * 1e3:.3g}"


def _diff(x: float) -> str:
    if x == 0.0:
        return "0"
    mantissa, exponent = f"{x:.0e}".split("e")
    return f"{mantissa}e{int(exponent)}".replace("-", "−")


def table(computed=None) -> str:
    """The markdown table of docs/model.md section 3.3 and its closing line."""
    v_c, rows = computed or results()
    worst = max(abs(m - e) for _, e, m in rows)
    return ("| v [mm/s] | " + " | ".join(_v(v) for v, _, _ in rows) + " |\n"
            "|---|" + "---|" * len(rows) + "\n"
            "| e, law | " + " | ".join(f"{e:.4f}" if e else "0" for _, e, _ in rows) + " |\n"
            "| e, library − law | " + " | ".join(_diff(m - e) for _, e, m in rows) + " |\n\n"
            f"(v_c = {v_c * 1e3:.4g} mm/s at φp = 0; the largest difference "
            f"{worst:.1e}.)")
