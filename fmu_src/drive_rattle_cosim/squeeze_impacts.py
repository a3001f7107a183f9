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
    """The defaults with the squeeze-film law, the wheel started free ``gap`` short of the
    drive flank approaching it at normal speed ``v`` [m/s] (pinion at rest at phi_p = 0),
    friction off."""
    p = MeshParameters(init_in_contact=False, friction_enabled=False, dissipation=3,
                       **changes)
    d = p.derived()
    return replace(p, phi_start=-DRIVE * (d["half_backlash"] - gap) / d["arm_wheel"],
                   w_start=-DRIVE * v / d["arm_wheel"])


def law(v: float, params: MeshParameters | None = None) -> tuple[float, float]:
    """(the law's restitution e(v), the critical speed v_c [m/s]) at phi_p = 0 on the drive
    flank, as the library's onset sets them: v_c = St_c v / St."""
    p = params or free_parameters(v)
    unit = Unit(MESH, p, initialize=False)
    try:
        out = (ctypes.c_double * 5)()
        unit.call("rm_probe_squeeze", int(DRIVE), 0.0, float(v), out)
        _area, stokes, e = out[0], out[1], out[2]
        return e, p.stokes_critical * v / stokes
    finally:
        unit.close()


def library_critical_speed() -> float:
    """The default pair's critical speed v_c [m/s] at phi_p = 0."""
    return law(1e-3)[1]


def speeds(v_c: float | None = None) -> list[float]:
    """The table's approach speeds [m/s], ascending."""
    v_c = library_critical_speed() if v_c is None else v_c
    return [m * v_c for m in CRITICAL_MULTIPLES] + list(FIXED_SPEEDS)


def measured_restitution(v: float) -> float:
    """Release speed over approach speed of one impact at normal speed ``v`` [m/s]: stepped
    by STEP until the impact has happened and the flanks have parted (load and approach 0;
    the wheel then flies at a constant speed)."""
    p = free_parameters(v)
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
