"""Every example runs (short horizons)."""

import importlib.util
import itertools
import math
import re
from pathlib import Path

import numpy as np
import pytest

from drive_rattle_cosim.analysis import strongest_line
from drive_rattle_cosim.spectral_lines import SpectralLine
from drive_rattle_cosim.sweep import read_results

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def load(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.slow
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
    # The contact models side by side in the paper's setup (a constant M_res on the wheel),
    # each cell "mean ± scatter [band]"; the default model at its defaults is the FMUs' run,
    # which runs the paper's setup too: the same statistic (the compiled loop gives their
    # numbers)
    models = result["models"]
    assert [m.model.name for m in models] == ["default model", "paper's contact model",
                                              "line contact"]
    assert all(m.setup.name == "the paper's setup" for m in models)
    assert all(m.central.driveline.vehicle_model == 1 for m in models)
    assert models[0].central.statistics.scatter("max_penetration").mean == \
        ws.scatter("max_penetration").mean
    assert "constant M_res" in report.splitlines()[0]
    # the band varies the friction and the teeth as well as the dissipation and the film;
    # the rigid paper's model gets compliant teeth, the compliant ones rigid teeth
    bands = [{r.setting.name for r in m.band} for m in models]
    assert {"boundary mu 0.05", "boundary mu 0.15", "dissipation low"} <= bands[0] & bands[2]
    assert "rigid teeth" in bands[0] and "compliant teeth" in bands[1]
    assert "bodies 7" in bands[0] and "bodies 7" not in bands[1]
    table = result["models_table"]
    pairs = next(r for r in table.splitlines() if r.startswith("| pairs loaded"))
    cells = [c.strip() for c in pairs.strip("|").split("|")]
    assert all(" ± " in c and c.endswith("]") for c in cells[1:4]) and "3–4" in cells[4]
    # the coupled driveline apart, labelled, its scope naming the slow load modulation
    assert [m.setup.name for m in result["coupled"]] == ["coupled driveline"] * 3
    assert all(m.central.driveline.vehicle_model == 0 for m in result["coupled"])
    assert "modulates the wheel's load" in result["coupled_scope"]
    assert "modulates" not in result["scope"] and "windows of 0.2 s" in result["scope"]
    text = (tmp_path / "models.md").read_text()
    assert "hypothesis" in text and "381.4 Hz" in text
    assert text.index("## The paper's setup") < text.index("## Coupled driveline")
    # No statistic reads nan or inf: a missing one says why in words.
    assert not re.search(r"\b(nan|inf)\b", report + text, re.IGNORECASE)
    # Fig. 5 names only detected lines, the strongest few; the rest are in the line table.
    full = result["lines"]
    named = mod.named_lines(full.lines)
    assert result["fig5_names"] == [ln.name or f"{ln.frequency:.0f} Hz ?" for ln in named]
    assert len(named) == min(mod.NAMED_LINES, len(full.lines))
    assert all(any(ln is d for d in full.lines) for ln in named)
    # The strongest line of the comparison is one of the lines the windows found.
    line = strongest_line(ws)
    if line is not None:
        assert any(d.near(line.frequency) is not None for d in ws.detections)
        assert f"| {line.text()} |" in report
    with pytest.raises(ValueError, match="transient"):
        mod.run(stop_time=0.5, transient=0.4, window=0.2, out_dir=tmp_path,
                fmu_dir=fmus["GearMeshRattle"].parent)


def test_the_envelope_holds_every_sample_where_a_thinned_line_aliases():
    """A 200.2 Hz sine over 5 s on 1000 columns (200 per second): one sample per column
    joined by a line shows a false 0.2 Hz wave; the min/max band of each column holds the
    sine's full swing in every column, and equals a brute-force min/max per column."""
    mod = load("paper_scenario")
    t = np.arange(50_001) * 1e-4
    y = np.sin(2 * np.pi * 200.2 * t)
    centre, low, high = mod.envelope(t, y, 1000)
    edges = np.linspace(t[0], t[-1], 1001)
    brute = []
    for a, b in itertools.pairwise(edges):  # [a, b), the last column with its end
        inside = y[(t >= a) & ((t < b) | (b == edges[-1]))]
        brute.append((inside.min(), inside.max()))
    assert centre == pytest.approx(0.5 * (edges[:-1] + edges[1:]))
    assert np.column_stack([low, high]) == pytest.approx(np.array(brute))
    assert low.max() < -0.99 and high.min() > 0.99  # the full swing in every column
    thinned = y[::50]  # one sample per column: a 0.2 Hz wave, one period over the 5 s
    assert np.ptp(thinned) > 1.99 and np.all(np.abs(np.diff(thinned)) < 0.01)
    # Fewer samples than columns: only the columns that hold one.
    centre, low, high = mod.envelope(t[:7], y[:7], 100)
    assert len(centre) == 7 and low == pytest.approx(y[:7]) and high == pytest.approx(y[:7])
    with pytest.raises(ValueError, match="columns"):
        mod.envelope(t, y, 0)


def test_the_zoom_spans_whole_forcing_periods_after_the_transient():
    mod = load("paper_scenario")
    h = 1e-4
    t = np.arange(50_001) * h
    period = 60.0 / (2 * 830.0)  # engine order 2 at 830 rpm: 36.1 ms
    span = mod.zoom_span(t, 1.0, period)
    assert t[span][0] == pytest.approx(1.0)
    assert span.stop - span.start == math.floor(3 * period / h) + 1
    assert t[span][-1] <= 1.0 + 3 * period < t[span][-1] + h
    end = mod.zoom_span(t, 4.99, period)  # cut at the record's end
    assert t[end][-1] == t[-1]
    with pytest.raises(ValueError, match="start"):
        mod.zoom_span(t, 6.0, period)


def test_a_pair_counts_its_own_onsets_by_the_flank_counters_of_the_step():
    """The pair's force rises from 0 four times: with a drive-flank onset in the step, with
    a coast-flank one, with both, and with neither (it takes up load on a flank in
    contact); a force already up at the span's start is no onset."""
    mod = load("paper_scenario")
    force = [3, 0, 5, 2, 0, 0, 4, 0, 1, 1, 0, 6, 0]
    drive = [0, 0, 1, 1, 1, 1, 1, 1, 2, 2, 2, 2, 2]
    coast = [0, 0, 0, 0, 0, 0, 1, 1, 2, 2, 2, 2, 2]
    counts = mod.pair_onsets(force, drive, coast)
    assert counts == {"drive": 1, "coast": 1, "both": 1, "under load": 1}
    assert mod.pair_onsets_text(counts).startswith("4 contact onsets of this pair")
    assert mod.pair_onsets([0, 0, 0], [0, 1, 2], [0, 0, 0]) == dict.fromkeys(
        mod.PAIR_ONSET_KINDS, 0)
    assert mod.pair_onsets_text(dict.fromkeys(mod.PAIR_ONSET_KINDS, 0)).startswith(
        "no contact onset of this pair")


def test_fig5_names_the_strongest_detected_lines_only():
    mod = load("paper_scenario")
    lines = [SpectralLine(100.0 + 10 * k, psd=float((7 * k) % 13 + 1), floor=0.1,
                          threshold=2.6, name=f"L{k}") for k in range(13)]
    named = mod.named_lines(lines, 4)
    assert sorted(ln.psd for ln in named) == sorted(ln.psd for ln in lines)[-4:]
    assert [ln.frequency for ln in named] == sorted(ln.frequency for ln in named)
    assert mod.named_lines(lines[:3], 4) == sorted(lines[:3], key=lambda ln: ln.frequency)
    assert mod.named_lines([], 4) == []


@pytest.mark.slow
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
