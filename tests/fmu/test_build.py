"""The built FMUs: validators, interface completeness, templates, documentation, what they
ship (the model library for linux64, the icon) and their GUIDs."""

import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
from fmpy import read_model_description

from drive_rattle.interface import DRIVELINE_INPUTS, DRIVELINE_OUTPUTS, MESH_INPUTS, MESH_OUTPUTS
from drive_rattle.parameters import specs
from drive_rattle_build import BuildError, build_one, fmu, templates
from drive_rattle_build.documentation import interface_docs
from drive_rattle_build.identity import fmu_guid
from drive_rattle_build.paths import SOURCE, TEST_ONLY_SOURCES

from ..fmi.slave_driver import SLAVES

ROOT = Path(__file__).resolve().parents[2]
INTERFACE = {  # the units' parameters, inputs and outputs
    "GearMeshRattle": (SLAVES["GearMeshRattle"].PARAMETERS, MESH_INPUTS, MESH_OUTPUTS),
    "Driveline": (SLAVES["Driveline"].PARAMETERS, DRIVELINE_INPUTS, DRIVELINE_OUTPUTS),
}


@pytest.mark.parametrize("name", ["GearMeshRattle", "Driveline"])
def test_model_description_is_complete(fmus, name):
    md = read_model_description(str(fmus[name]))
    params, inputs, outputs = INTERFACE[name]
    assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate
    assert float(md.defaultExperiment.stepSize) == 1e-4
    units = {u.name: u for u in md.unitDefinitions}
    by_name = {v.name: v for v in md.modelVariables}
    expected = ([s.name for _, s in specs(params)] + [s.name for s in inputs]
                + [s.name for s in outputs])
    assert [v.name for v in md.modelVariables] == expected
    for v in md.modelVariables:
        assert v.description, v.name
        if v.type == "Real":
            assert v.unit in units, v.name
            if v.displayUnit:
                assert v.displayUnit in [d.name for d in units[v.unit].displayUnits]
    for _, s in specs(params):
        v = by_name[s.name]
        assert v.causality == "parameter" and v.variability == "fixed" and v.initial == "exact"
        if s.fmi_type in ("Real", "Integer") and s.minimum is not None:
            assert float(v.min) == s.minimum and float(v.max) == s.maximum
    # Outputs: no direct feedthrough; all of them initial unknowns.
    out_idx = [md.modelVariables.index(by_name[s.name]) + 1 for s in outputs]
    assert [md.modelVariables.index(u.variable) + 1 for u in md.outputs] == out_idx
    assert all(u.dependencies == [] for u in md.outputs)
    assert [md.modelVariables.index(u.variable) + 1 for u in md.initialUnknowns] == out_idx


@pytest.mark.parametrize("name", ["GearMeshRattle", "Driveline"])
def test_model_description_matches_committed_template(fmus, name):
    from xml.etree import ElementTree

    with zipfile.ZipFile(fmus[name]) as z:
        xml = ElementTree.fromstring(z.read("modelDescription.xml"))
    template = (ROOT / "modelDescription_templates" / f"{name}.xml").read_text(encoding="utf-8")
    assert template.splitlines()[0] == templates.TEMPLATE_NOTE  # says what it is
    assert templates.template_body(template) == templates.normalised_xml(xml), (
        "interface changed: run `python build_fmu.py --update-templates` and review the diff")


@pytest.mark.slow
def test_build_refuses_an_interface_that_differs_from_its_template(tmp_path, monkeypatch):
    fake = tmp_path / "templates"
    fake.mkdir()
    for name in ("GearMeshRattle", "Driveline"):
        text = (ROOT / "modelDescription_templates" / f"{name}.xml").read_text()
        (fake / f"{name}.xml").write_text(text.replace('name="wheel.J"', 'name="wheel.I"'))
    monkeypatch.setattr(templates, "TEMPLATES", fake)
    with pytest.raises(BuildError, match="interface differs"):
        build_one("GearMeshRattle", tmp_path / "out")


def test_the_probes_are_in_the_tests_library_only(fmus, tmp_path):
    """The probes of the laws at given arguments (rm_probe.h) are the tests': the library the
    tests load exports every one the binding knows, the library a pythonfmu FMU ships none
    (looked up as a host would, by name in the loaded library's dynamic symbols)."""
    import ctypes

    from drive_rattle import library

    probes = sorted(library._PROBES)
    assert len(probes) == 9 and all(p.startswith("rm_probe_") for p in probes)
    assert "probe.c" in TEST_ONLY_SOURCES
    tests_library = ctypes.CDLL(str(library.default_path()))
    assert [p for p in probes if not hasattr(tests_library, p)] == []
    with zipfile.ZipFile(fmus["GearMeshRattle"]) as z:
        (tmp_path / "shipped.so").write_bytes(z.read("resources/drive_rattle/rattle_model.so"))
    shipped = ctypes.CDLL(str(tmp_path / "shipped.so"))
    assert hasattr(shipped, "rm_new") and hasattr(shipped, "rm_do_step")
    assert [p for p in probes if hasattr(shipped, p)] == []
    # the binding loads it all the same, without the probes
    assert not hasattr(library.load(tmp_path / "shipped.so"), "rm_probe_loads")


