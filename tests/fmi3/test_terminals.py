"""terminalsAndIcons/ of the FMI 3.0 FMUs (drive_rattle_build/terminals.py): valid against the
official FMI 3.0 schema (fmi3TerminalsAndIcons.xsd, as fmpy ships it); the icon of the FMI 2.0
FMUs; one terminal per shaft, whose members are variables of the FMU with the units of the
Modelica Standard Library's rotational signal adaptors (phi rad, w rad/s, a rad/s2, tau N.m),
drawn with an image the FMU ships; and the two units' terminals, connected by member name as
FMI 3.0's "bus" rule says, give the system's connections (``interface.CONNECTIONS``), each an
output to an input, the torques' flows in opposite senses."""

from __future__ import annotations

import zipfile
from pathlib import Path

import fmpy
import pytest
from fmpy import read_model_description
from lxml import etree

from drive_rattle.interface import CONNECTIONS, MODELS, Connection

SCHEMA = Path(fmpy.__file__).parent / "schema" / "fmi3" / "fmi3TerminalsAndIcons.xsd"
TERMINALS = "terminalsAndIcons/terminalsAndIcons.xml"
#: Modelica.Mechanics.Rotational.Components.GeneralAngleToTorqueAdaptor: the member names and
#: units of a rotational flange as signals.
ADAPTOR_UNITS = {"phi": "rad", "w": "rad/s", "a": "rad/s2", "tau": "N.m"}


def terminals_xml(fmu: Path) -> etree._Element:
    with zipfile.ZipFile(fmu) as z:
        return etree.fromstring(z.read(TERMINALS))


def terminals_of(fmu: Path) -> dict[str, dict[str, tuple[str, str]]]:
    """{terminal: {member: (variable, kind)}}."""
    root = terminals_xml(fmu)
    return {t.get("name"): {m.get("memberName"): (m.get("variableName"), m.get("variableKind"))
                            for m in t.findall("TerminalMemberVariable")}
            for t in root.find("Terminals")}


@pytest.mark.parametrize("model", MODELS)
def test_valid_against_the_fmi3_schema(fmi3_fmus, model):
    schema = etree.XMLSchema(etree.parse(str(SCHEMA)))
    root = terminals_xml(fmi3_fmus[model])
    assert schema.validate(root), schema.error_log
    assert root.get("fmiVersion") == read_model_description(str(fmi3_fmus[model])).fmiVersion
    # the check has teeth: a terminal without its required matching rule is refused
    del root.find("Terminals/Terminal").attrib["matchingRule"]
    assert not schema.validate(root)


@pytest.mark.parametrize("model", MODELS)
def test_one_terminal_per_shaft_of_the_fmus_variables(fmi3_fmus, model):
    fmu = fmi3_fmus[model]
    variables = {v.name: v for v in read_model_description(str(fmu)).modelVariables}
    root = terminals_xml(fmu)
    with zipfile.ZipFile(fmu) as z:
        names = set(z.namelist())
    terminals = root.find("Terminals")
    assert [t.get("name") for t in terminals] == ["pinion", "wheel"]
    for terminal in terminals:
        assert terminal.get("matchingRule") == "bus"
        members = terminal.findall("TerminalMemberVariable")
        assert len({m.get("memberName") for m in members}) == len(members)  # unique
        assert {"phi", "w"} <= {m.get("memberName") for m in members}
        for m in members:
            v = variables[m.get("variableName")]
            assert v.causality in ("input", "output")
            assert v.unit == ADAPTOR_UNITS[m.get("memberName")], (v.name, v.unit)
            # FMI 3.0's kinds: a torque sums to zero at a connection, the motion is equal
            assert m.get("variableKind") in (("inflow", "outflow") if m.get("memberName") ==
                                             "tau" else ("signal",))
        picture = terminal.find("TerminalGraphicalRepresentation")
        assert f"terminalsAndIcons/{picture.get('iconBaseName')}.png" in names


@pytest.mark.parametrize("model", MODELS)
def test_the_icon_is_the_fmi2_fmus_icon(fmi3_fmus, native_fmus, model):
    with zipfile.ZipFile(fmi3_fmus[model]) as z3, zipfile.ZipFile(native_fmus[model]) as z2:
        icon = z3.read("terminalsAndIcons/icon.png")
        assert icon == z2.read("model.png")
    assert icon.startswith(b"\x89PNG\r\n\x1a\n")


def test_connected_by_member_name_the_terminals_give_the_systems_connections(fmi3_fmus):
    """A tool that connects each shaft's terminal of one unit to the same shaft's of the other
    and matches the members by name (FMI 3.0's "bus" rule: members present on one side only
    stay unconnected) makes exactly the system's connections: an output to an input each,
    and the torque's flow into one unit the flow out of the other."""
    causality = {m: {v.name: v.causality
                     for v in read_model_description(str(fmi3_fmus[m])).modelVariables}
                 for m in MODELS}
    terminals = {m: terminals_of(fmi3_fmus[m]) for m in MODELS}
    first, second = MODELS
    made = set()
    for shaft, members in terminals[first].items():
        other = terminals[second][shaft]
        for member in members.keys() & other.keys():
            ends = [(first, *members[member]), (second, *other[member])]
            kinds = {kind for _, _, kind in ends}
            assert kinds in ({"signal"}, {"inflow", "outflow"}), (shaft, member, kinds)
            (src, out, _), = [e for e in ends if causality[e[0]][e[1]] == "output"]
            (dst, inp, _), = [e for e in ends if causality[e[0]][e[1]] == "input"]
            made.add(Connection(src, out, dst, inp))
    assert made == set(CONNECTIONS)
