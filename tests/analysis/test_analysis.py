"""Statistics after the transient in windows, against records built with known answers."""

import math
import re

import numpy as np
import pytest

from drive_rattle_cosim.analysis import (
    STRONGEST_LEVEL_ROW,
    STRONGEST_ROW,
    LineCatalogue,
    LineSearch,
    Scatter,
    extent_result_text,
    further_statistics,
    markdown_table,
    number_text,
    onsets_from_counters,
    paper_comparison,
    rattle_statistics,
    strongest_line,
    subharmonic_result_text,
    windowed_statistics,
)
from drive_rattle_cosim.spectral_lines import (
    Subharmonic,
    spectral_extent,
    subharmonic_test,
    welch_spectrum,
)
from drive_rattle_cosim.sweep import rattle_metrics

H = 1e-3  # s, sampling step
T_REC, TRANSIENT, WINDOW = 10.0, 1.0, 2.0  # 4 windows, 1 s tail left out
SPEEDS = (40.0, 42.0, 44.0, 46.0)  # rad/s, the wheel's speed in windows 0..3
M_N = 0.76  # kg


def record():
    """A 10 s record: a wild transient (speed 80 rad/s, penetration 9 um, 5 coast impacts at
    0.5 m/s) then 4 windows of known speed, impacts and loads, then a 1 s tail."""
    t = np.arange(round(T_REC / H) + 1) * H
    speed = np.where(t <= TRANSIENT, 80.0, 0.0)
    for i, w in enumerate(SPEEDS):
        a, b = TRANSIENT + i * WINDOW, TRANSIENT + (i + 1) * WINDOW
        speed[(t > a) & (t <= b)] = w
    speed[t > TRANSIENT + 4 * WINDOW] = 10.0
    phi = np.concatenate([[0.0], np.cumsum(speed[1:] * H)])  # angle advanced per step
    delta_peak = np.zeros(t.size)
    n_contact = np.full(t.size, 3)
    n_contact[t <= TRANSIENT] = 1
    W = np.full(t.size, 5.0)
    drive = np.zeros(t.size, dtype=int)
    coast = np.zeros(t.size, dtype=int)
    v = np.zeros(t.size)

    onsets = [(0.1 + 0.1 * k, -1, 0.5) for k in range(5)]
    delta_peak[round(0.3 / H)] = 9e-6
    for i in range(4):  # window i: i+1 drive onsets at (i+1) mm/s, one coast onset at 2 mm/s
        a = TRANSIENT + i * WINDOW
        onsets += [(a + 0.2 + 0.3 * j, 1, (i + 1) * 1e-3) for j in range(i + 1)]
        onsets.append((a + 1.5, -1, 2e-3))
        delta_peak[round((a + 1.0) / H)] = (i + 1) * 1e-7
        n_contact[(t > a + 0.5) & (t <= a + 1.0)] = 4 if i % 2 else 0
    # An onset exactly at the end of window 0 belongs to window 0: (start, end].
    onsets.append((TRANSIENT + WINDOW, 1, 1e-3))
    onsets.append((T_REC - 0.5, 1, 0.3))  # in the tail: in no window
    for time, flank, speed_ in sorted(onsets):  # counters and the last onset's speed
        k = round(time / H)
        (drive if flank > 0 else coast)[k:] += 1
        v[k:] = speed_
    signals = {"wheel.phi": phi, "mesh.W": W, "mesh.W_peak": W, "mesh.delta_peak": delta_peak,
               "mesh.n_contact": n_contact, "mesh.impacts_drive": drive,
               "mesh.impacts_coast": coast, "mesh.v_impact": v}
    return t, signals


