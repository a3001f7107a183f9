"""The native FMUs as the build makes them: the model library and its FMI 2.0 face compiled
together (linux64, win64) with their C sources, an interface rendered from the specs and held
against the committed templates, a GUID derived from the sources, validation by fmpy and
fmu-manipulation-toolbox, and only the fmi2 functions exported."""

from __future__ import annotations

import re
import shutil
import subprocess
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import pytest

from drive_rattle.interface import MODELS
from drive_rattle_build.native import (
    interface_diff,
    native_guid,
)

#: The functions of the FMI 2.0 co-simulation interface (25 common, 9 co-simulation).
FMI2_CO_SIMULATION_FUNCTIONS = 34


def description(fmu: Path) -> ElementTree.Element:
    with zipfile.ZipFile(fmu) as z:
        return ElementTree.fromstring(z.read("modelDescription.xml"))


@pytest.mark.parametrize("model", MODELS)
def test_interface_is_the_templates(native_fmus, model):
    """Same variables, value references, types, causalities, units, limits, starts and
    structure as the committed template (the pythonfmu FMU's); only the GUID, the generation
    tool, needsExecutionTool and the source files are the native flavour's own."""
    md = description(native_fmus[model])
    assert interface_diff(model, md) == []
    assert md.find("CoSimulation").get("needsExecutionTool") == "false"
    assert "native C" in md.get("generationTool")


def test_guid_from_the_sources(native_fmus):
    """The GUID is derived from the model, the flavour and the sources (library and glue):
    every build of the same sources has it, so a state saved by one restores in another."""
    guids = {model: description(native_fmus[model]).get("guid") for model in MODELS}
    assert guids == {model: native_guid(model) for model in MODELS}
    assert len(set(guids.values())) == len(MODELS)
    assert all(re.fullmatch(r"\{[0-9a-f-]{36}\}", g) for g in guids.values())


def _tool(name: str) -> str:
    path = shutil.which(name)
    if path is None:
        pytest.skip(f"{name} (binutils) is not installed")
    return path


@pytest.mark.parametrize("model", MODELS)
def test_linux64_binary_exports_only_fmi2_and_needs_only_libc(native_fmus, model, tmp_path):
    with zipfile.ZipFile(native_fmus[model]) as z:
        binary = tmp_path / f"{model}.so"
        binary.write_bytes(z.read(f"binaries/linux64/{model}.so"))
    dynamic = subprocess.run([_tool("readelf"), "-d", "-W", str(binary)], capture_output=True,
                             text=True, check=True).stdout
    needed = set(re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]", dynamic))
    assert needed and needed <= {"libc.so.6", "libm.so.6"}, needed
    symbols = subprocess.run([_tool("nm"), "-D", "--defined-only", str(binary)],
                             capture_output=True, text=True, check=True).stdout
    exported = {line.split()[-1] for line in symbols.splitlines() if line.strip()}
    assert {"fmi2Instantiate", "fmi2DoStep", "fmi2SerializeFMUstate"} <= exported
    # the library (rm_*) and the glue's helpers (rattle_*) stay inside
    assert all(name.startswith("fmi2") for name in exported), sorted(exported)
    assert len(exported) == FMI2_CO_SIMULATION_FUNCTIONS


@pytest.mark.parametrize("model", MODELS)
def test_win64_binary_exports_only_fmi2_and_imports_only_the_c_runtime(native_fmus, model,
                                                                         tmp_path):
    with zipfile.ZipFile(native_fmus[model]) as z:
        binary = tmp_path / f"{model}.dll"
        binary.write_bytes(z.read(f"binaries/win64/{model}.dll"))
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
    assert all(name.startswith("fmi2") for name in exported), sorted(exported)
    assert len(exported) == FMI2_CO_SIMULATION_FUNCTIONS
