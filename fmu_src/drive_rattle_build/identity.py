"""The GUID of each FMU: derived from what defines it -- the model identifier, the flavour,
the interface (the specs' tables) and the sources of the model library -- never random, so
that a state saved by one build restores in another build of the same source, and a build of
other sources or another interface refuses it (their GUIDs differ)."""

from __future__ import annotations

import uuid

from drive_rattle import library as binding

from .paths import MODEL_SOURCE

#: The namespace of the GUIDs (uuid5), fixed once.
NAMESPACE = uuid.UUID("6f1f3a9e-2c1d-5b8a-9c44-7e2d0d6f8a11")


def fmu_guid(model: str, flavour: str, extra: str = "") -> str:
    """``{...}``: the GUID of ``model``'s FMU of ``flavour`` ("pythonfmu" or "native"),
    from the model library's sources (tables included) and ``extra`` (what else the flavour
    ships: its glue's sources)."""
    key = f"{model}\0{flavour}\0{binding.source_id(MODEL_SOURCE)}\0{extra}"
    return "{" + str(uuid.uuid5(NAMESPACE, key)) + "}"
