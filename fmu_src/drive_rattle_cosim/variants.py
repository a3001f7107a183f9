"""Copies of an FMU (or of the FMUs inside an SSP) declared for masters that cannot read some
declarations of the original.  Only ``modelDescription.xml`` changes: the binaries, the GUID or
instantiation token (which the binaries check) and the value references stay the FMU's, and the
binaries get and set the variables of a copy with the same calls, so a copy computes what the
FMU computes, bit for bit.

* ``integer_codes``: every Enumeration variable (the integer codes: ``contact.dissipation``,
  ``friction.form``, ...) declared an integer of the same start and limits (FMI 2.0
  ``Integer``, FMI 3.0 ``Int64``: the calls that get and set an Enumeration), its codes and
  item names appended to its description (``code_list``), and no enumeration types.
  libcosim 0.0.6 and ecos 0.7.2 ignore FMI 2.0 Enumeration variables (libcosim: "FMI 2.0
  Enumeration variable type not supported, variable with name ... will be ignored"; ecos: "No
  variable named ... of type int"), and pathsim-fmi 0.1.1 sets none (``Unsupported variable
  type: Enumeration``).  The SSPs that ``ssp.write_ssp`` writes bundle such copies of their
  FMI 2.0 FMUs.
* ``real_outputs``: the integer codes as above, and every output that is not a float (the
  mesh's counters ``mesh.n_contact``, ``mesh.impacts_drive``, ``mesh.impacts_coast``)
  declared a local variable, out of the ModelStructure's outputs and initial unknowns: for
  masters that read every output as a float (pathsim-fmi 0.1.1, which fails at construction
  with ``fmi2GetReal failed with status 3``, FMI 3.0: ``fmi3GetFloat64``).  A local keeps its
  value reference and type, so a master that wants it still reads it.

``python -m drive_rattle_cosim.masters integer-codes|real-outputs SOURCE TARGET`` writes either.
"""

from __future__ import annotations

import io
import zipfile
from collections.abc import Callable, Iterable
from pathlib import Path
from xml.etree import ElementTree

MODEL_DESCRIPTION = "modelDescription.xml"
#: The variable element an Enumeration becomes, per FMI version: the type of the calls that
#: get and set it (FMI 2.0: fmi2Get/SetInteger; FMI 3.0: fmi3Get/SetInt64).
_INTEGER_OF = {"2.0": "Integer", "3.0": "Int64"}
#: The float types of each FMI version (every other output is not a float).
_FLOATS = {"2.0": {"Real"}, "3.0": {"Float64", "Float32"}}


def code_list(items: Iterable[tuple[int, str]]) -> str:
    """``"0 = none, 1 = hunt_crossley_restitution, ..."``: the codes of an enumeration and
    their item names, as the copies' descriptions and the SSD's bindings give them."""
    return ", ".join(f"{value} = {name}" for value, name in sorted(items))


def _version(root: ElementTree.Element) -> str:
    version = root.get("fmiVersion", "")
    key = next((k for k in _INTEGER_OF if version.startswith(k.split(".")[0] + ".")), None)
    if key is None:
        raise ValueError(f"modelDescription of fmiVersion {version!r}; allowed: 2.0 or 3.0")
    return key


def _variables(root: ElementTree.Element, version: str) -> list[tuple]:
    """``(variable, typed)`` of every variable in the modelDescription's order: the element
    holding its name, causality and description, and the element naming its type (FMI 2.0:
    a ScalarVariable and its child; FMI 3.0: the variable twice)."""
    model_variables = root.find("ModelVariables")
    if model_variables is None:
        return []
    if version == "2.0":
        return [(sv, next(iter(sv))) for sv in model_variables.findall("ScalarVariable")]
    return [(v, v) for v in model_variables]


def _enumeration_items(root: ElementTree.Element, version: str) -> dict[str, list[tuple]]:
    """``{type name: [(code, item name), ...]}`` of the modelDescription's enumeration types."""
    types = {}
    for definitions in root.findall("TypeDefinitions"):
        if version == "2.0":
            for simple in definitions.findall("SimpleType"):
                enumeration = simple.find("Enumeration")
                if enumeration is not None:
                    types[simple.get("name")] = [(int(i.get("value")), i.get("name"))
                                                 for i in enumeration.findall("Item")]
        else:
            for enumeration in definitions.findall("EnumerationType"):
                types[enumeration.get("name")] = [(int(i.get("value")), i.get("name"))
                                                  for i in enumeration.findall("Item")]
    return types


def _write(root: ElementTree.Element) -> bytes:
    return (b'<?xml version="1.0" encoding="UTF-8"?>\n'
            + ElementTree.tostring(root, encoding="utf-8", xml_declaration=False) + b"\n")


