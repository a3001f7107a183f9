"""The paper scenario under each contact option (docs/model.md section 3.6): the default
crowned point contacts, the paper's equivalent ellipsoids at the shared approach as printed
(rigid teeth; exact elliptical law and eq. 2), Palmgren's line contact of unmodified flanks,
and the Greenwood-Tripp asperity layer in series -- every other parameter at its default.

    python benchmarks/contact_laws.py [--stop-time 11] [--transient 1] [--window 2]
        [--out out/contact_laws.md]

Each case runs in the paper's setup -- the pinion kinematic from the default engine orders, a
constant resisting torque (the default drag, 0.5 M*) on the wheel: ``vehicle.model`` = 1 --
in the model library's compiled co-simulation loop (drive_rattle.units.run_coupled, the FMUs'
numbers bit for bit) at the default 1e-4 s step.  The statistics are those of
drive_rattle_cosim.analysis (windowed_statistics; onsets recovered from the recorded counters
and mesh.v_impact, as the sweep and examples/paper_scenario.py do): the first ``--transient``
seconds left out, then equal windows, each statistic as mean ± window-to-window standard
deviation.  A statistic is called sensitive to the contact law when the spread of its means
over the cases exceeds three times the largest window scatter.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from drive_rattle import DrivelineParameters, MeshParameters
from drive_rattle.units import DrivelineUnit, MeshUnit, coupled_start_inputs, run_coupled

from .analysis import onsets_from_counters, windowed_statistics

#: The paper's setup: a constant resisting torque on the wheel (band.PAPER_SETUP).
PAPER_SETUP = {"vehicle_model": 1}
STEP = 1e-4
RECORD = ["wheel.phi", "mesh.W", "mesh.W_peak", "mesh.delta_peak", "mesh.n_contact",
          "mesh.v_impact", "mesh.impacts_drive", "mesh.impacts_coast"]
CASES = {
    "default (crowned, exact law)": {},
    "paper, exact law": {"contact_geometry": 1, "tooth_compliance": 0},
    "paper, eq. 2": {"contact_geometry": 1, "hertz_law": 1, "tooth_compliance": 0},
    "line (Palmgren)": {"contact_geometry": 2},
    "rough (crowned + asperity layer)": {"roughness": 1},
    "paper + rough": {"contact_geometry": 1, "roughness": 1, "tooth_compliance": 0},
    "line + rough": {"contact_geometry": 2, "roughness": 1},
}
#: (row label, RattleStatistics field, display scale)
ROWS = (
    ("onsets per second, drive", "impacts_per_second_drive", 1.0),
    ("onsets per second, coast", "impacts_per_second_coast", 1.0),
    ("impact speed drive p10 [mm/s]", "impact_speed_p10_drive", 1e3),
    ("impact speed drive p50 [mm/s]", "impact_speed_p50_drive", 1e3),
    ("impact speed drive p90 [mm/s]", "impact_speed_p90_drive", 1e3),
    ("impact speed drive RMS [mm/s]", "impact_speed_rms_drive", 1e3),
    ("impact speed coast p10 [mm/s]", "impact_speed_p10_coast", 1e3),
    ("impact speed coast p50 [mm/s]", "impact_speed_p50_coast", 1e3),
    ("impact speed coast p90 [mm/s]", "impact_speed_p90_coast", 1e3),
    ("impact speed coast RMS [mm/s]", "impact_speed_rms_coast", 1e3),
    ("δmax, mesh.delta_peak [µm]", "max_penetration", 1e6),
    ("pairs loaded while in contact", "mean_loaded_pairs", 1.0),
    ("fraction of time in contact", "contact_fraction", 1.0),
    ("mean wheel speed [rad/s]", "mean_wheel_speed", 1.0),
    ("rattle index (impact energy per second) [mW]", "impact_energy_rate", 1e3),
)


def run_case(changes: dict, stop_time: float, transient: float, window: float):
    """The windowed statistics of one case and the wall time of its run [s]."""
    mp, dp = MeshParameters(**changes), DrivelineParameters(**PAPER_SETUP)
    steps = round(stop_time / STEP)
    mesh_in, wheel = coupled_start_inputs(mp, dp)
    wall = time.perf_counter()
    with MeshUnit(mp, mesh_in["pinion.phi"], mesh_in["pinion.w"], mesh_in["wheel.tau_load"],
                  mesh_in["pinion.a"]) as mesh, \
            DrivelineUnit(dp, wheel["wheel.phi"], wheel["wheel.w"]) as drive:
        run = run_coupled(mesh, drive, round(STEP * 1e9), steps,
                          [f"GearMeshRattle.{n}" for n in RECORD])
    wall = time.perf_counter() - wall
    t = np.arange(steps + 1) * STEP
    s = {n: np.asarray(run.column_buffer(f"GearMeshRattle.{n}")) for n in RECORD}
    onsets = onsets_from_counters(t, s["mesh.impacts_drive"], s["mesh.impacts_coast"],
                                  s["mesh.v_impact"])
    ws = windowed_statistics(t, s, *onsets, mp.derived()["normal_mass"], transient, window)
    return ws, wall


def cell(sc, scale: float, digits: int = 3) -> str:
    if sc.n == 0:
        return "—"
    return f"{sc.mean * scale:.{digits}g} ± {sc.std * abs(scale):.2g}"


def results(stop_time: float = 11.0, transient: float = 1.0, window: float = 2.0,
            progress: bool = False) -> dict:
    """The windowed statistics of every case, by name."""
    out = {}
    for name, changes in CASES.items():
        ws, wall = run_case(changes, stop_time, transient, window)
        out[name] = ws
        if progress:
            print(f"{name}: {len(ws.windows)} windows, {wall:.2f} s", file=sys.stderr)
    return out


def sensitive(scatters) -> bool:
    """Whether the spread of the means over the cases exceeds three times the largest window
    scatter (and a thousandth of the largest mean)."""
    means = [sc.mean for sc in scatters if sc.n]
    stds = [sc.std for sc in scatters if sc.n and not np.isnan(sc.std)]
    if not means:
        return False
    spread = max(means) - min(means)
    return spread > 3.0 * (max(stds) if stds else 0.0) and spread > 1e-3 * max(map(abs, means))


def report(stop_time: float = 11.0, transient: float = 1.0, window: float = 2.0,
           progress: bool = True, runs: dict | None = None) -> str:
    """The Markdown table of every case, and the sensitivity of each statistic."""
    results_ = runs if runs is not None else results(stop_time, transient, window, progress)
    names = list(CASES)
    lines = ["| statistic | " + " | ".join(names) + " | sensitive to the contact law |",
             "|---|" + "---|" * (len(names) + 1)]
    for label, field, scale in ROWS:
        scatters = [results_[n].scatter(field) for n in names]
        verdict = "yes" if sensitive(scatters) else "no"
        digits = 5 if field == "mean_wheel_speed" else 3
        lines.append(f"| {label} | " + " | ".join(cell(sc, scale, digits) for sc in scatters)
                     + f" | {verdict} |")
    ws0 = next(iter(results_.values()))
    span = ws0.starts[-1] + ws0.window
    head = (f"The paper's setup (a constant M_res on the wheel), {span:g} s at {STEP:g} s, "
            f"{ws0.transient:g} s transient left out, {len(ws0.windows)} windows of "
            f"{ws0.window:g} s; mean ± window-to-window standard deviation "
            "(`python benchmarks/contact_laws.py`).\n\n")
    return head + "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--stop-time", type=float, default=11.0)
    ap.add_argument("--transient", type=float, default=1.0)
    ap.add_argument("--window", type=float, default=2.0)
    ap.add_argument("--out", type=Path, default=None, help="write the table here too")
    args = ap.parse_args(argv)
    text = report(args.stop_time, args.transient, args.window)
    print(text)
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text, encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