def test_windows_after_the_transient_against_the_record():
    t, s = record()
    onsets = onsets_from_counters(t, s["mesh.impacts_drive"], s["mesh.impacts_coast"],
                                  s["mesh.v_impact"])
    ws = windowed_statistics(t, s, *onsets, M_N, TRANSIENT, WINDOW)
    assert len(ws.windows) == 4
    assert (ws.transient, ws.window) == pytest.approx((TRANSIENT, WINDOW), rel=1e-12)
    assert ws.starts == pytest.approx([1.0, 3.0, 5.0, 7.0])
    assert ws.unused_tail == pytest.approx(1.0)
    speed = ws.scatter("mean_wheel_speed")
    assert [w.mean_wheel_speed for w in ws.windows] == pytest.approx(SPEEDS, rel=1e-12)
    assert speed.mean == pytest.approx(43.0) and speed.std == pytest.approx(np.std(SPEEDS,
                                                                                   ddof=1))
    assert (speed.min, speed.max, speed.n) == pytest.approx((40.0, 46.0, 4))
    # Window 0 holds its one onset at 1 mm/s and the one dated exactly at its end.
    drive = [w.impacts_per_second_drive * WINDOW for w in ws.windows]
    assert drive == pytest.approx([2, 2, 3, 4])
    assert [w.impacts_per_second_coast * WINDOW for w in ws.windows] == pytest.approx([1] * 4)
    assert [w.peak_impact_speed for w in ws.windows] == pytest.approx([2e-3, 2e-3, 3e-3, 4e-3])
    assert ws.windows[2].median_impact_speed == pytest.approx(3e-3)
    energy = 0.5 * M_N * (3 * (3e-3) ** 2 + (2e-3) ** 2) / WINDOW
    assert ws.windows[2].impact_energy_rate == pytest.approx(energy)
    # Nothing of the transient (9 um, 0.5 m/s) nor of the tail (0.3 m/s) leaks in.
    assert ws.scatter("max_penetration").max == pytest.approx(4e-7)
    assert ws.scatter("peak_impact_speed").max == pytest.approx(4e-3)
    # Pairs: 0 for 0.5 s in even windows (contact 75 %, 3 pairs while in contact), 4 in odd.
    assert [w.contact_fraction for w in ws.windows] == pytest.approx([0.75, 1, 0.75, 1])
    assert [w.mean_loaded_pairs for w in ws.windows] == pytest.approx([3, 3.25, 3, 3.25])
    assert [w.max_loaded_pairs for w in ws.windows] == [3, 4, 3, 4]
    # Without a line search the spectral figures are absent, not zero.
    assert math.isnan(ws.windows[0].dominant_line_frequency)
    assert ws.scatter("dominant_line_frequency").n == 0


def test_one_window_after_the_transient_and_the_whole_record():
    t, s = record()
    onsets = onsets_from_counters(t, s["mesh.impacts_drive"], s["mesh.impacts_coast"],
                                  s["mesh.v_impact"])
    ws = windowed_statistics(t, s, *onsets, M_N, TRANSIENT)
    assert len(ws.windows) == 1 and ws.window == pytest.approx(9.0) and ws.unused_tail == 0
    assert ws.windows[0].mean_wheel_speed == pytest.approx((sum(SPEEDS) * 2 + 10) / 9)
    assert math.isnan(ws.scatter("mean_wheel_speed").std)
    assert ws.scatter("mean_wheel_speed").text().endswith("(one window)")
    whole = rattle_statistics(t, s, onsets[1], onsets[2], M_N)
    assert whole.max_penetration == pytest.approx(9e-6)
    assert whole.impacts_per_second_coast == pytest.approx((5 + 4) / T_REC)


@pytest.mark.parametrize("kwargs, message", [
    ({"transient": 10.0}, "transient"),
    ({"transient": -1.0}, "transient"),
    ({"window": 9.5}, "does not fit"),
    ({"window": 0.0}, "window"),
])
def test_bad_windows_are_refused(kwargs, message):
    t, s = record()
    args = {"transient": TRANSIENT, "window": WINDOW, **kwargs}
    with pytest.raises(ValueError, match=message):
        windowed_statistics(t, s, [], [], [], M_N, **args)


