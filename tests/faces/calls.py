"""The calls the face tests share: an instance started in the face's standard, the last message
it logged, and the model library's own message for the same calls (what a face must pass on
verbatim)."""

from __future__ import annotations

import pytest

from drive_rattle.library import ModelError
from drive_rattle.units import Unit

from .raw_fmi import OK, Model, unpack
from .twin import KINDS


def loaded(fmus: dict, tmp_path_factory, tag: str) -> dict:
    """``fmus`` ({model: path}) unpacked and loaded in the raw driver, by model."""
    return {name: Model(unpack(fmu, tmp_path_factory.mktemp(f"{tag}_{name}")))
            for name, fmu in fmus.items()}


def started(model: Model, **values):
    """An instance initialized at t = 0 with ``values`` set in initialization mode."""
    inst = model.instantiate(b"glue")
    assert inst is not None, model.pending_log
    assert inst.begin(0.0) == OK
    assert inst.set_named(values) == OK
    assert inst.exit() == OK, inst.log
    return inst


def last(inst) -> tuple[int, str, str]:
    return inst.log[-1]


def twin_error(model: str, *calls) -> str:
    """The library's message for the last of ``calls`` (name, args...) on a fresh unit."""
    with Unit(KINDS[model], initialize=False) as unit:
        for name, *args in calls[:-1]:
            getattr(unit, name)(*args) if not name.startswith("rm_") else unit.call(name, *args)
        name, *args = calls[-1]
        with pytest.raises(ModelError) as err:
            getattr(unit, name)(*args) if not name.startswith("rm_") else unit.call(name, *args)
        return str(err.value)
