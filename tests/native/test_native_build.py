"""The native FMUs as the build makes them: the model library and its FMI 2.0 face compiled
together (linux64, win64) with their C sources, an interface rendered from the specs and held
against the committed templates, a GUID derived from the sources, validation by fmpy and
fmu-manipulation-toolbox, and only the fmi2 functions exported."""

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
from drive_rattle_build.native import (
    CONFIG_HEADER,
    FMI_HEADERS,
    GLUE_HEADERS,
    GLUE_SOURCES,
    RESOURCE_MARKER,
    interface_diff,
    model_sources,
    native_guid,
    render_config,
    source_files,
)
from drive_rattle_build.paths import TEST_ONLY_SOURCES
from drive_rattle_cosim.regression import reference_files

#: The functions of the FMI 2.0 co-simulation interface (25 common, 9 co-simulation).
FMI2_CO_SIMULATION_FUNCTIONS = 34


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
        # the one model: the library's sources as they are in the repository
        for path in model_sources():
            assert z.read(f"sources/{path.name}") == path.read_bytes(), path.name
        # the probes of the laws are the tests' (rm_probe.h): not in the FMU's sources
        assert not {f"sources/{name}" for name in TEST_ONLY_SOURCES} & names
        config = z.read(f"sources/{CONFIG_HEADER}").decode()
    # FMI 2.0 importers load binaries/linux64 on aarch64 Linux too (docs/native_fmu.md): no
    # aarch64 binary, and no untested macOS one
    assert {n for n in names if n.startswith("binaries/")} == {
        f"binaries/linux64/{model}.so", f"binaries/win64/{model}.dll"}
    assert not any(n.endswith((".py", ".pyc")) or "pythonfmu" in n for n in names), names
    listed = [f.get("name") for f in md.find("CoSimulation").find("SourceFiles")]
    assert listed == source_files()
    assert set(GLUE_SOURCES) <= set(listed) and "unit.c" in listed and "stepper.c" in listed
    for name in (*listed, *GLUE_HEADERS, *FMI_HEADERS, CONFIG_HEADER, "rattle_model.h"):
        assert f"sources/{name}" in names, name
    assert config == render_config(model, md.get("guid"))


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