def test_docs_interface_tables_are_generated_from_the_specs():
    text = (ROOT / "docs" / "fmi.md").read_text(encoding="utf-8")
    assert interface_docs(text) == text, (
        "docs/fmi.md is stale: run `python build_fmu.py --update-docs`")


@pytest.mark.parametrize("name", ["GearMeshRattle", "Driveline"])
def test_guid_is_derived_from_the_sources(fmus, name):
    """The same sources give the same GUID (a state saved by one build restores in another);
    the model library's and the face's sources are both in it."""
    guid = read_model_description(str(fmus[name])).guid
    assert guid == fmu.guid(name) == fmu_guid(name, "pythonfmu", fmu.glue_id(name))
    assert guid != fmu.guid("Driveline" if name == "GearMeshRattle" else "GearMeshRattle")
    assert guid != fmu_guid(name, "native", fmu.glue_id(name))
    assert fmu_guid(name, "pythonfmu", "another face") != guid
    sources = fmu.glue_sources(name)
    assert SOURCE / "slaves" / f"{name}.py" in sources
    assert SOURCE / "drive_rattle_fmi" / "slave.py" in sources
    # the status shim refuses another GUID and was compiled with this one
    with zipfile.ZipFile(fmus[name]) as z:
        assert guid.encode() in z.read(f"binaries/linux64/{name}.so")


_LOADED = """
import sys
{prelude}
from fmpy import simulate_fmu
simulate_fmu(sys.argv[1], stop_time=1e-3, output_interval=1e-4)
library = sys.modules["drive_rattle.library"]
print(repr((sys.modules["drive_rattle"].__file__, sorted(library._LOADED))))
"""


@pytest.mark.parametrize("prelude", ["", "import drive_rattle"],
                         ids=["fresh host", "host with the source package"])
def test_the_fmu_runs_its_own_model_library(fmus, prelude):
    """The slave loads the library shipped in its resources, also in a host that imported
    another drive_rattle before (all pythonfmu FMUs of a process share sys.modules)."""
    run = subprocess.run([sys.executable, "-c", _LOADED.format(prelude=prelude),
                          str(fmus["GearMeshRattle"])], capture_output=True, text=True,
                         timeout=300)
    assert run.returncode == 0, run.stderr
    package, loaded = eval(run.stdout.strip().splitlines()[-1])
    own = [p for p in loaded if p.endswith("/resources/drive_rattle/rattle_model.so")]
    assert own, loaded
    if not prelude:
        assert package.endswith("/resources/drive_rattle/__init__.py")


def test_the_cli_builds_the_library_in_place():
    run = subprocess.run([sys.executable, str(ROOT / "build_fmu.py"), "--library"],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    assert "built the model library" in run.stdout
    assert (SOURCE / "drive_rattle" / "rattle_model.so").is_file()


@pytest.mark.slow
def test_a_state_saved_by_one_build_restores_in_another_of_the_same_sources(fmus, tmp_path):
    """The GUID comes from the sources: it was once random per build, and a state saved by one
    build could not be restored by another build of the same sources."""
    from drive_rattle_cosim.harness import Unit

    other = fmu.package(SOURCE / "slaves" / "GearMeshRattle.py", tmp_path, references=False)
    assert read_model_description(str(other)).guid == read_model_description(
        str(fmus["GearMeshRattle"])).guid
    units = [Unit(path, f"u{k}") for k, path in enumerate((fmus["GearMeshRattle"], other))]
    for u in units:
        u.slave.setupExperiment(startTime=0.0)
        u.slave.enterInitializationMode()
        u.set({"pinion.w": 86.92, "wheel.tau_load": 0.15})
        u.slave.exitInitializationMode()
    saver, restorer = units
    vrs = [saver.var(n).vr for n in ("wheel.phi", "wheel.w", "mesh.W")]
    for k in range(10):
        saver.set({"pinion.phi": 86.92 * k * 1e-4})
        saver.slave.doStep(k * 1e-4, 1e-4)
    blob = saver.slave.serializeFMUstate(saver.slave.getFMUstate())
    restorer.slave.setFMUstate(restorer.slave.deSerializeFMUstate(blob))
    for u in units:
        u.set({"pinion.phi": 86.92 * 10 * 1e-4})
        u.slave.doStep(10 * 1e-4, 1e-4)
    assert saver.slave.getReal(vrs) == restorer.slave.getReal(vrs)
    for u in units:
        u.close()
