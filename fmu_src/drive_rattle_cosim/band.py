"""The paper scenario's statistics as a band over what the paper does not give: the
contact's dissipation, the film, the boundary friction and the teeth's compliance.  Each
statistic for the defaults (the squeeze-film law), the squeeze-film law over its plausible
parameters, Hunt-Crossley's restitution range, the mesh damping ratios of gear-dynamics
practice, piezoviscous friction, the boundary friction coefficient over 0.05-0.15 (and friction
off, to measure its effect), rigid teeth and the gear bodies' range -- mean ± window-to-window
scatter, so that no single calibrated point stands for the model.

    python -m drive_rattle_cosim.band [--stop-time 11] [--transient 1] [--window 2]
        [--coupled] [--case NAME ...] [--out out/band.md]

The runs are the compiled loop (``system.simulate``: the co-simulation's numbers, bit for
bit) in the paper's setup -- the pinion kinematic from the engine orders, a constant resisting
torque on the wheel (``vehicle.model`` = 1) -- or, with ``--coupled``, the coupled driveline;
the statistics those of ``analysis.windowed_statistics``; the film's fraction of in-contact
samples in the mixed or full-film regime (psi < 1) is counted from ``mesh.psi``.  The window
scatter covers the windows of one run after its start transient, nothing else.
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
           "mesh.psi", "wheel.tau_load")


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

#: Hunt-Crossley from a restitution at 4 mm/s (an option; the default of earlier releases).
HUNT_CROSSLEY = {"dissipation": 1}
#: The boundary friction coefficient A_e tau_s / W is proportional to tau_s (eq. 12-13), 0.1
#: at the default; lubricated steel in the boundary regime: about 0.05-0.15 (the paper gives
#: no value).
BOUNDARY_FRICTION_DEFAULT = 0.1
BOUNDARY_LOW = {"tau_s": MeshParameters().tau_s * 0.05 / BOUNDARY_FRICTION_DEFAULT}
BOUNDARY_HIGH = {"tau_s": MeshParameters().tau_s * 0.15 / BOUNDARY_FRICTION_DEFAULT}
FRICTION_OFF = {"friction_enabled": False}
#: The teeth: rigid (the paper's equations) or compliant (docs/model.md section 3.7), and
#: the gear bodies at the ends of the range Sainsot, Velex and Duverger fitted (root over
#: bore radius 1.4-7, both gears).
RIGID_TEETH = {"tooth_compliance": 0}
COMPLIANT_TEETH = {"tooth_compliance": 1}
BODY_LOW = {"body_ratio_pinion": 1.4, "body_ratio_wheel": 1.4}
BODY_HIGH = {"body_ratio_pinion": 7.0, "body_ratio_wheel": 7.0}
#: The paper's setup: the wheel under a constant resisting torque M_res = vehicle.drag
#: (eq. 10), the pinion kinematic; the coupled driveline is the Driveline's default.
PAPER_SETUP = {"vehicle_model": 1}
COUPLED_SETUP: dict = {}
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
    BandCase("boundary mu 0.05", "boundary friction coefficient 0.05 (friction.tau_s halved)",
             BOUNDARY_LOW),
    BandCase("boundary mu 0.15", "boundary friction coefficient 0.15 (friction.tau_s x 1.5)",
             BOUNDARY_HIGH),
    BandCase("friction off", "no flank friction (friction.enabled = false): its effect, not a "
             "plausible setting", FRICTION_OFF),
    BandCase("rigid teeth", "only the contact deforms (tooth.compliance = 0)", RIGID_TEETH),
    BandCase("bodies 1.4", "gear bodies root/bore radius 1.4 (both gears)", BODY_LOW),
    BandCase("bodies 7", "gear bodies root/bore radius 7 (both gears)", BODY_HIGH),
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
    ("load on the wheel [mN·m]", "load", 1e3, 4),
)
#: Columns computed here rather than by the windowed statistics.
OWN = ("psi", "load")


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
             window: float = 2.0, step: float = 1e-4, setup: dict | None = None) -> BandRow:
    """The scenario with the case's mesh parameters in ``setup`` (driveline parameters;
    default the paper's setup, ``PAPER_SETUP``): its windowed statistics."""
    mesh = MeshParameters(**case.mesh)
    drive = DrivelineParameters(**(PAPER_SETUP if setup is None else setup))
    wall = time.perf_counter()
    rec = simulate(mesh, drive, stop_time=stop_time, step=step, signals=list(SIGNALS))
    wall = time.perf_counter() - wall
    ws = windowed_statistics(rec.time, rec.signals, rec.onset_times, rec.onset_speeds,
                             rec.onset_flanks, mesh.derived()["normal_mass"], transient, window)
    values = {name: ws.scatter(name) for _, name, _, _ in COLUMNS if name not in OWN}
    values["psi"] = Scatter.of([
        mixed_regime_fraction(np.asarray(rec.signals["mesh.n_contact"])[s],
                              np.asarray(rec.signals["mesh.psi"])[s]) for s in ws.slices])
    values["load"] = Scatter.of([float(np.mean(np.asarray(rec.signals["wheel.tau_load"])[s]))
                                 for s in ws.slices])
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


def markdown(rows: list[BandRow], timings: bool = True) -> str:
    """The band as a Markdown table, one row per case, and what each case is (with the wall
    time of its run unless ``timings`` is false: a documented table stays reproducible)."""
    head = "| case | " + " | ".join(h for h, _, _, _ in COLUMNS) + " |"
    rule = "|---" * (len(COLUMNS) + 1) + "|"
    lines = [head, rule]
    for r in rows:
        cells = [cell(r.values[name], scale, digits) for _, name, scale, digits in COLUMNS]
        lines.append(f"| {r.case.name} | " + " | ".join(cells) + " |")
    lines.append("")
    lines += [f"* {r.case.name}: {r.case.meaning}"
              + (f" ({r.seconds:.1f} s)" if timings else "") for r in rows]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m drive_rattle_cosim.band",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--stop-time", type=float, default=11.0)
    parser.add_argument("--transient", type=float, default=1.0)
    parser.add_argument("--window", type=float, default=2.0)
    parser.add_argument("--step", type=float, default=1e-4)
    parser.add_argument("--coupled", action="store_true",
                        help="the coupled driveline instead of the paper's constant load")
    parser.add_argument("--case", action="append", choices=[c.name for c in CASES],
                        help="run only these cases (repeatable; default all)")
    parser.add_argument("--out", type=Path, help="also write the table to this file")
    args = parser.parse_args(argv)
    cases = [c for c in CASES if args.case is None or c.name in args.case]
    rows = []
    for c in cases:
        rows.append(run_case(c, args.stop_time, args.transient, args.window, args.step,
                             COUPLED_SETUP if args.coupled else PAPER_SETUP))
        print(f"{c.name}: {rows[-1].seconds:.1f} s", file=sys.stderr)
    text = markdown(rows)
    print(text)
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