def test_bad_records_are_refused():
    t, s = record()
    uneven = t.copy()
    uneven[5] += 0.3 * H
    with pytest.raises(ValueError, match="uniformly"):
        windowed_statistics(uneven, s, [], [], [], M_N, TRANSIENT, WINDOW)
    with pytest.raises(ValueError, match=r"wheel\.phi"):
        rattle_statistics(t, {"mesh.W": s["mesh.W"]}, [], [], M_N)


def _line_record(catalogue):
    """A force with a strong 620 Hz line and, in windows 0 and 2 only, one at 310 Hz (-6 dB
    of it).  Neither is an excited order at 830 rpm (44.8 and 22.4 times 13.83 Hz, more than
    a bin from even orders): unexplained."""
    fs, window = 10_000.0, 2.0
    t = np.arange(round(4 * window * fs) + 1) / fs
    rng = np.random.default_rng(3)
    W = 10.0 + rng.standard_normal(t.size) + 0.4 * np.sin(2 * np.pi * 620.0 * t)
    half = (t % (2 * window)) < window
    W += np.where(half, 0.2 * np.sin(2 * np.pi * 310.0 * t), 0.0)
    return t, {"wheel.phi": 44.5 * t, "mesh.W": W}, window


def test_spectral_figures_per_window():
    """The sub-harmonic of the 620 Hz line (f0 given) is flagged in the two windows that
    have it; the line table's figures per window."""
    cat = LineCatalogue(830 / 60, 20, (2.0, 4.0, 6.0))
    t, s, window = _line_record(cat)
    ws = windowed_statistics(t, s, [], [], [], M_N, 0.0, window, lines=LineSearch(),
                             catalogue=cat, fundamental=620.0)
    assert [w.dominant_line_frequency for w in ws.windows] == pytest.approx([620.0] * 4,
                                                                            abs=1.0)
    assert [w.subharmonic_flag for w in ws.windows] == [1.0, 0.0, 1.0, 0.0]
    assert [w.subharmonic_ratio_db for w in ws.windows][::2] == pytest.approx([-6.0] * 2,
                                                                              abs=1.0)
    assert ws.scatter("subharmonic_flag").mean == 0.5
    assert [w.lines_detected for w in ws.windows] == [2, 1, 2, 1]
    assert all(w.lines_unexplained == w.lines_detected for w in ws.windows)
    assert [w.resonances_detected for w in ws.windows] == [0] * 4
    assert ws.most_common("dominant_line_name") == ("unexplained", 4)
    rows = paper_comparison(ws)
    sub = next(r for r in rows if r[0].startswith("windows with a sub-harmonic"))
    assert sub[1] == "2 of 4 windows (f0 = 620 Hz)"
    assert (f"| {STRONGEST_ROW} | 620.0 (unexplained), found in 4 of 4 windows |"
            in markdown_table(rows))
    # Without a fundamental, the catalogue's is used: the forcing's period, engine order 2
    # (27.67 Hz).  620 Hz lies 0.6 bins from 622.5 Hz, the odd order 45 -- where a response
    # with twice the forcing's period has lines -- so every window is flagged.
    ws = windowed_statistics(t, s, [], [], [], M_N, 0.0, window, lines=LineSearch(),
                             catalogue=cat)
    assert [w.subharmonic_fundamental for w in ws.windows] == pytest.approx([830 / 30] * 4)
    assert [w.subharmonic_flag for w in ws.windows] == [1.0] * 4


def test_subharmonic_of_the_strongest_line_without_a_catalogue():
    t, s, window = _line_record(None)
    ws = windowed_statistics(t, s, [], [], [], M_N, 0.0, window, lines=LineSearch())
    assert [w.subharmonic_fundamental for w in ws.windows] == pytest.approx([620.0] * 4,
                                                                            abs=0.5)
    assert [w.subharmonic_flag for w in ws.windows] == [1.0, 0.0, 1.0, 0.0]


