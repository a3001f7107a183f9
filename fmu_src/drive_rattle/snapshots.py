"""Checking saved state before it is trusted: a snapshot read back from JSON (an FMU state a
master hands back may be forged or corrupted) is a dict of lists whose entries must each lie
in their domain.  The steppers' ``from_json`` and the FMI layer check their parts here, so every
refusal names the entry, its value and what is allowed in the same words."""

from __future__ import annotations

import math

#: Largest magnitude of a saved count (the compiled kernel holds the impact counters as
#: doubles, exact up to 2^53).
MAX_STATE_INTEGER = 2**53

#: The domains of saved values: a check and the words a refusal uses.
DOMAINS = {
    "f": "a finite float",
    "f+": "a finite float >= 0",
    "n": "an integer in [0, 2^53]",
    "flank": "-1, 0 or 1",
}


def short_repr(value, limit: int = 60) -> str:
    text = repr(value)
    return text if len(text) <= limit else f"{text[:limit]}..."


def is_finite_float(x) -> bool:
    return isinstance(x, float) and math.isfinite(x)


def _in_domain(value, domain: str) -> bool:
    if domain == "f":
        return is_finite_float(value)
    if domain == "f+":
        return is_finite_float(value) and value >= 0.0
    integer = isinstance(value, int) and not isinstance(value, bool)
    if domain == "n":
        return integer and 0 <= value <= MAX_STATE_INTEGER
    if domain == "flank":
        return integer and value in (-1, 0, 1)
    raise ValueError(f"unknown domain {domain!r}; allowed: {', '.join(DOMAINS)}")


def check_fields(snapshot, layout: dict[str, tuple]) -> dict:
    """``snapshot`` if it is a dict with exactly the keys of ``layout`` and each entry in the
    domains given there: a tuple of domains for a list (one per item), ``("=f",)``-style (a
    leading ``=``) for a single value, ``("any",)`` unchecked; the domains are the keys of
    ``DOMAINS``.  ValueError naming the first entry out of its domain otherwise."""
    if not isinstance(snapshot, dict) or set(snapshot) != set(layout):
        got = sorted(snapshot) if isinstance(snapshot, dict) else type(snapshot).__name__
        raise ValueError(f"model snapshot has entries {got}, expected {sorted(layout)}")
    for key, domains in layout.items():
        value = snapshot[key]
        if domains == ("any",):
            continue
        scalar = domains[0].startswith("=")
        items = [value] if scalar else value
        if not scalar and not (isinstance(value, list) and len(value) == len(domains)):
            raise ValueError(f"model snapshot '{key}' = {short_repr(value)}: expected a list "
                             f"of {len(domains)} values")
        for i, (item, domain) in enumerate(zip(items, domains, strict=True)):
            domain = domain.lstrip("=")
            if not _in_domain(item, domain):
                where = key if scalar else f"{key}[{i}]"
                raise ValueError(f"model snapshot {where} = {short_repr(item)}: "
                                 f"expected {DOMAINS[domain]}")
    return snapshot
