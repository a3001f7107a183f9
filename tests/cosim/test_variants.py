"""Copies of the FMUs for masters that cannot read some declarations of the originals
(``drive_rattle_cosim.variants``, ``python -m drive_rattle_cosim.masters integer-codes|
real-outputs``): the same binaries and variables, only those declarations changed, checked
against the specs and validated.  That the copies compute the FMUs' numbers is tested where
they run: libcosim and ecos (test_ssp.py), pathsim-fmi (test_masters.py)."""

import zipfile

import pytest
from fmpy import read_model_description
from fmpy.validation import validate_fmu

from drive_rattle.catalog import UNITS
from drive_rattle.interface import MODELS
from drive_rattle.parameters import specs
from drive_rattle_cosim import variants
from drive_rattle_cosim.masters import main
from drive_rattle_cosim.ssp import SSD_NAME, write_ssp

#: The integer codes of each unit, in the order of its specs.
CODED = {"GearMeshRattle": ["contact.hertz_law", "contact.geometry", "contact.roughness",
                            "contact.dissipation", "tooth.compliance", "friction.form",
                            "friction.shear_speed", "friction.viscous_law", "lubricant.film"],
         "Driveline": ["vehicle.model"]}

#: What the copies leave as it is, per variable.
KEPT = ("valueReference", "variability", "initial", "start", "min", "max", "unit")


def coded(model: str) -> dict[str, str]:
    """``{parameter: "(codes: 0 = ..., 1 = ...)"}`` of the unit's integer codes, from the
    specs' ``choice_names``."""
    return {spec.name: "(codes: " + ", ".join(f"{code} = {name}" for code, name in
                                              sorted(spec.choice_names.items())) + ")"
            for _, spec in specs(UNITS[model].parameters) if spec.choices}


def variables(fmu) -> dict:
    return {v.name: v for v in read_model_description(str(fmu)).modelVariables}


def members(fmu) -> dict[str, bytes]:
    with zipfile.ZipFile(fmu) as z:
        return {name: z.read(name) for name in z.namelist()}


def assert_same_but(original, copy, changed: dict) -> None:
    """Every variable of ``copy`` is that of ``original``, in the same order, but for the
    attributes ``changed`` gives per name (``{name: {attribute: value}}``); every member of
    the FMU but the modelDescription has the same bytes."""
    before, after = variables(original), variables(copy)
    assert list(after) == list(before)
    for name, v in after.items():
        expected = {"type": before[name].type, "causality": before[name].causality,
                    "description": before[name].description, **changed.get(name, {})}
        assert {k: getattr(v, k) for k in expected} == expected, name
        assert [getattr(v, k, None) for k in KEPT] == [getattr(before[name], k, None)
                                                      for k in KEPT], name
    a, b = members(original), members(copy)
    assert list(a) == list(b)
    assert {n for n in a if a[n] != b[n]} == {"modelDescription.xml"}


@pytest.mark.parametrize("model", MODELS)
def test_the_integer_codes_copy_declares_each_code_an_integer_named_by_the_specs(
        model, flavour_fmus, tmp_path):
    original = flavour_fmus[model]
    copy = variants.integer_codes(original, tmp_path / original.name)
    assert validate_fmu(str(copy)) == []
    codes = coded(model)
    assert list(codes) == CODED[model]
    before = variables(original)
    assert {n for n, v in before.items() if v.type == "Enumeration"} == set(codes)
    assert_same_but(original, copy, {name: {"type": "Integer",
                                            "description": f"{before[name].description} {text}"}
                                     for name, text in codes.items()})
    assert b"TypeDefinitions" not in members(copy)["modelDescription.xml"]
    # nothing left to change: a copy of the copy declares the same
    again = variants.integer_codes(copy, tmp_path / "again" / original.name)
    assert members(again)["modelDescription.xml"] == members(copy)["modelDescription.xml"]


