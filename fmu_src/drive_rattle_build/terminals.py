"""``terminalsAndIcons/`` of the FMI 3.0 FMUs (FMI 3.0.2, section 2.4.9, "Terminals and
Icons"): the icon of the FMI 2.0 FMUs (``icon.model_png``) and one terminal per shaft flange of
the unit, rendered from the flanges the interface declares (``drive_rattle.interface.FLANGES``).

FMI 3.0 defines the file, the matching rules (``plug``, ``bus``, ``sequence``, ``none``) and
the variable kinds (``signal``, ``inflow``, ``outflow``), and leaves terminal kinds to other
standards; it defines no rotational flange.  The terminals follow what exists:

* member names ``phi``, ``w``, ``a``, ``tau`` with units rad, rad/s, rad/s2, N.m: the
  Modelica Standard Library's rotational signal adaptors "especially useful for FMUs"
  (``Modelica.Mechanics.Rotational.Components.GeneralAngleToTorqueAdaptor`` and
  ``GeneralTorqueToAngleAdaptor``), which the build checks against the variables' units;
* ``matchingRule="bus"``: matched by member name, a connection allowed when some members are
  absent (a flange here has no acceleration or no torque where the unit has none);
* the torque ``inflow`` or ``outflow`` by its sign (``interface.FlangeMember``), the other
  members ``signal``;
* ``terminalKind`` vendor-specific as the standard advises ("should start with
  ``_vendorName``"): :data:`TERMINAL_KIND`;
* each terminal drawn as the Modelica flange's grey disc (``terminalsAndIcons/flange.png``)
  on the icon's edge beside its gear: the pinion's on the right, the wheel's on the left.
"""

from __future__ import annotations

import zipfile
from xml.dom.minidom import parseString
from xml.etree import ElementTree
from xml.etree.ElementTree import Element, SubElement

from drive_rattle.catalog import UNITS
from drive_rattle.interface import FLANGES

from .compiler import BuildError
from .icon import SIZE, flange_png, gear_centres, model_png

FOLDER = "terminalsAndIcons"
TERMINALS_XML = f"{FOLDER}/terminalsAndIcons.xml"
ICON_PNG = f"{FOLDER}/icon.png"
#: The base name of the terminals' image (terminalsAndIcons/flange.png).
FLANGE_ICON = "flange"
MATCHING_RULE = "bus"
TERMINAL_KIND = "_drive_rattle_RotationalFlange"
#: The unit of each member (the Modelica adaptors' units).
MEMBER_UNITS = {"phi": "rad", "w": "rad/s", "a": "rad/s2", "tau": "N.m"}
#: The variable kinds FMI 3.0 predefines.
VARIABLE_KINDS = ("signal", "inflow", "outflow")
#: The icon's extent in the standard's default coordinate system, and a terminal's side.
EXTENT, TERMINAL_SIDE = 100.0, 20.0
#: The side of the icon each shaft's terminal is drawn on (+1 right, -1 left).
SIDES = {"pinion": 1, "wheel": -1}


def _signals(model: str) -> dict:
    """The inputs and outputs of ``model`` by name (FMI 3.0 restricts every predefined
    variable kind to inputs, outputs and parameters)."""
    unit = UNITS[model]
    return {s.name: s for s in (*unit.inputs, *unit.outputs)}


def _fmt(x: float) -> str:
    return f"{x:.6g}"


def render(model: str) -> Element:
    """The ``<fmiTerminalsAndIcons>`` of ``model``: the icon over the standard's default
    coordinate system and a terminal per flange of the unit.  BuildError if a member's
    variable has another unit than the member's, or a kind is not one FMI 3.0 defines."""
    root = Element("fmiTerminalsAndIcons", {"fmiVersion": "3.0"})
    graphics = SubElement(root, "GraphicalRepresentation")
    SubElement(graphics, "CoordinateSystem", {
        "x1": _fmt(-EXTENT), "y1": _fmt(-EXTENT), "x2": _fmt(EXTENT), "y2": _fmt(EXTENT),
        "suggestedScalingFactorTo_mm": "0.1"})
    SubElement(graphics, "Icon", {"x1": _fmt(-EXTENT), "y1": _fmt(-EXTENT),
                                  "x2": _fmt(EXTENT), "y2": _fmt(EXTENT)})
    terminals = SubElement(root, "Terminals")
    signals = _signals(model)
    centres = gear_centres()
    for flange in (f for f in FLANGES if f.unit == model):
        terminal = SubElement(terminals, "Terminal", {
            "name": flange.name, "matchingRule": MATCHING_RULE, "terminalKind": TERMINAL_KIND,
            "description": flange.description})
        for m in flange.members:
            spec = signals[m.variable]
            if m.kind not in VARIABLE_KINDS:
                raise BuildError(f"flange {model}.{flange.name}: member {m.member} has the "
                                 f"variable kind {m.kind!r}; allowed: "
                                 f"{', '.join(VARIABLE_KINDS)}")
            if spec.unit != MEMBER_UNITS[m.member]:
                raise BuildError(f"flange {model}.{flange.name}: member {m.member} is "
                                 f"{m.variable} in {spec.unit}; allowed: "
                                 f"{MEMBER_UNITS[m.member]}")
            SubElement(terminal, "TerminalMemberVariable", {
                "variableName": m.variable, "memberName": m.member, "variableKind": m.kind})
        # beside its gear: at the gear centre's height (y up), just outside the icon's edge
        height = round(EXTENT - 2 * EXTENT * centres[flange.name][1] / SIZE)
        x = sorted(SIDES[flange.name] * e for e in (EXTENT, EXTENT + TERMINAL_SIDE))
        SubElement(terminal, "TerminalGraphicalRepresentation", {
            "x1": _fmt(x[0]), "y1": _fmt(height - TERMINAL_SIDE / 2),
            "x2": _fmt(x[1]), "y2": _fmt(height + TERMINAL_SIDE / 2),
            "iconBaseName": FLANGE_ICON})
    return root


def xml_text(model: str) -> str:
    """``terminalsAndIcons.xml`` of ``model``, pretty-printed."""
    text = parseString(ElementTree.tostring(render(model), "unicode")).toprettyxml(
        indent="  ", encoding="UTF-8").decode()
    return "\n".join(line for line in text.splitlines() if line.strip()) + "\n"


def add_terminals_and_icon(archive: zipfile.ZipFile, model: str) -> None:
    """Write ``terminalsAndIcons/`` of ``model`` into the open FMU ``archive``."""
    archive.writestr(TERMINALS_XML, xml_text(model))
    archive.writestr(ICON_PNG, model_png())
    archive.writestr(f"{FOLDER}/{FLANGE_ICON}.png", flange_png())
