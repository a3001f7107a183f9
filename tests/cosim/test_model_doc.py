"""docs/model.md's numbers as a reader meets them: every ``<!-- BEGIN name -->`` block equals
what ``drive_rattle_cosim.model_doc`` computes now (``python -m drive_rattle_cosim.model_doc
--update`` rewrites them).  The closed forms at the defaults (``doc_constants``) are checked
whole here, with the sentences around them that their values decide; the runs (``doc_runs``)
in the slow layer: the contact options' block (seven 11 s runs of the compiled loop), the
findings' sentences on short runs, and every other block of the document once."""

import math
import re
from pathlib import Path

import pytest

from drive_rattle_cosim import doc_constants, doc_runs, model_doc

ROOT = Path(__file__).resolve().parents[2]
TEXT = (ROOT / "docs" / "model.md").read_text(encoding="utf-8")
#: A short horizon: two windows of 0.5 s after 0.3 s.
SHORT = {"stop_time": 1.3, "transient": 0.3, "window": 0.5}


def test_the_document_holds_every_block_once():
    names = re.findall(r"<!-- BEGIN ([^>]+?) -->", TEXT)
    assert sorted(names) == sorted(model_doc.BLOCKS)


@pytest.mark.slow
def test_the_contact_options_are_a_fresh_runs():
    assert model_doc.stale(TEXT, ["contact options", "contact findings"]) == [], (
        "docs/model.md section 3.6 is stale: run `python -m drive_rattle_cosim.model_doc "
        "--update` and review the diff")


def test_the_single_impacts_table_is_a_fresh_runs():
    assert model_doc.stale(TEXT, ["single impacts"]) == [], (
        "docs/model.md section 3.3's single impacts are stale: run `python -m "
        "drive_rattle_cosim.model_doc --update --only 'single impacts'`")


def test_the_dissipation_constants_are_the_librarys():
    assert model_doc.stale(TEXT, ["dissipation constants"]) == [], (
        "docs/model.md section 3.3's constants of the dissipation laws are stale: run `python "
        "-m drive_rattle_cosim.model_doc --update --only 'dissipation constants'`")
    text = doc_constants.dissipation_constants()
    # the defaults' critical speed sits where the band's low and high cases bracket it, the
    # flooded film's far above it (phi enters v_c linearly: 1/0.03 times)
    central, low, high, flooded = (float(x) for x in re.search(
        r"v_c = (\S+) mm/s at the defaults.*? from (\S+) mm/s .*? to (\S+) mm/s .*?"
        r"flooded \(φ = 1\) (\S+) mm/s", text).groups())
    assert low < central < high < flooded
    assert flooded / central == pytest.approx(1 / 0.03, rel=1e-2)


@pytest.mark.slow
def test_the_constants_of_the_defaults_are_the_librarys():
    """Every closed-form block -- the reference pair's geometry, the contact laws and ellipses,
    the static loads and approaches of the contact models, the film and friction at those
    loads, the vehicle mode and its damping, the separation load -- is the library's value
    at the defaults now."""
    assert model_doc.stale(TEXT, list(model_doc.CONSTANT_BLOCKS)) == [], (
        "docs/model.md's constants of the defaults are stale: run `python -m "
        "drive_rattle_cosim.model_doc --update` and review the diff")
    # the offset's torque is the shaft stiffness times the offset angle, as the text says
    mrad, mnm = (float(x) for x in re.search(
        r"k × (\S+) mrad = (\S+) mN·m", doc_constants.start_offset()).groups())
    from drive_rattle import DrivelineParameters

    assert mnm == pytest.approx(DrivelineParameters().k_shaft * mrad, rel=0.02)


def _half_line() -> float:
    return float(re.search(r"= (\S+) mm", doc_constants.half_lines())[1]) * 1e-3