def test_white_noise_force_has_no_dominant_line():
    """The old "dominant line with a half-frequency sub-harmonic" found one in 47 of 50
    white-noise spectra; now neither a line nor a sub-harmonic of the forcing is found (at
    most the false-alarm count)."""
    fs = 10_000.0
    t = np.arange(round(2.0 * fs) + 1) / fs
    cat = LineCatalogue(830 / 60, 20, (2.0, 4.0, 6.0))
    found = flagged = 0
    for seed in range(25):
        W = 10.0 + np.random.default_rng(seed).standard_normal(t.size)
        ws = windowed_statistics(t, {"wheel.phi": t, "mesh.W": W}, [], [], [], M_N,
                                 lines=LineSearch(), catalogue=cat)
        found += not math.isnan(ws.windows[0].dominant_line_frequency)
        flagged += ws.windows[0].subharmonic_flag == 1.0
    assert found <= 2 and flagged <= 2


def test_scatter_text():
    assert Scatter.of([1.0, 2.0, 3.0]).text(1e3) == "2000 ± 1e+03 (1000–3000)"
    assert Scatter.of([math.nan, 4.0]).n == 1
    assert Scatter.of([]).text() == "none in any window"
    assert Scatter.of([2.0, 2.0]).relative_scatter == 0.0


def test_sweep_metrics_in_windows():
    t, s = record()
    m = rattle_metrics(t, s, M_N, TRANSIENT, WINDOW)
    assert m["windows"] == 4
    assert m["mean_wheel_speed"] == pytest.approx(43.0)
    assert m["mean_wheel_speed_std"] == pytest.approx(np.std(SPEEDS, ddof=1))
    assert m["impacts_per_s_drive"] == pytest.approx((2 + 2 + 3 + 4) / 4 / WINDOW)
    assert m["peak_impact_speed"] == pytest.approx(np.mean([2e-3, 2e-3, 3e-3, 4e-3]))
    # A constant force has no power in any band: the floor value, with no scatter.
    assert m["band_100_500_Hz_dB"] == -300.0 and m["band_100_500_Hz_dB_std"] == 0.0
    whole = rattle_metrics(t, s, M_N)
    assert whole["windows"] == 1 and math.isnan(whole["mean_wheel_speed_std"])


def test_a_line_in_some_windows_says_in_how_many():
    fs, window = 10_000.0, 1.0
    t = np.arange(round(4 * window * fs) + 1) / fs
    W = 10.0 + np.random.default_rng(8).standard_normal(t.size)
    W += np.where(t < 2 * window, 0.4 * np.sin(2 * np.pi * 620.0 * t), 0.0)
    ws = windowed_statistics(t, {"wheel.phi": t, "mesh.W": W}, [], [], [], M_N, 0.0, window,
                             lines=LineSearch())
    assert ws.scatter("dominant_line_frequency").n == 2
    assert ws.text("dominant_line_frequency").endswith(
        "; in 2 of 4 windows (no line found in 100–1500 Hz in the others)")
    assert [w.dominant_line_name for w in ws.windows] == ["unexplained"] * 2 + ["none found"] * 2
    assert ws.text("mean_wheel_speed") == "1 ± 0 (1–1)"


