"""The committed C tables of the model library (fmu_src/rattle_model/rm_tables.h, .c) are the
ones the Python specs generate, and the library built from them holds the specs' variables."""

from drive_rattle import DrivelineParameters, MeshParameters, library
from drive_rattle.interface import DRIVELINE_INPUTS, DRIVELINE_OUTPUTS, MESH_INPUTS, MESH_OUTPUTS
from drive_rattle.parameters import specs
from drive_rattle_build import model_tables


def test_the_committed_tables_are_current():
    assert model_tables.is_current(), (
        "fmu_src/rattle_model/rm_tables.[ch] differ from the specs: run drive-rattle-build "
        "--library (it regenerates them) and commit them")


def test_the_library_holds_the_specs_variables_in_order():
    for kind, params, inputs, outputs in ((library.MESH, MeshParameters, MESH_INPUTS,
                                           MESH_OUTPUTS),
                                          (library.DRIVELINE, DrivelineParameters,
                                           DRIVELINE_INPUTS, DRIVELINE_OUTPUTS)):
        table = library.variables(kind)
        expected = ([(s.name, "parameter", s.fmi_type, s.allowed()) for _, s in specs(params)]
                    + [(s.name, "input", s.fmi_type, s.allowed()) for s in inputs]
                    + [(s.name, "output", s.fmi_type, "") for s in outputs])
        assert [(v["name"], v["causality"], v["type"], v["allowed"]) for v in table] == expected
        for v, (_, spec) in zip(table, specs(params), strict=False):
            if spec.fmi_type in ("Real", "Integer", "Boolean"):
                assert v["start"] == float(spec.default), v["name"]
            else:
                assert v["start"] == spec.default
            assert v["min"] == spec.minimum and v["max"] == spec.maximum, v["name"]