def test_the_ellipses_are_short_against_the_contact_lines():
    """Sections 2.1 and 3.1: the point-contact laws hold because the contact ellipse is far
    inside the engaged lines' half-length, for the paper's ellipsoids at 5 N and the crowned
    default at 10 N."""
    paper = [r["law"]["ka"] * doc_constants.PAPER_ELLIPSE_LOAD ** (1 / 3)
             for r in doc_constants.loaded_pairs(doc_constants.PAPER)]
    crowned = [r["law"]["ka"] * doc_constants.CROWNED_ELLIPSE_LOAD ** (1 / 3)
               for rows in doc_constants.static_pairs() for r in rows]
    half = _half_line()
    assert max(paper) < 0.05 * half, (max(paper), half)
    assert max(crowned) < 0.25 * half, (max(crowned), half)


def test_the_smooth_laws_are_outside_their_validity_under_the_default_drag():
    """Section 3.5: Johnson's roughness parameter sigma/delta_0 of every contact model's static
    approach exceeds the bound (the text: outside their validity everywhere); the asperity
    layer's approach stays inside the fit's 4 sigma for the crowned and line contacts and is
    largest for the paper's ellipsoids; section 3.4's line pressures are tens of MPa."""
    from drive_rattle import MeshParameters

    sigma = MeshParameters().sigma
    for case in (doc_constants.CROWNED, doc_constants.PAPER, doc_constants.LINE):
        alpha = min(sigma / x for x in doc_constants.largest_own_approaches(case))
        assert alpha > doc_constants.JOHNSON_ALPHA, (case, alpha)
    layer = doc_constants.layer_approaches()
    assert max(layer["crowned"] + layer["line"]) < 4.0, layer
    assert min(layer["paper"]) > max(layer["crowned"] + layer["line"]), layer
    pressure = [doc_constants.peak_pressure(r)
                for r in doc_constants.loaded_pairs(doc_constants.LINE)]
    assert min(pressure) >= 10e6 and max(pressure) <= 100e6, pressure


def test_the_film_and_friction_sentences_hold_at_the_static_loads():
    """Section 4: the EHL film puts some pairs in the mixed regime and not others (lambda
    spans 1); eq. 7's delta_max stays below sigma, so the eq. 11 film leaves the pairs
    boundary; the apparent-area form's coefficient exceeds 1 (friction can hold the wheel
    against its normal force, section 5); the kinematic sliding acceleration at the pitch
    point dominates the friction's by far."""
    from drive_rattle import MeshParameters

    sigma = MeshParameters().sigma
    lam = [r["film_parameter"] for r in doc_constants.loaded_pairs(doc_constants.EHL)]
    assert min(lam) < 1.0 < max(lam), lam
    eq7 = [r["delta_max_eq7"] for r in doc_constants.loaded_pairs(
        doc_constants.CROWNED, v_impact=doc_constants.EQ7_SPEED)]
    assert 0.0 < max(eq7) < sigma, eq7
    coefficients = doc_constants.boundary_coefficients()
    assert min(b for _, b in coefficients) > 1.0, coefficients
    kinematic, friction = doc_constants.sliding_accelerations()
    assert kinematic > 100.0 * friction, (kinematic, friction)


def test_the_damping_examples_say_what_the_text_says():
    """Section 6: the example shaft damping loads the wheel beyond the drag; the example
    vehicle-side damping shortens the vehicle mode's memory but adds a mean drag far above
    the default one."""
    from drive_rattle import DrivelineParameters

    drive = DrivelineParameters()
    times = float(re.search(r"(\S+) times the drag", doc_constants.shaft_damping())[1])
    assert times > 1.0
    damped = DrivelineParameters(drag_viscous=doc_constants.VEHICLE_DAMPING_EXAMPLE).derived()
    assert damped["vehicle_mode_decay_time"] < drive.derived()["vehicle_mode_decay_time"]
    added = float(re.search(r"c_v ω_v of (\S+) N·m", doc_constants.vehicle_damping())[1])
    assert added > 10.0 * drive.drag


