"""The FMUs of every face as the build makes them: what each ships (binaries, resources,
documentation, sources) and validation by fmpy and fmu-manipulation-toolbox."""

from __future__ import annotations

import shutil
import subprocess
import sys
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import pytest
from fmpy.validation import validate_fmu

from drive_rattle.interface import (
    DRIVELINE_INPUTS,
    DRIVELINE_OUTPUTS,
    MESH_INPUTS,
    MESH_OUTPUTS,
    MODELS,
)
from drive_rattle_build import native
from drive_rattle_build.fmi3 import FMI_HEADERS as FMI3_HEADERS
from drive_rattle_build.fmi3 import fmi3_headers
from drive_rattle_build.fmi3 import source_files as fmi3_source_files
from drive_rattle_build.icon import model_png
from drive_rattle_build.paths import RUNTIME_PACKAGES, SOURCE, TEST_ONLY_SOURCES
from drive_rattle_cosim.regression import reference_files

#: the binaries each face ships, by model ({m})
BINARIES = {
    "pythonfmu": {"binaries/linux64/{m}.so", "binaries/linux64/{m}_pythonfmu.so"},
    # FMI 2.0 importers load binaries/linux64 on aarch64 Linux too (docs/native_fmu.md): no
    # aarch64 binary, and no untested macOS one
    "native": {"binaries/linux64/{m}.so", "binaries/win64/{m}.dll"},
    "fmi3": {"binaries/x86_64-linux/{m}.so", "binaries/x86_64-windows/{m}.dll",
             "binaries/aarch64-linux/{m}.so"},
}
INTERFACE = {"GearMeshRattle": (MESH_INPUTS, MESH_OUTPUTS),
             "Driveline": (DRIVELINE_INPUTS, DRIVELINE_OUTPUTS)}


def pythonfmu_contents(z, names, page, md, model):
    """The shim, pythonfmu's binary, the slave and the runtime packages whole, with the
    compiled model library next to the binding, and nothing else of the sources."""
    assert f"resources/{model}.py" in names
    shipped = {n.removeprefix("resources/") for n in names
               if n.startswith("resources/drive_rattle")}
    sources = {str(p.relative_to(SOURCE)) for package in RUNTIME_PACKAGES
               for p in (SOURCE / package).glob("*.py")}
    assert "drive_rattle/library.py" in sources and "drive_rattle_fmi/slave.py" in sources
    assert shipped == sources | {"drive_rattle/rattle_model.so"}
    assert z.read("resources/drive_rattle/rattle_model.so")[:4] == b"\x7fELF"
    # pythonfmu's generic win64 binary (no shim; it needs an installed Windows Python and the
    # VC++ runtime) is not shipped, and the FMU says to use the native one
    assert not any(n.endswith(".dll") for n in names)
    assert f"dist/native/{model}.fmu" in page and "Windows" in page
    assert z.read("model.png") == model_png()  # the icon (FMI 2.0: model.png at the root)
    inputs, outputs = INTERFACE[model]
    for s in (*inputs, *outputs):
        assert f"<td>{s.name}</td>" in page


def native_contents(z, names, page, md, model):
    """The model library's and the FMI 2.0 face's sources, listed in <SourceFiles>."""
    assert "no Python" in page
    listed = [f.get("name") for f in md.find("CoSimulation").find("SourceFiles")]
    assert listed == native.source_files()
    assert set(native.GLUE_SOURCES) <= set(listed) and "unit.c" in listed and \
        "stepper.c" in listed
    for name in (*listed, *native.GLUE_HEADERS, *native.FMI_HEADERS, native.CONFIG_HEADER,
                 "rattle_model.h"):
        assert f"sources/{name}" in names, name
    assert z.read(f"sources/{native.CONFIG_HEADER}").decode() == native.render_config(
        model, md.get("guid"))


def fmi3_contents(z, names, page, md, model):
    """The model library's and the FMI 3.0 face's sources, listed in buildDescription.xml,
    the standard's headers as fmpy ships them, terminalsAndIcons/."""
    assert "FMI 3.0 co-simulation" in page and "fmi2" not in page
    for name in FMI3_HEADERS:
        assert z.read(f"sources/{name}") == (fmi3_headers() / name).read_bytes()
    assert {"sources/buildDescription.xml", "terminalsAndIcons/terminalsAndIcons.xml",
            "terminalsAndIcons/icon.png"} <= names
    assert not any("linux64" in n for n in names), names
    assert md.find("CoSimulation").find("SourceFiles") is None  # FMI 3.0: buildDescription
    for name in fmi3_source_files():
        assert f"sources/{name}" in names
    assert z.read(f"sources/{native.CONFIG_HEADER}").decode() == native.render_config(
        model, md.get("instantiationToken"), "fmi3_functions.c")


CONTENTS = {"pythonfmu": pythonfmu_contents, "native": native_contents, "fmi3": fmi3_contents}


@pytest.mark.cross
@pytest.mark.parametrize("model", MODELS)
def test_a_binary_for_every_shipped_platform(face, shipped_face_fmus, model):
    with zipfile.ZipFile(shipped_face_fmus[model]) as z:
        assert {n for n in z.namelist() if n.startswith("binaries/")} == {
            b.format(m=model) for b in BINARIES[face.name]}


@pytest.mark.parametrize("model", MODELS)
def test_contents(face, face_fmus, model):
    with zipfile.ZipFile(face_fmus[model]) as z:
        names = set(z.namelist())
        md = ElementTree.fromstring(z.read("modelDescription.xml"))
        page = z.read("documentation/index.html").decode()
        assert f"binaries/{face.linux}/{model}.so" in names
        CONTENTS[face.name](z, names, page, md, model)
        if face.native:
            # C only, with the regression references and the marker of its resources
            assert not any(n.endswith((".py", ".pyc")) or "pythonfmu" in n for n in names), \
                names
            assert z.read(f"resources/{native.RESOURCE_MARKER}").decode() == f"{model}\n"
            for ref in reference_files(model):
                assert z.read(f"resources/regression/{ref.name}") == ref.read_bytes()
            # the one model: the library's sources as they are in the repository
            for path in native.model_sources():
                assert z.read(f"sources/{path.name}") == path.read_bytes(), path.name
            # the probes of the laws are the tests' (rm_probe.h): not in the FMU's sources
            assert not {f"sources/{name}" for name in TEST_ONLY_SOURCES} & names


@pytest.mark.parametrize("model", MODELS)
def test_validated_by_fmpy_and_fmutool(face, face_fmus, model):
    assert validate_fmu(str(face_fmus[model])) == []
    tool = shutil.which("fmutool") or Path(sys.executable).with_name("fmutool")
    if not Path(tool).exists():
        pytest.skip("fmu-manipulation-toolbox (fmutool) is not installed")
    run = subprocess.run([str(tool), "-input", str(face_fmus[model]), "-check"],
                         capture_output=True, text=True, timeout=300)
    report = run.stdout + run.stderr
    assert run.returncode == 0 and "ERROR" not in report, report
    assert ("No semantic error" if face.standard == "2.0" else "compliant with FMI-3.0") in \
        report, report
