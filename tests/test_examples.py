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
    assert names == {"comparison.md", "cosim.csv", "fig3_wheel_speed.png", "fig4_pair_force.png",
                     "fig5_force_spectrum.png"}
    for f in result["files"]:
        assert f.stat().st_size > (5000 if f.suffix == ".png" else 300)
    ws = result["statistics"]
    assert len(ws.windows) == 2 and ws.transient == pytest.approx(0.1)
    speed = ws.scatter("mean_wheel_speed")
    assert speed.mean == pytest.approx(86.92 * 20 / 39, rel=0.01) and speed.n == 2
    report = (tmp_path / "comparison.md").read_text()
    row = next(r for r in report.splitlines() if r.startswith("| mean wheel speed [rad/s] |"))
    assert " ± " in row and "| 44.5 |" in row  # this run with its scatter, the paper's figure
    with pytest.raises(ValueError, match="transient"):
        mod.run(stop_time=0.5, transient=0.4, window=0.2, out_dir=tmp_path,
                fmu_dir=fmus["GearMeshRattle"].parent)


def test_rattle_maps_example(tmp_path):
    """The maps on the library engine (the default); engine 'fmu' is the same numbers bit for
    bit (tests/cosim/test_sweep.py)."""
    mod = load("rattle_maps")
    result = mod.run(points=2, transient=0.01, window=0.01, windows=2, workers=2,
                     out_dir=tmp_path, progress=False)
    names = sorted(f.name for f in result["files"])
    assert names == ["amplitude_speed.csv", "amplitude_speed.png", "backlash_drag.csv",
                     "backlash_drag.png"]
    rows = {f.stem: read_results(f) for f in result["files"] if f.suffix == ".csv"}
    assert [r["error"] for rs in rows.values() for r in rs if r["error"]] == []
    assert all(c["done"] == 4 and c["failed"] == 0 for c in result["counts"].values()), (
        result["counts"])
    assert (tmp_path / "backlash_drag.png").stat().st_size > 5000
    assert all(r["windows"] == 2 and "rattle_index_W_std" in r and r["engine"] == "library"
               for r in rows["backlash_drag"])
    # Resuming with other windows would mix settings: refused.
    with pytest.raises(ValueError, match="was run with"):
        mod.run(points=2, transient=0.01, window=0.01, windows=3, workers=1, out_dir=tmp_path,
                progress=False)
