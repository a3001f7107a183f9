"""The FMI 3.0 FMUs as the build makes them: the model library and its FMI 3.0 face compiled
together (x86_64-linux, x86_64-windows, aarch64-linux; no macOS binary, which nothing here
can run) with their C sources, buildDescription.xml and terminalsAndIcons/, an
interface rendered from the same specs as the FMI 2.0 FMUs' (the same variables at the same
value references, the same causality, variability, units, limits and starts; the integer codes
as Enumerations with named items; the independent variable time), held against the committed
templates, a token from the GUID scheme, validation by fmpy and fmu-manipulation-toolbox, and
only (and all) the fmi3 functions exported."""

from __future__ import annotations

import re
import shutil
import subprocess
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import pytest

from drive_rattle.catalog import UNITS
from drive_rattle.interface import MODELS
from drive_rattle.parameters import specs
from drive_rattle_build import model_description
from drive_rattle_build.fmi3 import (
    fmi3_headers,
    fmi3_token,
    normalised_xml,
    template_path,
)
from drive_rattle_build.native import (
    native_guid,
)
from drive_rattle_build.templates import template_body


def description(fmu: Path) -> ElementTree.Element:
    with zipfile.ZipFile(fmu) as z:
        return ElementTree.fromstring(z.read("modelDescription.xml"))


def header_functions() -> list[str]:
    """The functions fmi3Functions.h declares (every one an FMU binary must export)."""
    text = (fmi3_headers() / "fmi3Functions.h").read_text(encoding="utf-8")
    return re.findall(r"^FMI3_Export\s+\w+TYPE\s+(fmi3\w+);", text, re.M)


@pytest.mark.parametrize("model", MODELS)
def test_interface_is_the_fmi2_interface(fmi3_fmus, model):
    """Every variable of the FMI 2.0 modelDescription (rendered from the same specs) is in
    the FMI 3.0 one with the same value reference, description, causality, variability,
    initial, unit, display unit, limits and start; the types map Real -> Float64, Integer ->
    Int32 or (with choices) Enumeration; time is added; the structure is the same."""
    fmi2 = model_description.render(model, "{G}", "tool", needs_execution_tool=False)
    md = description(fmi3_fmus[model])
    mine = {v.get("name"): v for v in md.find("ModelVariables")}
    choices = {s.name: s.choices for _, s in specs(UNITS[model].parameters) if s.choices}
    type_of = {e.get("name"): e for e in md.find("TypeDefinitions") or []}
    for sv in fmi2.find("ModelVariables"):
        name, typed = sv.get("name"), next(iter(sv))
        v = mine.pop(name)
        for attr in ("valueReference", "description", "causality", "variability", "initial"):
            assert v.get(attr) == sv.get(attr), (name, attr)
        if typed.tag == "Enumeration":  # the FMI 2.0 type, item for item
            assert name in choices
            declared = typed.get("declaredType")
            assert v.tag == "Enumeration" and v.get("declaredType") == declared
            items = [(i.get("name"), int(i.get("value")), i.get("description"))
                     for i in type_of[declared]]
            fmi2_type = next(t for t in fmi2.find("TypeDefinitions") if t.get("name") == declared)
            assert items == [(i.get("name"), int(i.get("value")), i.get("description"))
                             for i in fmi2_type.find("Enumeration")]
            assert [i[1] for i in items] == sorted(choices[name])
        else:
            assert v.tag == {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean",
                             "String": "String"}[typed.tag], name
        for attr in ("unit", "displayUnit", "min", "max"):
            if v.tag != "Enumeration":
                assert v.get(attr) == typed.get(attr), (name, attr)
        start = (v.find("Start").get("value") if v.find("Start") is not None
                 else v.get("start"))
        assert start == typed.get("start"), name
    assert list(mine) == ["time"]
    assert mine["time"].attrib == {
        "name": "time", "valueReference": str(len(fmi2.find("ModelVariables"))),
        "description": "simulation time (the independent variable)",
        "causality": "independent", "variability": "continuous", "unit": "s"}
    outputs2 = [int(u.get("index")) - 1 for u in fmi2.find("ModelStructure/Outputs")]
    structure = md.find("ModelStructure")
    assert [int(u.get("valueReference")) for u in structure.findall("Output")] == outputs2
    assert all(u.get("dependencies") == "" for u in structure.findall("Output"))
    assert [int(u.get("valueReference")) for u in structure.findall("InitialUnknown")] == \
        outputs2
    for attr in ("modelName", "description", "author", "version", "license",
                 "variableNamingConvention"):
        assert md.get(attr) == fmi2.get(attr)
    assert md.find("DefaultExperiment").attrib == fmi2.find("DefaultExperiment").attrib
    cosim = md.find("CoSimulation").attrib
    assert cosim["hasEventMode"] == cosim["mightReturnEarlyFromDoStep"] == "false"
    assert cosim["providesIntermediateUpdate"] == "false"
    assert cosim["canGetAndSetFMUState"] == cosim["canSerializeFMUState"] == "true"


