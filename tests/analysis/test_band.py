"""The dissipation band (drive_rattle_cosim.band) on a short run: every case runs, every column
has a value, the table names every case."""

import math

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
