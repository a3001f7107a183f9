"""Accuracy of the coupled system against the communication step (docs/tools.md).

    python benchmarks/step_accuracy.py [--stop-time 2] [--steps 1e-5 2e-5 ... 2e-2]

Runs the default system in the model library's compiled loop at each communication step, three
times with the phase of engine order 1 moved by 0, 1e-6 and 2e-6 rad (rattle is chaotic: their
spread is the scatter a statistic has at a step anyway), and prints per step the mean and the
range of the rattle statistics over the three runs and the largest change of a mean against the
finest step, or the reason the step was refused (``drive_rattle_cosim.step_accuracy``; the
same table is in docs/tools.md, written by ``python build_fmu.py --update-docs``).
"""

from __future__ import annotations

import argparse

from drive_rattle_cosim.step_accuracy import STEPS, STOP_TIME, table


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--stop-time", type=float, default=STOP_TIME, help="[s]")
    ap.add_argument("--steps", type=float, nargs="+", default=list(STEPS), help="[s]")
    args = ap.parse_args(argv)
    print(table(args.steps, args.stop_time), end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