def test_the_defaults_the_text_quotes_are_the_specs():
    """The parameter defaults docs/model.md quotes in its prose, each as the specs give it
    (drive_rattle.parameters), and a limit and a derived constant it quotes: a changed
    default fails here until the text follows."""
    from drive_rattle import DrivelineParameters, MeshParameters
    from drive_rattle.parameters import specs
    from drive_rattle_cosim import band, mesh_stiffness

    p, d = MeshParameters(), DrivelineParameters()
    limits = dict(specs(p))
    text = " ".join(re.sub(r"<!-- BEGIN (.+?) -->.*?<!-- END \1 -->", "", TEXT,
                           flags=re.S).split())
    quoted = [
        f"(default {p.crowning * 1e6:g} µm, a representative value",
        f"St_c = {p.stokes_critical:g}: Gondret", f"e_dry = {p.restitution_dry:g}: Gondret",
        f"η = {p.eta:g} Pa·s: a gear oil", f"σ = {p.sigma * 1e6:g} µm: MODEL_NOTES",
        f"φ = {p.squeeze_fraction:g} has **no published value**",
        f"Hunt–Crossley e = {p.restitution:g} at {p.restitution_speed * 1e3:g} mm/s, the "
        "default before",
        f"`contact.stokes_critical` (default {p.stokes_critical:g},",
        f"`contact.restitution_dry` (default {p.restitution_dry:g},",
        f"oil film develops (default {p.squeeze_fraction:g})",
        f"with σ `surface.sigma` ({p.sigma * 1e6:g} µm, the paper)",
        # (the powers of ten as the text writes them; another default: the plain number,
        # which the text does not hold)
        ("`surface.gamma` (the asperity tip radius, 10⁻⁴ m" if p.gamma == 1e-4
         else f"`surface.gamma` (the asperity tip radius, {p.gamma:g} m"),
        ("`surface.asperity_density` (default 10⁹ m⁻²" if p.asperity_density == 1e9
         else f"`surface.asperity_density` (default {p.asperity_density:g} m⁻²"),
        f"defaults {p.body_ratio_pinion:g} and {p.body_ratio_wheel:g}, the reference",
        f"(`solver.h_max`, default {p.h_max * 1e6:g} µs)",
        f"`rattle.time_constant` (default {p.rattle_time:g} s,",
        f"**A soft shaft, k = {d.k_shaft:g} N·m/rad (default).**",
        f"**Light shaft damping** c = {d.c_shaft:g} N·m·s/rad",
        f"`lubricant.alpha` α = {p.alpha_pv * 1e8:g}·10⁻⁸ 1/Pa",
        f"`lubricant.tau_limit_0` {p.tau_limit_0 / 1e6:g} MPa and "
        f"`lubricant.tau_limit_slope` {p.tau_limit_slope:g}",
        # a spec's limit and a derived constant inside a formula block, where no inline
        # block can stand
        f"`contact.crowning` is limited to ≥ {limits['crowning'].minimum * 1e6:g} µm",
        f"E*_steel^0.9 = {p.derived()['palmgren_constant']:.5g}",
        f"{p.z_pinion}/{p.z_wheel} teeth, m_n = {p.m_n * 1e3:g} mm, α_n = "
        f"{math.degrees(p.alpha_n):.4g}°, β = {math.degrees(p.beta):.4g}°, b = {p.b * 1e3:g} mm",
        f"every report carries its band φ = {band.SQUEEZE_LOW['squeeze_fraction']:g}–"
        f"{band.SQUEEZE_HIGH['squeeze_fraction']:g}",
        f"and {limits['body_ratio_pinion'].minimum:g} ≤ h ≤ "
        f"{limits['body_ratio_pinion'].maximum:g} (the range of",
        f"tested within {mesh_stiffness.ISO_BAND[0]:g}–{mesh_stiffness.ISO_BAND[1]:g} × c_γα b "
        f"at {mesh_stiffness.ISO_LOAD:g} and",
    ]
    assert [limits["body_ratio_wheel"].minimum, limits["body_ratio_wheel"].maximum] == [
        limits["body_ratio_pinion"].minimum, limits["body_ratio_pinion"].maximum]
    missing = [q for q in quoted if q not in text]
    assert not missing, (f"docs/model.md does not quote these defaults as the specs give "
                         f"them: {missing}")


