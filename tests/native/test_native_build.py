"""The native FMUs as built by build_fmu.py: their contents, an interface identical to the
pythonfmu FMUs', validation by fmpy and fmu-manipulation-toolbox, and nothing of Python in
their binaries."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import pytest
from fmpy.validation import validate_fmu

from drive_rattle.interface import MODELS
from drive_rattle_build.native import C_SOURCES, FMI_HEADERS, HEADERS, RESOURCE_MARKER, interface_of
from drive_rattle_build.templates import normalised_xml
from drive_rattle_cosim.regression import reference_files


def description(fmu: Path) -> ElementTree.Element:
    with zipfile.ZipFile(fmu) as z:
        return ElementTree.fromstring(z.read("modelDescription.xml"))


@pytest.mark.parametrize("model", MODELS)
def test_contents(native_fmus, model):
    with zipfile.ZipFile(native_fmus[model]) as z:
        names = set(z.namelist())
        md = ElementTree.fromstring(z.read("modelDescription.xml"))
        assert z.read(f"resources/{RESOURCE_MARKER}").decode() == f"{model}\n"
        for ref in reference_files(model):
            assert z.read(f"resources/regression/{ref.name}") == ref.read_bytes()
        assert b"no Python" in z.read("documentation/index.html")
    assert {f"binaries/linux64/{model}.so", f"binaries/win64/{model}.dll"} <= names
    assert not any(n.endswith((".py", ".pyc")) or "pythonfmu" in n for n in names), names
    listed = [f.get("name") for f in md.find("CoSimulation").find("SourceFiles")]
    assert listed == list(C_SOURCES)
    for name in (*C_SOURCES, *HEADERS, *FMI_HEADERS):
        assert f"sources/{name}" in names, name
    guid = md.get("guid")
    with zipfile.ZipFile(native_fmus[model]) as z:  # the GUID is compiled into the sources
        assert guid.encode() in z.read("sources/rattle_native_tables.h")


@pytest.mark.parametrize("model", MODELS)
def test_interface_is_the_pythonfmu_fmus(native_fmus, fmus, model):
    """Same variables, value references, types, causalities, units, limits, starts and
    structure as the pythonfmu FMU; only the GUID, the generation tool, needsExecutionTool and
    the source files differ."""
    native, python = description(native_fmus[model]), description(fmus[model])
    assert normalised_xml(interface_of(native, python)) == normalised_xml(python)
    assert native.get("guid") != python.get("guid")
    assert native.find("CoSimulation").get("needsExecutionTool") == "false"
    assert python.find("CoSimulation").get("needsExecutionTool") == "true"
    assert "native C" in native.get("generationTool")


@pytest.mark.parametrize("model", MODELS)
def test_validated_by_fmpy_and_fmutool(native_fmus, model):
    assert validate_fmu(str(native_fmus[model])) == []
    tool = shutil.which("fmutool") or Path(sys.executable).with_name("fmutool")
    if not Path(tool).exists():
        pytest.skip("fmu-manipulation-toolbox (fmutool) is not installed")
    run = subprocess.run([str(tool), "-input", str(native_fmus[model]), "-check"],
                         capture_output=True, text=True, timeout=300)
    report = run.stdout + run.stderr
    assert run.returncode == 0 and "ERROR" not in report, report


def _tool(name: str) -> str:
    path = shutil.which(name)
    if path is None:
        pytest.skip(f"{name} (binutils) is not installed")
    return path


@pytest.mark.parametrize("model", MODELS)
def test_linux64_binary_needs_only_the_c_library(native_fmus, model, tmp_path):
    with zipfile.ZipFile(native_fmus[model]) as z:
        binary = tmp_path / f"{model}.so"
        binary.write_bytes(z.read(f"binaries/linux64/{model}.so"))
    dynamic = subprocess.run([_tool("readelf"), "-d", "-W", str(binary)], capture_output=True,
                             text=True, check=True).stdout
    needed = set(re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]", dynamic))
    assert needed and needed <= {"libc.so.6", "libm.so.6"}, needed
    symbols = subprocess.run([_tool("nm"), "-D", str(binary)], capture_output=True, text=True,
                             check=True).stdout
    undefined = [line.split()[-1] for line in symbols.splitlines() if " U " in line]
    assert not [s for s in undefined if s.startswith(("Py", "_Py"))], undefined
    exported = {line.split()[-1] for line in symbols.splitlines() if " T " in line}
    assert {"fmi2Instantiate", "fmi2DoStep", "fmi2SerializeFMUstate"} <= exported


@pytest.mark.parametrize("model", MODELS)
def test_win64_binary_imports_only_the_c_runtime_and_kernel(native_fmus, model, tmp_path):
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
    assert "fmi2Instantiate" in headers.stdout and "fmi2DoStep" in headers.stdout
