"""Unit definitions of the FMUs' modelDescription: every unit string used by a parameter or
signal spec, its SI base-unit exponents and its display units (FMI 2.0 section 2.2.2).

A display value is ``factor * value + offset``.
"""

from __future__ import annotations

import math

#: unit -> base-unit exponents (kg, m, s, A, K, mol, cd, rad)
BASE_UNITS: dict[str, dict[str, int]] = {
    "1": {},
    "rad": {"rad": 1},
    "rad/s": {"rad": 1, "s": -1},
    "rad/s2": {"rad": 1, "s": -2},
    "s": {"s": 1},
    "m": {"m": 1},
    "m/s": {"m": 1, "s": -1},
    "s/m": {"s": 1, "m": -1},
    "N": {"kg": 1, "m": 1, "s": -2},
    "N.m": {"kg": 1, "m": 2, "s": -2},
    "J": {"kg": 1, "m": 2, "s": -2},
    "W": {"kg": 1, "m": 2, "s": -3},
    "N.m/rad": {"kg": 1, "m": 2, "s": -2, "rad": -1},
    "N.m.s/rad": {"kg": 1, "m": 2, "s": -1, "rad": -1},
    "Pa": {"kg": 1, "m": -1, "s": -2},
    "Pa.s": {"kg": 1, "m": -1, "s": -1},
    "1/Pa": {"kg": -1, "m": 1, "s": 2},
    "kg.m2": {"kg": 1, "m": 2},
    "kg/m3": {"kg": 1, "m": -3},
    "1/m2": {"m": -2},
}

#: unit -> {display unit: factor}
DISPLAY_UNITS: dict[str, dict[str, float]] = {
    "rad": {"deg": 180.0 / math.pi},
    "rad/s": {"rpm": 60.0 / (2.0 * math.pi)},
    "m": {"mm": 1e3, "um": 1e6},
    "m/s": {"mm/s": 1e3},
}


def check_display_unit(unit: str, display_unit: str | None) -> None:
    """Raise ValueError if a spec names a unit or display unit that is not defined here."""
    if unit not in BASE_UNITS:
        raise ValueError(f"unit {unit!r} has no definition in drive_rattle_build.unit_definitions")
    if display_unit is not None and display_unit not in DISPLAY_UNITS.get(unit, {}):
        raise ValueError(f"display unit {display_unit!r} is not defined for unit {unit!r}")