def test_the_gear_bodies_defaults_are_the_root_radii_on_the_text_shafts():
    """Section 3.7: the default root/bore radius ratios are the reference pair's root radii
    (pitch radius less the ISO 53 dedendum 1.25 m_n) on the shafts the text names."""
    from drive_rattle import MeshParameters

    p = MeshParameters()
    d = p.derived()
    shafts = [float(x) * 1e-3 for x in re.search(
        r"root radii on a (\d+) mm input and a (\d+) mm output shaft", " ".join(TEXT.split())
    ).groups()]
    found = [round((r - 1.25 * p.m_n) / (shaft / 2), 1)
             for r, shaft in zip((d["r_pinion"], d["r_wheel"]), shafts, strict=True)]
    assert found == [p.body_ratio_pinion, p.body_ratio_wheel], (found, shafts)


def test_the_compliant_grid_is_the_committed_measurement():
    """Section 6.2's grid, and section 6.1's table of its rows at the default backlash, are
    rendered from docs/data/multistability_grid.json, the data of the grid's command (every
    point of it, every start at each point); the slow tests/analysis/test_multistability.py
    measures two of its points again."""
    assert model_doc.stale(TEXT, ["compliant grid", "separation loads"]) == [], (
        "docs/model.md section 6.2's grid or section 6.1's table is not the rendering of its "
        "data: run `python -m drive_rattle_cosim.model_doc --update --only 'compliant grid' "
        "--only 'separation loads'`")
    data = doc_runs.grid_data()
    assert data["command"] == doc_runs.GRID_COMMAND, (
        f"the grid's data was measured by {data['command']!r}; allowed: "
        f"{doc_runs.GRID_COMMAND!r} (run `python -m drive_rattle_cosim.model_doc "
        "--measure-grid`)")
    starts = sorted(s.name for s in doc_runs.grid_starts())
    for p in data["points"]:
        found = sorted([*(s for a in p["attractors"] for s in a["starts"]),
                        *(u["start"] for u in p["unsettled"])])
        assert found == starts, (p["load_fraction"], p["backlash"], found)


def test_the_load_table_refuses_grid_data_without_its_backlash():
    data = doc_runs.grid_data()
    other = {**data, "points": [p for p in data["points"]
                                if p["backlash"] != doc_runs.LOAD_BACKLASH]}
    with pytest.raises(ValueError, match=r"no point at backlash 0\.0001 m; allowed: the "
                                         r"backlashes of `python -m drive_rattle_cosim"):
        doc_runs.separation_loads(other)


def test_the_mixed_regime_is_measured_over_the_roughness_and_the_film():
    text = doc_runs.mixed_regime(SHORT)
    rows = [r for r in text.splitlines() if r.startswith("| 0.")]
    assert [r.split(" |")[0] for r in rows] == [f"| {s * 1e6:g}" for s in doc_runs.SIGMAS]
    assert not re.search(r"\b(nan|inf)\b", text, re.IGNORECASE)
    # the EHL film of a smooth flank (0.02 um) is thicker than sigma wherever it is built:
    # every in-contact sample mixed or full, in every window
    assert rows[-1].endswith("| 100 ± 0 % |")


def test_the_kicked_coupled_start_is_measured_on_a_short_run():
    text = doc_runs.kicked_coupled(6.0)
    # the kick winds the soft shaft up: the load falls from the drag (0.0833 N.m) to minus
    # several drags, and the wheel, held on one flank, stops impacting for seconds
    low, high = (float(x.replace("−", "-")) for x in
                 re.search(r"between (\S+) and (\S+) N·m", text).groups())
    assert low < -0.0833 and high < 0.1
    assert re.search(r"no onset from [\d.]+ to 6 s", text), text


#: Blocks whose runs a test of the study checks (tests/analysis/test_multistability.py): the
#: test holds the block to its own run, so the whole document's test does not run it again
#: (under pytest-xdist the two files may run in different processes, which share no cache).
CHECKED_WITH_THEIR_RUNS = {
    "rigid orbit": "test_phase_starts_find_the_orbit_the_seven_starts_miss",
    "hunt-crossley states": "test_the_command_finds_the_second_attractor_at_0_4_and_one_at_0_8",
    "two states": "test_the_compliant_teeth_have_two_states_at_0_4_and_0_1_mm",
}