@pytest.mark.parametrize("model", MODELS)
def test_the_real_outputs_copy_has_only_real_outputs(model, native_fmus, tmp_path):
    original = native_fmus[model]
    copy = variants.real_outputs(original, tmp_path / original.name)
    assert validate_fmu(str(copy)) == []
    before = variables(original)
    counters = [s.name for s in UNITS[model].outputs if s.fmi_type != "Real"]
    assert counters == (["mesh.n_contact", "mesh.impacts_drive", "mesh.impacts_coast"]
                        if model == "GearMeshRattle" else [])
    changed = {name: {"type": "Integer", "description": f"{before[name].description} {text}"}
               for name, text in coded(model).items()}
    changed.update({name: {"causality": "local"} for name in counters})
    assert_same_but(original, copy, changed)
    md = read_model_description(str(copy))
    reals = [v for v in md.modelVariables if v.causality == "output"]
    assert {v.type for v in reals} == {"Real"}
    assert [u.variable for u in md.outputs] == reals
    assert [u.variable for u in md.initialUnknowns] == reals


def test_the_fmi3_copies_declare_codes_int64_and_only_float_outputs(fmi3_fmus, tmp_path):
    """FMI 3.0 gets and sets an Enumeration with fmi3GetInt64/fmi3SetInt64: the codes become
    Int64 variables; the mesh's Int32 counters become locals, out of the ModelStructure."""
    original = fmi3_fmus["GearMeshRattle"]
    copy = variants.real_outputs(original, tmp_path / original.name)
    assert validate_fmu(str(copy)) == []
    before = variables(original)
    codes = coded("GearMeshRattle")
    changed = {name: {"type": "Int64", "description": f"{before[name].description} {text}"}
               for name, text in codes.items()}
    changed.update({name: {"causality": "local"}
                    for name in ("mesh.n_contact", "mesh.impacts_drive", "mesh.impacts_coast")})
    assert_same_but(original, copy, changed)
    md = read_model_description(str(copy))
    floats = [v for v in md.modelVariables if v.causality == "output"]
    assert {v.type for v in floats} == {"Float64"}
    assert [u.variable for u in md.outputs] == floats


def test_an_ssp_copy_converts_every_fmu_and_nothing_else(fmus, tmp_path):
    ssp = write_ssp(tmp_path / "plain.ssp", fmus["GearMeshRattle"], fmus["Driveline"],
                    integer_codes=False)
    copy = variants.integer_codes(ssp, tmp_path / "copy.ssp")
    assert members(copy)[SSD_NAME] == members(ssp)[SSD_NAME]
    for model in MODELS:
        with zipfile.ZipFile(copy) as z:
            z.extract(f"resources/{model}.fmu", tmp_path / "copy")
        assert {v.type for v in variables(tmp_path / "copy" / "resources" / f"{model}.fmu")
                .values()} == {"Real", "Integer", "Boolean"} | (
            {"String"} if model == "Driveline" else set())


@pytest.mark.parametrize("command", ["integer-codes", "real-outputs"])
def test_the_command_writes_the_copy_or_refuses_in_one_sentence(command, fmus, tmp_path,
                                                                capsys):
    target = tmp_path / "copy" / "GearMeshRattle.fmu"
    assert main([command, str(fmus["GearMeshRattle"]), str(target)]) == 0
    assert capsys.readouterr().out == f"wrote {target}\n"
    assert validate_fmu(str(target)) == []
    not_a_zip = tmp_path / "broken.fmu"
    not_a_zip.write_text("not an FMU")
    for source, message in ((not_a_zip, f"{not_a_zip} is not a zip file; allowed: an FMU or "
                                         "a zipped SSP"),
                            (tmp_path / "missing.fmu", "is not an existing .fmu or .ssp file"),
                            (fmus["GearMeshRattle"].with_suffix(".txt"),
                             "is not an existing .fmu or .ssp file")):
        with pytest.raises(SystemExit) as exit_:
            main([command, str(source), str(tmp_path / "refused.fmu")])
        assert exit_.value.code == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1 and "Traceback" not in err
    assert not (tmp_path / "refused.fmu").exists()
