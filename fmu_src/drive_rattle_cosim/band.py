"""The paper scenario's statistics as a band over the contact's dissipation and the film
(issue 19, item 3): each statistic for the defaults (the squeeze-film law), the squeeze-film
law over its plausible parameters, Hunt-Crossley's restitution range, the mesh damping ratios
of gear-dynamics practice and piezoviscous friction -- mean ± window-to-window scatter, so that
no single calibrated point stands for the model.

    python -m drive_rattle_cosim.band [--stop-time 11] [--transient 1] [--window 2]
        [--case NAME ...] [--out out/dissipation_band.md]

The runs are the compiled coupled loop (``system.simulate``: the co-simulation's numbers, bit
for bit); the statistics those of ``analysis.windowed_statistics``; the film's fraction of
in-contact samples in the mixed or full-film regime (psi < 1) is counted from ``mesh.psi``.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from drive_rattle.parameters import DrivelineParameters, MeshParameters

from .analysis import Scatter, windowed_statistics
from .system import simulate

#: Recorded mesh outputs.
SIGNALS = ("wheel.phi", "mesh.W", "mesh.W_peak", "mesh.delta_peak", "mesh.n_contact",
           "mesh.psi")


@dataclass(frozen=True)
class BandCase:
    """One setting of the band: a name, what it stands for, the mesh parameters changed."""

    name: str
    meaning: str
    mesh: dict = field(default_factory=dict)


#: The squeeze-film law's plausible range (docs/model.md section 3.3): the critical Stokes
#: number of spheres in liquids (about 10: Gondret et al. 2002, Joseph et al. 2001; 5-20
#: over the elasticity parameter, Davis et al. 2002), the dry restitution of steel (0.9-0.99),
#: and the starved film's fraction of the flooded squeeze force, the calibration-level unknown
#: (flooded, phi = 1, no impact below about 70 mm/s rebounds: no rattle at the paper's speeds).
SQUEEZE_LOW = {"dissipation": 3, "stokes_critical": 5.0, "restitution_dry": 0.99,
               "squeeze_fraction": 0.01}
SQUEEZE_CENTRAL = {"dissipation": 3, "stokes_critical": 10.0, "restitution_dry": 0.97,
                   "squeeze_fraction": 0.03}
SQUEEZE_HIGH = {"dissipation": 3, "stokes_critical": 20.0, "restitution_dry": 0.9,
                "squeeze_fraction": 0.1}

#: Hunt-Crossley from a restitution at 4 mm/s (an option; the default before issue 19).
HUNT_CROSSLEY = {"dissipation": 1}
CASES = (
    BandCase("default", "the defaults: squeeze film, St_c 10, e_dry 0.97, phi 0.03"),
    BandCase("squeeze low", "squeeze film, St_c 5, e_dry 0.99, phi 0.01", SQUEEZE_LOW),
    BandCase("squeeze high", "squeeze film, St_c 20, e_dry 0.9, phi 0.1", SQUEEZE_HIGH),
    BandCase("squeeze phi 0.01", "squeeze film, the default St_c and e_dry, phi 0.01",
             {**SQUEEZE_CENTRAL, "squeeze_fraction": 0.01}),
    BandCase("squeeze phi 0.1", "squeeze film, the default St_c and e_dry, phi 0.1",
             {**SQUEEZE_CENTRAL, "squeeze_fraction": 0.1}),
    BandCase("e 0.7", "Hunt-Crossley, e = 0.7 at 4 mm/s", {**HUNT_CROSSLEY, "restitution": 0.7}),
    BandCase("e 0.8", "Hunt-Crossley, e = 0.8 at 4 mm/s", {**HUNT_CROSSLEY, "restitution": 0.8}),
    BandCase("e 0.9", "Hunt-Crossley, e = 0.9 at 4 mm/s", {**HUNT_CROSSLEY, "restitution": 0.9}),
    BandCase("zeta 0.03", "mesh damping ratio 0.03", {"dissipation": 4, "damping_ratio": 0.03}),
    BandCase("zeta 0.05", "mesh damping ratio 0.05", {"dissipation": 4, "damping_ratio": 0.05}),
    BandCase("zeta 0.1", "mesh damping ratio 0.1", {"dissipation": 4, "damping_ratio": 0.1}),
    BandCase("Barus", "default dissipation; Barus viscosity with limiting shear, sliding shear",
             {"viscous_law": 1, "shear_speed": 1}),
    BandCase("Barus + EHL film", "as Barus, the film the larger of eq. 11 and Hamrock-Dowson's",
             {"viscous_law": 1, "shear_speed": 1, "film": 1}),
)

#: Columns: (heading, statistic of RattleStatistics or "psi", display scale, digits).
COLUMNS = (
    ("drive onsets [1/s]", "impacts_per_second_drive", 1.0, 3),
    ("coast onsets [1/s]", "impacts_per_second_coast", 1.0, 3),
    ("v p10 [mm/s]", "impact_speed_p10_drive", 1e3, 2),
    ("v p50 [mm/s]", "impact_speed_p50_drive", 1e3, 2),
    ("v p90 [mm/s]", "impact_speed_p90_drive", 1e3, 3),
    ("v RMS [mm/s]", "impact_speed_rms_drive", 1e3, 3),
    ("coast v RMS [mm/s]", "impact_speed_rms_coast", 1e3, 3),
    ("δmax [µm]", "max_penetration", 1e6, 3),
    ("pairs in contact", "mean_loaded_pairs", 1.0, 3),
    ("mean wheel speed [rad/s]", "mean_wheel_speed", 1.0, 5),
    ("rattle index [mW]", "impact_energy_rate", 1e3, 3),
    ("ψ < 1 [% of in-contact samples]", "psi", 100.0, 2),
)


@dataclass
class BandRow:
    """The windowed statistics of one case: each column's scatter over the windows."""

    case: BandCase
    values: dict[str, Scatter]
    seconds: float  # wall time of the run


