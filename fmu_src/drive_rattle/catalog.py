"""Every unit of the system with its specs, declared once: the model identifier (the FMU's), the
model library's unit kind, the parameter class, the inputs and outputs, and the descriptions
the FMUs carry.  The slaves, the modelDescription of both flavours, the documentation and the
studies take a unit's specs from here."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from . import interface, library
from .parameters import DrivelineParameters, MeshParameters, ParameterSpec, specs


@dataclass(frozen=True)
class UnitSpec:
    """One unit of the system."""

    model: str  # model identifier of its FMUs (interface.MODELS)
    kind: int  # the model library's unit kind (library.MESH, library.DRIVELINE)
    parameters: type  # its parameter class (drive_rattle.parameters)
    inputs: tuple  # its inputs' SignalSpecs (drive_rattle.interface)
    outputs: tuple  # its outputs' SignalSpecs
    description: str  # one sentence: the modelDescription's description
    summary: str  # what goes in and out, for documentation


UNITS: dict[str, UnitSpec] = {
    interface.MESH: UnitSpec(
        interface.MESH, library.MESH, MeshParameters, interface.MESH_INPUTS,
        interface.MESH_OUTPUTS,
        "Transmission drive rattle: gear-mesh impact (Hertz, every tooth pair, both flanks) and "
        "flank friction of a helical pair with backlash; kinematic pinion, wheel integrated "
        "inside (Theodossiades, Rahnejat, De la Cruz, Kelly, ENOC 2008)",
        "Helical gear mesh with backlash: Hertzian impacts of every tooth pair on both flanks "
        "and mixed boundary/viscous flank friction; pinion kinematics in, wheel motion and "
        "torques out."),
    interface.DRIVELINE: UnitSpec(
        interface.DRIVELINE, library.DRIVELINE, DrivelineParameters,
        interface.DRIVELINE_INPUTS, interface.DRIVELINE_OUTPUTS,
        "Driveline around the drive-rattle gear mesh: input-shaft kinematics from engine orders "
        "or a measured speed table, output shaft as a torsional spring-damper to a reflected "
        "vehicle inertia with drag",
        "Engine-order (or measured) pinion kinematics out; wheel angle and speed in, "
        "output-shaft load torque out."),
}
if tuple(UNITS) != interface.MODELS:
    raise ImportError("catalog.UNITS must list interface.MODELS in order")


def parameter_names() -> list[str]:
    """Every parameter of the system by its qualified name, ``<Unit>.<name>``, in unit order."""
    return [f"{model}.{spec.name}" for model, unit in UNITS.items()
            for _, spec in specs(unit.parameters)]


def parameter_spec(qualified: str) -> ParameterSpec:
    """The spec of the parameter ``<Unit>.<name>`` (``GearMeshRattle.gear.backlash``), or
    ValueError naming it with the nearest known names ("did you mean ...")."""
    model, _, name = qualified.partition(".")
    unit = UNITS.get(model)
    if unit is not None:
        for _, spec in specs(unit.parameters):
            if spec.name == name:
                return spec
        for kind, signals in (("an input", unit.inputs), ("an output", unit.outputs)):
            if any(signal.name == name for signal in signals):
                raise ValueError(f"'{qualified}' is {kind} of {model}, not a parameter; "
                                 "allowed: a parameter's name (docs/fmi.md lists them)")
    raise ValueError(f"unknown parameter '{qualified}'{_did_you_mean(qualified)}; allowed: "
                     f"<Unit>.<name> with Unit one of {', '.join(UNITS)} and name one of its "
                     "parameters (docs/fmi.md lists them)")


def _did_you_mean(qualified: str) -> str:
    """`` (did you mean A or B?)``: the parameters of that name in other units, else the
    nearest names of the unit (of the nearest unit name), else nothing."""
    from difflib import get_close_matches

    known = parameter_names()
    model, _, name = qualified.partition(".")
    near = [q for q in known if q.split(".", 1)[1] in (qualified, name)]
    if not near:
        units = [model] if model in UNITS else get_close_matches(model, list(UNITS), n=1)
        for unit in units:
            names = [spec.name for _, spec in specs(UNITS[unit].parameters)]
            near = [f"{unit}.{n}" for n in get_close_matches(name, names, n=3)]
    return f" (did you mean {' or '.join(near)}?)" if near else ""


def parse_setting(text: str) -> tuple[str, Any]:
    """``(qualified name, value)`` of a command line's ``<Unit>.<name>=<value>``, the value
    read by the parameter's declared type (:meth:`ParameterSpec.parse`); ValueError with one
    sentence naming what is wrong, the text and what is allowed.  The range and the
    combinations are the model library's to check (:func:`check_settings`)."""
    qualified, sep, value = text.partition("=")
    if not sep or not qualified.strip():
        raise ValueError(f"setting {text!r} is not NAME=VALUE; allowed: <Unit>.<name>=<value>, "
                         "e.g. GearMeshRattle.gear.backlash=1.2e-4")
    qualified = qualified.strip()
    return qualified, parameter_spec(qualified).parse(value, qualified)


def parse_settings(texts: list[str]) -> dict[str, Any]:
    """``{qualified name: value}`` of several settings (:func:`parse_setting`); a parameter set
    twice is refused (the first value would be lost silently)."""
    out: dict[str, Any] = {}
    for text in texts:
        name, value = parse_setting(text)
        if name in out:
            raise ValueError(f"parameter '{name}' is set twice ({out[name]!r} and {value!r}); "
                             "allowed: one value per parameter")
        out[name] = value
    return out


def check_settings(values: dict[str, Any]) -> None:
    """ValueError (the model library's message) unless ``{qualified name: value}`` gives each
    unit a valid parameter set: ranges, choices and the combination checks, the others at
    their defaults."""
    for name in values:
        parameter_spec(name)
    for model, unit in UNITS.items():
        prefix = f"{model}."
        unit.parameters.from_public({k[len(prefix):]: v for k, v in values.items()
                                     if k.startswith(prefix)})