def test_impact_speeds_per_flank():
    """Percentiles (numpy's linear interpolation), RMS and energy rate of each flank's onset
    speeds, and nothing invented for a flank without onsets."""
    fs = 1000.0
    t = np.arange(2001) / fs  # one 2 s window
    drive = np.arange(1, 11) * 1e-3  # 1..10 mm/s
    coast = np.array([20e-3, 20e-3, 26e-3])
    speeds = np.concatenate([drive, coast])
    flanks = [1] * 10 + [-1] * 3
    s = {"wheel.phi": t, "mesh.W": np.ones(t.size)}
    st = rattle_statistics(t, s, speeds, flanks, M_N)
    assert (st.impact_speed_p10_drive, st.impact_speed_p50_drive,
            st.impact_speed_p90_drive) == pytest.approx((1.9e-3, 5.5e-3, 9.1e-3))
    assert st.impact_speed_rms_drive == pytest.approx(math.sqrt(np.mean(drive ** 2)))
    assert st.impact_energy_rate_drive == pytest.approx(0.5 * M_N * np.sum(drive ** 2) / 2.0)
    assert st.impact_speed_p50_coast == pytest.approx(20e-3)
    assert st.impact_speed_p90_coast == pytest.approx(24.8e-3)
    assert st.impact_energy_rate_coast == pytest.approx(0.5 * M_N * np.sum(coast ** 2) / 2.0)
    assert (st.impact_energy_rate_drive + st.impact_energy_rate_coast
            == pytest.approx(st.impact_energy_rate))
    only_drive = rattle_statistics(t, s, drive, [1] * 10, M_N)
    assert math.isnan(only_drive.impact_speed_p50_coast)
    assert math.isnan(only_drive.impact_speed_rms_coast)
    assert only_drive.impact_energy_rate_coast == 0.0


def test_paper_rows_give_percentiles_with_scatter_and_claim_no_agreement():
    t, s = record()
    onsets = onsets_from_counters(t, s["mesh.impacts_drive"], s["mesh.impacts_coast"],
                                  s["mesh.v_impact"])
    ws = windowed_statistics(t, s, *onsets, M_N, TRANSIENT, WINDOW)
    rows = {q: (run, paper) for q, run, paper in paper_comparison(ws)}
    for flank in ("drive", "coast"):
        for label in ("10th percentile", "median", "90th percentile", "RMS"):
            run, _ = rows[f"impact speed at onsets, {flank} flank: {label} [mm/s]"]
            assert " ± " in run
        run, _ = rows[f"impact energy rate, {flank} flank: Σ ½ m_n v² per second [mW]"]
        assert " ± " in run
    # Window i: i + 1 drive onsets at (i + 1) mm/s (window 0 also one at 1 mm/s): medians
    # 1, 2, 3, 4 mm/s; the coast onset is at 2 mm/s in every window.
    assert rows["impact speed at onsets, drive flank: median [mm/s]"][0] == (
        "2.5 ± 1.3 (1–4)")
    assert rows["impact speed at onsets, coast flank: median [mm/s]"][0] == "2 ± 0 (2–2)"
    paper = rows["impact speed at onsets, drive flank: median [mm/s]"][1]
    assert "4 mm/s" in paper and "not a like-for-like" in paper
    assert not any("typical" in q for q in rows)
    # Without a line search the spectral rows say so instead of inventing a value.
    no_search = "no spectrum analysed (no line search asked for)"
    assert rows["spectral extent: 1/3-octave PSD 10 dB below its 100–500 Hz mean [Hz]"][0] == (
        no_search)
    assert rows["windows with a sub-harmonic of the forcing (power at odd multiples of f0/2) "
                "[1]"][0] == no_search
    assert rows[STRONGEST_ROW][0] == no_search


def test_extent_rows_say_when_the_extent_is_only_a_lower_bound():
    """White noise is flat to Nyquist: the extent row gives the band top as a lower bound in
    every window, not a mean with a scatter."""
    fs = 10_000.0
    t = np.arange(round(4.0 * fs) + 1) / fs
    W = 10.0 + np.random.default_rng(5).standard_normal(t.size)
    ws = windowed_statistics(t, {"wheel.phi": t, "mesh.W": W}, [], [], [], M_N, 0.0, 2.0,
                             lines=LineSearch())
    assert [w.spectral_extent_censored for w in ws.windows] == [1.0, 1.0]
    text = next(r[1] for r in paper_comparison(ws) if r[0].startswith("spectral extent"))
    assert text.startswith("≥ 4996 (the band top, below Nyquist) in 2 of 2 windows")
    assert "±" not in text


