"""Every example runs (short horizons)."""

import importlib.util
from pathlib import Path

import pytest

from drive_rattle_cosim.sweep import read_results

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def load(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_paper_scenario_example(tmp_path, fmus):
    mod = load("paper_scenario")
    result = mod.run(stop_time=0.5, transient=0.1, window=0.2, out_dir=tmp_path,
                     fmu_dir=fmus["GearMeshRattle"].parent)
    names = {f.name for f in result["files"]}
    assert names == {"comparison.md", "models.md", "cosim.csv", "fig3_wheel_speed.png",
                     "fig4_pair_force.png", "fig5_force_spectrum.png"}
    for f in result["files"]:
        assert f.stat().st_size > (5000 if f.suffix == ".png" else 300)
    ws = result["statistics"]
    assert len(ws.windows) == 2 and ws.transient == pytest.approx(0.1)
    speed = ws.scatter("mean_wheel_speed")
    assert speed.mean == pytest.approx(86.92 * 20 / 39, rel=0.01) and speed.n == 2
    report = (tmp_path / "comparison.md").read_text()
    row = next(r for r in report.splitlines() if r.startswith("| mean wheel speed [rad/s] |"))
    assert " ± " in row and "| 44.5 |" in row  # this run with its scatter, the paper's figure
    # The two models side by side, each cell "mean ± scatter [band]"; the default model at its
    # defaults is the FMUs' run: the same statistic (the compiled loop gives their numbers)
    models = result["models"]
    assert [m.model.name for m in models] == ["default model", "paper's contact model"]
    assert models[0].central.statistics.scatter("max_penetration").mean == \
        ws.scatter("max_penetration").mean
    assert len(models[1].band) == 3
    table = result["models_table"]
    pairs = next(r for r in table.splitlines() if r.startswith("| pairs loaded"))
    cells = [c.strip() for c in pairs.strip("|").split("|")]
    assert all(" ± " in c and c.endswith("]") for c in cells[1:3]) and "3–4" in cells[3]
    text = (tmp_path / "models.md").read_text()
    assert "hypothesis" in text and "381.4 Hz" in text
    with pytest.raises(ValueError, match="transient"):
        mod.run(stop_time=0.5, transient=0.4, window=0.2, out_dir=tmp_path,
                fmu_dir=fmus["GearMeshRattle"].parent)


def test_rattle_maps_example(tmp_path):
    """The maps on the library engine (the default; engine 'fmu' is the same numbers bit for
    bit, tests/cosim/test_sweep.py), every cell from two starts."""
    mod = load("rattle_maps")
    result = mod.run(points=2, transient=0.01, window=0.01, windows=2, workers=2,
                     out_dir=tmp_path, progress=False, starts=("smooth", "free"))
    names = sorted(f.name for f in result["files"])
    assert names == ["amplitude_speed.csv", "amplitude_speed.png", "backlash_drag.csv",
                     "backlash_drag.png"]
    rows = {f.stem: read_results(f) for f in result["files"] if f.suffix == ".csv"}
    assert [r["error"] for rs in rows.values() for r in rs if r["error"]] == []
    assert all(c["done"] == 8 and c["failed"] == 0 for c in result["counts"].values()), (
        result["counts"])
    assert (tmp_path / "backlash_drag.png").stat().st_size > 5000
    assert all(r["windows"] == 2 and "rattle_index_W_std" in r and r["engine"] == "library"
               for r in rows["backlash_drag"])
    # each cell once per start: in the flank equilibrium, and free in mid-backlash at the
    # rigid speed of its own engine speed
    for r in rows["amplitude_speed"]:
        if r["GearMeshRattle.init.in_contact"] == 0.0:
            assert r["GearMeshRattle.wheel.w_start"] == pytest.approx(
                r["Driveline.engine.w_mean"] * 20 / 39, rel=1e-12)
    assert sorted(r["GearMeshRattle.init.in_contact"] for r in rows["backlash_drag"]) == [
        0.0] * 4 + [1.0] * 4
    assert set(result["multistable"]) == {"backlash_drag", "amplitude_speed"}
    # Resuming with other windows would mix settings: refused.
    with pytest.raises(ValueError, match="was run with"):
        mod.run(points=2, transient=0.01, window=0.01, windows=3, workers=1, out_dir=tmp_path,
                progress=False, starts=("smooth", "free"))


def test_rattle_maps_mark_the_cells_whose_starts_disagree_beyond_their_scatter(tmp_path):
    mod = load("rattle_maps")
    x, y = "Driveline.vehicle.drag", "GearMeshRattle.gear.backlash"

    def row(xv, yv, start, mean, std):
        return {x: xv, y: yv, "start": start, "rattle_index_W": mean,
                "rattle_index_W_std": std, "error": ""}

    rows = [row(0.1, 1e-4, 0, 10e-3, 0.1e-3), row(0.1, 1e-4, 4, 12e-3, 0.2e-3),  # apart
            row(0.2, 1e-4, 0, 10e-3, 2e-3), row(0.2, 1e-4, 4, 12e-3, 2e-3),  # within scatter
            row(0.1, 2e-4, 0, 5e-3, 0.0), row(0.1, 2e-4, 4, 5.02e-3, 0.0),  # within 1 %
            row(0.2, 2e-4, 0, 0.0, 0.0), row(0.2, 2e-4, 4, 0.0, 0.0)]
    path, split = mod._heat_map(rows, (x, 1.0, "drag"), (y, 1e3, "backlash"),
                                tmp_path / "m.png", "test", 0.2)
    assert split == [(0.1, 1e-4)] and path.stat().st_size > 5000


@pytest.mark.slow
def test_the_benchmark_quick_form_completes(tmp_path):
    """``python benchmarks/run.py --quick``: every run of the benchmark's default form on a
    1 s horizon (a step whose cost grows with the run's length shows here as a run that does
    not end), each phase announced with its time, the report written."""
    import subprocess
    import sys

    bench = EXAMPLES.parent / "benchmarks" / "run.py"
    run = subprocess.run([sys.executable, str(bench), "--quick", "--out", str(tmp_path)],
                         capture_output=True, text=True, timeout=1200)
    assert run.returncode == 0, run.stderr[-3000:]
    report = (tmp_path / "report.md").read_text(encoding="utf-8")
    assert "| compiled loop: the two units in the library, one call |" in report
    assert "| library: 2 workers / 1 worker |" in report
    assert "benchmarks [" in run.stderr and "done in" in run.stderr.splitlines()[-1]
