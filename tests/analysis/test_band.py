"""The dissipation band (drive_rattle_cosim.band) on a short run: every case runs, every column
has a value, the table names every case."""

import math

import pytest

from drive_rattle_cosim import band


def test_the_band_runs_every_column_for_a_short_scenario():
    cases = [c for c in band.CASES if c.name in ("default", "e 0.8", "zeta 0.1",
                                                 "Barus + EHL film")]
    rows = band.band(cases, stop_time=1.3, transient=0.3, window=0.5)
    for r in rows:
        assert set(r.values) == {name for _, name, _, _ in band.COLUMNS}
        assert r.values["mean_wheel_speed"].n == 2
        assert 44.0 < r.values["mean_wheel_speed"].mean < 45.0
        assert 0.0 <= r.values["psi"].mean <= 1.0
    by_name = {r.case.name: r for r in rows}
    assert by_name["default"].values["psi"].mean == 0.0  # the printed film: boundary only
    assert by_name["Barus + EHL film"].values["psi"].mean > 0.1  # the EHL film: mixed
    text = band.markdown(rows)
    assert all(f"| {c.name} |" in text for c in cases) and "nan" not in text
    assert math.isfinite(by_name["e 0.8"].values["max_penetration"].mean)


def test_the_band_runs_the_papers_setup_unless_told_the_coupled_driveline():
    from drive_rattle import DrivelineParameters

    drag = DrivelineParameters().drag
    default = next(c for c in band.CASES if c.name == "default")
    paper = band.run_case(default, stop_time=1.3, transient=0.3, window=0.5)
    # the paper's M_res: the wheel's load is the drag at every sample
    assert paper.values["load"].mean == drag and paper.values["load"].std == 0.0
    coupled = band.run_case(default, stop_time=1.3, transient=0.3, window=0.5,
                            setup=band.COUPLED_SETUP)
    # through the shaft the load follows the wheel
    assert coupled.values["load"].mean != drag and coupled.values["load"].std > 0.0


def test_the_band_varies_the_boundary_friction_and_the_teeth():
    from drive_rattle import MeshParameters

    by_name = {c.name: MeshParameters(**c.mesh) for c in band.CASES}
    base = MeshParameters()
    # the boundary friction coefficient A_e tau_s / W is proportional to tau_s (eq. 12-13)
    assert by_name["boundary mu 0.05"].tau_s / base.tau_s == pytest.approx(0.5, rel=1e-12)
    assert by_name["boundary mu 0.15"].tau_s / base.tau_s == pytest.approx(1.5, rel=1e-12)
    assert not by_name["friction off"].friction_enabled
    assert base.tooth_compliance == 1 and by_name["rigid teeth"].tooth_compliance == 0
    assert {by_name["bodies 1.4"].body_ratio_pinion, by_name["bodies 7"].body_ratio_wheel} \
        == {1.4, 7.0}
    rows = band.band([c for c in band.CASES if c.name in ("boundary mu 0.15", "rigid teeth")],
                     stop_time=0.8, transient=0.3, window=0.5)
    text = band.markdown(rows, timings=False)
    assert "| boundary mu 0.15 |" in text and " s)" not in text
