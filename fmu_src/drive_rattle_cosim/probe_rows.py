"""The model library's test-only probes of the tooth pairs (rm_probe.h: ``rm_probe_loads``,
``rm_probe_pair_laws``), read into one dict of named fields per pair: what the generated
constants of docs/model.md and the single-impact studies read from the library built in place
(its probes are not in a shipped FMU's binary)."""

from __future__ import annotations

import ctypes

#: Doubles per pair row of rm_probe_loads and rm_probe_pair_laws, in their order (rm_probe.h).
LOAD_FIELDS = ("slot", "s", "offset", "r_x", "K", "delta", "W", "F", "sliding_speed",
               "entrainment_speed", "h", "film_parameter", "dry_fraction", "delta_max_eq7")
LAW_FIELDS = ("slot", "s", "length", "r_x", "r_y", "K", "ka", "kz", "W_r", "c_t")
#: Pairs a probe may return (more than any flank holds in the zone of action).
CAPACITY = 16


def rows(unit, name: str, fields: tuple, *args) -> list[dict]:
    """The pairs the probe ``name`` writes, called on ``unit`` with ``args`` then the rows'
    buffer, its capacity and the count (the probes' common tail)."""
    out, n = (ctypes.c_double * (len(fields) * CAPACITY))(), ctypes.c_size_t()
    unit.call(name, *args, out, CAPACITY, ctypes.byref(n))
    w = len(fields)
    return [dict(zip(fields, out[w * i: w * (i + 1)], strict=True)) for i in range(n.value)]


def loads(unit, phi_p, w_p, phi_w, w_w, v_impact) -> list[dict]:
    """Each pair's load on the drive flank at the given gear angles and speeds, the onset at
    ``v_impact`` (``rm_probe_loads``, LOAD_FIELDS; its totals are not kept)."""
    from drive_rattle import DRIVE

    totals = (ctypes.c_double * 5)()
    return rows(unit, "rm_probe_loads", LOAD_FIELDS, int(DRIVE), phi_p, w_p, phi_w, w_w,
                v_impact, totals)


def pair_laws(unit, phi_p) -> list[dict]:
    """Each pair's law on the drive flank at pinion angle ``phi_p`` (``rm_probe_pair_laws``,
    LAW_FIELDS)."""
    from drive_rattle import DRIVE

    return rows(unit, "rm_probe_pair_laws", LAW_FIELDS, int(DRIVE), phi_p)