@pytest.mark.parametrize("model", MODELS)
def test_interface_is_the_committed_template(fmi3_fmus, model):
    text = template_body(template_path(model).read_text(encoding="utf-8"))
    assert text == normalised_xml(description(fmi3_fmus[model]))


def test_token_from_the_sources(fmi3_fmus):
    """The token is the GUID scheme's (model, flavour, sources): every build of the same
    sources has it, and it is not the FMI 2.0 FMU's (their states are told apart)."""
    tokens = {m: description(fmi3_fmus[m]).get("instantiationToken") for m in MODELS}
    assert tokens == {m: fmi3_token(m) for m in MODELS}
    assert len(set(tokens.values())) == len(MODELS)
    assert all(re.fullmatch(r"\{[0-9a-f-]{36}\}", t) for t in tokens.values())
    assert not set(tokens.values()) & {native_guid(m) for m in MODELS}


def _tool(name: str) -> str:
    path = shutil.which(name)
    if path is None:
        pytest.skip(f"{name} (binutils) is not installed")
    return path


@pytest.mark.parametrize("platform, machine", [("x86_64-linux", "Advanced Micro Devices X86-64"),
                                               ("aarch64-linux", "AArch64")])
@pytest.mark.parametrize("model", MODELS)
def test_linux_binary_exports_every_fmi3_function_and_needs_only_libc(fmi3_fmus, model,
                                                                      platform, machine,
                                                                      tmp_path):
    with zipfile.ZipFile(fmi3_fmus[model]) as z:
        binary = tmp_path / f"{model}.so"
        binary.write_bytes(z.read(f"binaries/{platform}/{model}.so"))
    header = subprocess.run([_tool("readelf"), "-h", str(binary)], capture_output=True,
                            text=True, check=True).stdout
    assert re.search(rf"Machine:\s+{machine}\n", header), header
    dynamic = subprocess.run([_tool("readelf"), "-d", "-W", str(binary)], capture_output=True,
                             text=True, check=True).stdout
    needed = set(re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]", dynamic))
    assert needed and needed <= {"libc.so.6", "libm.so.6"}, needed
    if platform == "aarch64-linux":  # docs/fmi3.md: glibc 2.29 or later (ziglang's default)
        versions = subprocess.run([_tool("readelf"), "-V", "-W", str(binary)],
                                  capture_output=True, text=True, check=True).stdout
        assert max(tuple(map(int, v.split("."))) for v in re.findall(
            r"Name: GLIBC_([0-9.]+)", versions)) == (2, 29)
    symbols = subprocess.run([_tool("nm"), "-D", "--defined-only", str(binary)],
                             capture_output=True, text=True, check=True).stdout
    exported = {line.split()[-1] for line in symbols.splitlines() if line.strip()}
    functions = header_functions()
    assert len(functions) == 75  # FMI 3.0's API
    assert exported == set(functions), sorted(exported ^ set(functions))


@pytest.mark.parametrize("model", MODELS)
def test_windows_binary_exports_every_fmi3_function_and_imports_only_the_c_runtime(
        fmi3_fmus, model, tmp_path):
    with zipfile.ZipFile(fmi3_fmus[model]) as z:
        binary = tmp_path / f"{model}.dll"
        binary.write_bytes(z.read(f"binaries/x86_64-windows/{model}.dll"))
    headers = subprocess.run([_tool("objdump"), "-p", str(binary)], capture_output=True,
                             text=True)
    if headers.returncode != 0:
        pytest.skip(f"objdump cannot read PE files here: {headers.stderr.strip()}")
    assert "pei-x86-64" in headers.stdout
    imported = {d.lower() for d in re.findall(r"DLL Name: (\S+)", headers.stdout)}
    assert imported and all(d.startswith("api-ms-win-crt-") or d in ("kernel32.dll",
                                                                    "msvcrt.dll")
                            for d in imported), imported
    table = headers.stdout.split("[Ordinal/Name Pointer] Table")[1].split("\n\n")[0]
    exported = set(re.findall(r"\]\s+(\w+)", table))
    assert exported == set(header_functions())