def _integer_coded(root: ElementTree.Element, version: str) -> None:
    """``root`` with every Enumeration variable an integer, in place (see the module)."""
    items = _enumeration_items(root, version)
    for variable, typed in _variables(root, version):
        if typed.tag != "Enumeration":
            continue
        declared = typed.attrib.pop("declaredType", None)
        typed.attrib.pop("quantity", None)
        typed.tag = _INTEGER_OF[version]
        if declared in items:
            text = variable.get("description", "")
            variable.set("description", f"{text}{' ' if text else ''}"
                                        f"(codes: {code_list(items[declared])})")
    for definitions in root.findall("TypeDefinitions"):
        kind = "SimpleType" if version == "2.0" else "EnumerationType"
        for declared in [d for d in definitions if d.tag == kind and (
                version == "3.0" or d.find("Enumeration") is not None)]:
            definitions.remove(declared)
        if len(definitions) == 0:
            root.remove(definitions)


def integer_coded_model_description(xml: bytes) -> bytes:
    """``xml`` (a modelDescription) with every Enumeration variable declared an integer."""
    root = ElementTree.fromstring(xml)
    _integer_coded(root, _version(root))
    return _write(root)


def real_outputs_model_description(xml: bytes) -> bytes:
    """``xml`` (a modelDescription) with the integer codes declared integers and every output
    that is not a float a local variable, out of the ModelStructure."""
    root = ElementTree.fromstring(xml)
    version = _version(root)
    _integer_coded(root, version)
    # the ModelStructure names a variable by its index (FMI 2.0, from 1) or value reference
    dropped = set()
    for index, (variable, typed) in enumerate(_variables(root, version), 1):
        if variable.get("causality") == "output" and typed.tag not in _FLOATS[version]:
            variable.set("causality", "local")
            dropped.add(str(index) if version == "2.0" else typed.get("valueReference"))
    structure = root.find("ModelStructure")
    if structure is not None and version == "2.0":  # <Outputs>, <InitialUnknowns> of <Unknown>
        for part in list(structure):
            for unknown in [u for u in part if u.get("index") in dropped]:
                part.remove(unknown)
            if len(part) == 0:
                structure.remove(part)  # the schema allows no empty list
    elif structure is not None:  # <Output>, <InitialUnknown>, ... by value reference
        for entry in [e for e in structure if e.tag in ("Output", "InitialUnknown")
                      and e.get("valueReference") in dropped]:
            structure.remove(entry)
    return _write(root)


def fmu_copy(data: bytes, convert: Callable[[bytes], bytes]) -> bytes:
    """The FMU ``data`` (the bytes of an .fmu) with its modelDescription through ``convert``;
    every other member as it was, in the same order.  ValueError if it has no
    modelDescription."""
    buffer = io.BytesIO()
    with zipfile.ZipFile(io.BytesIO(data)) as source, \
            zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as target:
        if MODEL_DESCRIPTION not in source.namelist():
            raise ValueError(f"no {MODEL_DESCRIPTION} in it; allowed: an FMU")
        for info in source.infolist():
            member = source.read(info)
            if info.filename == MODEL_DESCRIPTION:
                member = convert(member)
            target.writestr(info, member)
    return buffer.getvalue()


def _converted(source: Path, convert: Callable[[bytes], bytes]) -> bytes:
    """The bytes of the copy of ``source`` (an .fmu, or an .ssp with every FMU inside
    converted); ValueError naming the file and what is wrong with it."""
    if source.suffix not in (".fmu", ".ssp") or not source.is_file():
        raise ValueError(f"{source} is not an existing .fmu or .ssp file; allowed: an FMU or "
                         "a zipped SSP")
    try:
        if source.suffix == ".fmu":
            return fmu_copy(source.read_bytes(), convert)
        buffer = io.BytesIO()
        with zipfile.ZipFile(source) as ssp, \
                zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as out:
            for info in ssp.infolist():
                member = ssp.read(info)
                if info.filename.endswith(".fmu"):
                    member = fmu_copy(member, convert)
                out.writestr(info, member)
        return buffer.getvalue()
    except zipfile.BadZipFile:
        raise ValueError(f"{source} is not a zip file; allowed: an FMU or a zipped SSP") from None
    except ElementTree.ParseError as err:
        raise ValueError(f"{source}: a modelDescription in it is not XML ({err})") from None
    except ValueError as err:
        raise ValueError(f"{source}: {err}") from None


def _copy(source: Path, target: Path, convert: Callable[[bytes], bytes]) -> Path:
    """``target``: the copy of ``source`` (``_converted``), written whole or not at all."""
    data = _converted(Path(source), convert)
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    part = target.with_name(f".{target.name}.part")
    part.write_bytes(data)
    part.replace(target)
    return target


def integer_codes(source: Path, target: Path) -> Path:
    """A copy of an FMU or SSP file whose integer codes are declared integers (see the
    module), for libcosim and ecos; ``target``."""
    return _copy(source, target, integer_coded_model_description)


def real_outputs(source: Path, target: Path) -> Path:
    """A copy of an FMU (or the FMUs of an SSP) whose outputs are all floats and whose integer
    codes are integers (see the module), for masters that read every output as a float;
    ``target``."""
    return _copy(source, target, real_outputs_model_description)