def _two_lines_trading_places():
    """Four 2 s windows at 10 kHz with tones at 300 and 900 Hz (bin centres at 4 Hz bins) in
    weak white noise: 300 Hz is the stronger in windows 0 and 2 (amplitude 1 against 0.5),
    900 Hz in windows 1 and 3 (0.8 against 0.3).  The per-window strongest lines average to
    600 Hz, where there is no line; 900 Hz has the higher mean level."""
    fs, window = 10_000.0, 2.0
    t = np.arange(round(4 * window * fs) + 1) / fs
    odd = (t // window).astype(int) % 2 == 1
    a300, a900 = np.where(odd, 0.3, 1.0), np.where(odd, 0.8, 0.5)
    W = (10.0 + a300 * np.sin(2 * np.pi * 300.0 * t) + a900 * np.sin(2 * np.pi * 900.0 * t)
         + 0.05 * np.random.default_rng(4).standard_normal(t.size))
    return t, {"wheel.phi": 44.5 * t, "mesh.W": W}, window


def test_the_strongest_line_is_one_line_followed_through_the_windows():
    t, s, window = _two_lines_trading_places()
    ws = windowed_statistics(t, s, [], [], [], M_N, 0.0, window, lines=LineSearch(),
                             segment_seconds=0.25)
    # The input is hard: each window's own strongest line alternates, and their mean
    # frequency lies where no line is.
    assert [w.dominant_line_frequency for w in ws.windows] == pytest.approx(
        [300.0, 900.0] * 2, abs=1.0)
    assert ws.scatter("dominant_line_frequency").mean == pytest.approx(600.0, abs=1.0)
    line = strongest_line(ws)
    assert line.frequency == pytest.approx(900.0, abs=1.0)
    assert (line.name, line.found_in, line.windows) == ("unexplained", 4, 4)
    # A tone of amplitude A on a bin centre has the Welch PSD A²/2 over the equivalent noise
    # bandwidth of the Hann window, 1.5 bins of 4 Hz: its level in dB, averaged over the windows.
    expected = np.mean([10 * math.log10(a * a / 2 / (1.5 * 4.0)) for a in (0.5, 0.8) * 2])
    assert line.level_db.mean == pytest.approx(expected, abs=0.05)
    assert line.level_db.n == 4 and line.above_floor_db.n == 4
    rows = dict((q, run) for q, run, _paper in paper_comparison(ws))
    assert rows[STRONGEST_ROW] == "900.0 (unexplained), found in 4 of 4 windows"
    assert rows[STRONGEST_LEVEL_ROW] == line.level_db.text()


def test_a_line_found_in_one_window_is_ranked_by_its_level_in_all():
    """A 620 Hz tone only in the first of four windows, strong there, against a weaker
    400 Hz tone in all four: the strongest line is the one that is there throughout, and a
    line found in fewer windows says so."""
    fs, window = 10_000.0, 1.0
    t = np.arange(round(4 * window * fs) + 1) / fs
    W = (10.0 + 0.5 * np.sin(2 * np.pi * 400.0 * t)
         + np.where(t < window, 1.0, 0.0) * np.sin(2 * np.pi * 620.0 * t)
         + 0.05 * np.random.default_rng(9).standard_normal(t.size))
    ws = windowed_statistics(t, {"wheel.phi": t, "mesh.W": W}, [], [], [], M_N, 0.0, window,
                             lines=LineSearch())
    assert ws.windows[0].dominant_line_frequency == pytest.approx(620.0, abs=1.0)
    line = strongest_line(ws)
    assert line.frequency == pytest.approx(400.0, abs=1.0) and line.found_in == 4
    only_first = strongest_line(ws, band=(600.0, 640.0))
    assert only_first.frequency == pytest.approx(620.0, abs=1.0)
    assert only_first.text() == "620.0 (unexplained), found in 1 of 4 windows"


def test_white_noise_has_no_strongest_line():
    fs = 10_000.0
    t = np.arange(round(4.0 * fs) + 1) / fs
    cat = LineCatalogue(830 / 60, 20, (2.0, 4.0, 6.0))
    for seed in range(10):
        W = 10.0 + np.random.default_rng(seed).standard_normal(t.size)
        ws = windowed_statistics(t, {"wheel.phi": t, "mesh.W": W}, [], [], [], M_N, 0.0, 1.0,
                                 lines=LineSearch(), catalogue=cat)
        assert strongest_line(ws) is None, seed
        rows = dict((q, run) for q, run, _paper in paper_comparison(ws))
        assert rows[STRONGEST_ROW] == "no line found in 100–1500 Hz in any window"


def test_reports_say_in_words_what_is_missing():
    """A run with drive onsets only and a force without lines: every row of the paper
    comparison and of the further statistics, and the whole stretch's sub-harmonic test, is
    a number or says why there is none -- never nan or inf."""
    fs = 10_000.0
    t = np.arange(round(4.0 * fs) + 1) / fs
    W = 10.0 + np.random.default_rng(2).standard_normal(t.size)
    onset_t = np.arange(0.05, 4.0, 0.1)
    speeds = 1e-3 * (1.0 + (np.arange(onset_t.size) % 3))
    ws = windowed_statistics(t, {"wheel.phi": 44.5 * t, "mesh.W": W}, onset_t, speeds,
                             [1] * onset_t.size, M_N, 0.0, 1.0, lines=LineSearch(),
                             catalogue=LineCatalogue(830 / 60, 20, (2.0, 4.0, 6.0)))
    spec = welch_spectrum(t[1:], W[1:], 0.25)
    sub = subharmonic_test(spec, 830 / 30)
    text = (markdown_table(paper_comparison(ws)) + markdown_table(further_statistics(ws))
            + subharmonic_result_text(sub)
            + extent_result_text(spectral_extent(spec), spec.sample_rate))
    assert not re.search(r"\b(nan|inf)\b", text, re.IGNORECASE), text
    rows = dict((q, run) for q, run, _paper in paper_comparison(ws))
    assert rows["impact speed at onsets, coast flank: median [mm/s]"] == (
        "no coast-flank onset in any window")
    assert rows[STRONGEST_LEVEL_ROW] == "no line found in 100–1500 Hz in any window"
    assert ws.text("dominant_line_level") == "no line found in 100–1500 Hz in any window"


@pytest.mark.parametrize("sub, words", [
    (Subharmonic(27.67, 51, 1.06, 1.13, -0.2, 3.0, False),
     "the sub-harmonic comb has no power above the noise floor"),
    (Subharmonic(27.67, 51, 1.3, 1.13, 0.2, -1.0, True),
     "the comb at k·f0 has no power above the noise floor"),
    (Subharmonic(27.67, 0, math.nan, math.nan, math.nan, math.nan, False),
     "no test possible"),
])
def test_the_subharmonic_result_says_in_words_what_it_lacks(sub, words):
    text = subharmonic_result_text(sub)
    assert words in text and "nan" not in text


def test_the_subharmonic_result_gives_the_ratio_where_both_combs_have_power():
    text = subharmonic_result_text(Subharmonic(27.67, 51, 1.3, 1.13, 0.25, 1.0, True))
    assert text == ("flagged (f0 = 27.67 Hz, 51 positions, statistic 1.3 against the "
                    "threshold 1.13; sub-harmonic comb over the comb -6.0 dB)")


def test_scatter_and_tables_never_print_nan():
    assert Scatter.of([math.inf, 2.0, math.nan]).text() == "2 (one window)"
    assert Scatter.of([]).text(missing="no coast-flank onset") == "no coast-flank onset"
    assert number_text(math.nan, "no line found") == "no line found"
    assert markdown_table([("x", math.nan)], headers=("q", "v")).splitlines()[-1] == (
        "| x | no value |")