def mixed_regime_fraction(n_contact, psi) -> float:
    """Fraction of the samples with a pair in contact whose most loaded pair's film is mixed
    or full (psi < 1); nan without contact."""
    n = np.asarray(n_contact, dtype=float)[1:]
    p = np.asarray(psi, dtype=float)[1:]
    inside = n > 0
    return float(np.mean(p[inside] < 1.0)) if inside.any() else float("nan")


def run_case(case: BandCase, stop_time: float = 11.0, transient: float = 1.0,
             window: float = 2.0, step: float = 1e-4) -> BandRow:
    """The scenario with the case's mesh parameters: its windowed statistics."""
    mesh = MeshParameters(**case.mesh)
    wall = time.perf_counter()
    rec = simulate(mesh, DrivelineParameters(), stop_time=stop_time, step=step,
                   signals=list(SIGNALS))
    wall = time.perf_counter() - wall
    ws = windowed_statistics(rec.time, rec.signals, rec.onset_times, rec.onset_speeds,
                             rec.onset_flanks, mesh.derived()["normal_mass"], transient, window)
    values = {name: ws.scatter(name) for _, name, _, _ in COLUMNS if name != "psi"}
    values["psi"] = Scatter.of([
        mixed_regime_fraction(np.asarray(rec.signals["mesh.n_contact"])[s],
                              np.asarray(rec.signals["mesh.psi"])[s]) for s in ws.slices])
    return BandRow(case, values, wall)


def band(cases=CASES, **kwargs) -> list[BandRow]:
    """Every case of the band (keyword arguments: those of :func:`run_case`)."""
    return [run_case(c, **kwargs) for c in cases]


def cell(sc: Scatter, scale: float, digits: int) -> str:
    """``mean ± std`` of a column (nan: no value in any window)."""
    if sc.n == 0:
        return "–"
    std = "" if sc.n < 2 else f" ± {sc.std * scale:.2g}"
    return f"{sc.mean * scale:.{digits}g}{std}"


def markdown(rows: list[BandRow]) -> str:
    """The band as a Markdown table, one row per case."""
    head = "| case | " + " | ".join(h for h, _, _, _ in COLUMNS) + " |"
    rule = "|---" * (len(COLUMNS) + 1) + "|"
    lines = [head, rule]
    for r in rows:
        cells = [cell(r.values[name], scale, digits) for _, name, scale, digits in COLUMNS]
        lines.append(f"| {r.case.name} | " + " | ".join(cells) + " |")
    lines.append("")
    lines += [f"* {r.case.name}: {r.case.meaning} ({r.seconds:.1f} s)" for r in rows]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m drive_rattle_cosim.band",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--stop-time", type=float, default=11.0)
    parser.add_argument("--transient", type=float, default=1.0)
    parser.add_argument("--window", type=float, default=2.0)
    parser.add_argument("--step", type=float, default=1e-4)
    parser.add_argument("--case", action="append", choices=[c.name for c in CASES],
                        help="run only these cases (repeatable; default all)")
    parser.add_argument("--out", type=Path, help="also write the table to this file")
    args = parser.parse_args(argv)
    cases = [c for c in CASES if args.case is None or c.name in args.case]
    rows = []
    for c in cases:
        rows.append(run_case(c, args.stop_time, args.transient, args.window, args.step))
        print(f"{c.name}: {rows[-1].seconds:.1f} s", file=sys.stderr)
    text = markdown(rows)
    print(text)
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