def test_the_blocks_left_to_the_study_tests_are_checked_there():
    source = (ROOT / "tests" / "analysis" / "test_multistability.py").read_text(encoding="utf-8")
    tests = {name: body for name, body in
             re.findall(r"\ndef (test_\w+)\(.*?\):\n(.*?)(?=\n\n\n|\Z)", source, re.S)}
    for block, test in CHECKED_WITH_THEIR_RUNS.items():
        assert block in model_doc.BLOCKS
        assert f'model_doc.stale(text, ["{block}"]) == []' in tests[test], (block, test)


#: Blocks a test of this file holds to a fresh computation of its own (the contact options'
#: runs, the single impacts, the grid's data, the constants of the defaults), which the whole
#: document's test leaves to it.
CHECKED_ABOVE = {"contact options", "contact findings", "single impacts", "compliant grid",
                 "separation loads",
                 *model_doc.CONSTANT_BLOCKS}


@pytest.mark.slow
def test_every_block_of_the_document_is_current():
    blocks = [b for b in model_doc.BLOCKS
              if b not in CHECKED_WITH_THEIR_RUNS and b not in CHECKED_ABOVE]
    assert model_doc.stale(TEXT, blocks) == [], (
        "docs/model.md is stale: run `python -m drive_rattle_cosim.model_doc --update` and "
        "review the diff")


@pytest.mark.slow
def test_the_findings_are_written_from_the_runs_of_a_short_horizon():
    contact = doc_runs.contact_findings(SHORT)
    paper = doc_runs.paper_findings(SHORT)
    band = doc_runs.band_findings(SHORT)
    for text in (contact, paper, band):
        assert not re.search(r"\b(nan|inf)\b", text, re.IGNORECASE)
    # the pairs in contact of the paper's and the line contact, each held against 3-4
    assert "the paper's ellipsoids load 3.0" in contact and "the line contact 3.0" in contact
    assert paper.count("pairs loaded while in contact") == 3
    # the band measures friction and the teeth, each against the defaults and their scatter
    assert "Friction off: drive onsets" in band and "window scatter ±" in band
    assert "Rigid teeth: drive onsets" in band
    assert "moves the statistics below by at most" in band
    # the coupled driveline apart, with its load's range
    assert "coupled driveline" in paper and "mN·m" in paper
    # the same runs give the same text (the compiled loop is deterministic)
    doc_runs._band_runs.cache_clear()
    assert doc_runs.band_findings(SHORT) == band


def test_the_update_replaces_the_blocks_and_nothing_else():
    text = "".join(f"a {n}\n<!-- BEGIN {n} -->old<!-- END {n} -->\n" for n in model_doc.BLOCKS)
    new = model_doc.update(text, {n: f"new {n}" for n in model_doc.BLOCKS})
    assert new == "".join(f"a {n}\n<!-- BEGIN {n} -->new {n}<!-- END {n} -->\n"
                          for n in model_doc.BLOCKS)


def test_a_document_without_a_block_is_refused_in_one_line(tmp_path, capsys):
    doc = tmp_path / "model.md"
    doc.write_text("no block <!-- BEGIN stray -->x<!-- END stray -->\n", encoding="utf-8")
    assert model_doc.main(["--update", "--doc", str(doc)]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith("model_doc: ") and "\n" not in err
    assert "unknown stray" in err and "missing" in err
    assert doc.read_text(encoding="utf-8").startswith("no block")  # left as it was


@pytest.mark.slow
def test_the_analysis_documents_default_run_is_the_paper_setups():
    text = (ROOT / "docs" / "analysis.md").read_text(encoding="utf-8")
    found = re.findall(r"<!-- BEGIN ([^>]+?) -->", text)
    assert sorted(found) == sorted(model_doc.ANALYSIS_BLOCKS)
    block = doc_runs.default_run(SHORT)
    assert "| mean wheel speed [rad/s] |" in block and "| 44.5 |" in block
    assert "| further statistics | this run |" in block


@pytest.mark.slow
def test_every_block_of_the_analysis_document_is_current():
    text = (ROOT / "docs" / "analysis.md").read_text(encoding="utf-8")
    assert model_doc.stale(text, blocks=model_doc.ANALYSIS_BLOCKS) == [], (
        "docs/analysis.md is stale: run `python -m drive_rattle_cosim.model_doc --update`")
