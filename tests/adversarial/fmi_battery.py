"""Bad input through the FMI interface of a built FMU, case by case (run as a script in a
subprocess, so that a crash of the host shows up as a failed test, not a dead test session).

    python fmi_battery.py <GearMeshRattle.fmu|Driveline.fmu>   -> JSON list of case results
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

from fmpy.fmi1 import FMICallException

from drive_rattle_cosim.harness import Unit

H = 1e-4
INPUTS = {
    "GearMeshRattle": {"pinion.phi": 0.0, "pinion.w": 86.92, "pinion.a": 0.0,
                       "wheel.tau_load": 0.17},
    "Driveline": {"wheel.phi": 0.0, "wheel.w": 44.57},
}
BAD_VALUES = [math.nan, math.inf, -math.inf, 1e300, -1e300]


def status_of(fn, *args) -> int:
    try:
        fn(*args)
        return 0
    except FMICallException as err:
        return err.status


class Case:
    """A fresh instance, initialized and stepped STEPS times unless ``raw``."""

    STEPS = 5

    def __init__(self, fmu: Path, raw: bool = False):
        self.u = Unit(fmu, "adv")
        self.model = self.u.model_name
        self.k = 0
        if not raw:
            self.u.slave.setupExperiment(startTime=0.0)
            self.u.slave.enterInitializationMode()
            self.u.set(INPUTS[self.model])
            self.u.slave.exitInitializationMode()
            for _ in range(self.STEPS):
                self.step()

    def outputs(self) -> list:
        names = [v.name for v in self.u.variables.values() if v.causality == "output"]
        real = [self.u.var(n).vr for n in names if self.u.var(n).fmi_type == "Real"]
        ints = [self.u.var(n).vr for n in names if self.u.var(n).fmi_type == "Integer"]
        return [repr(x) for x in self.u.slave.getReal(real)] + self.u.slave.getInteger(ints)

    def step(self) -> int:
        t = self.k * H
        if self.model == "GearMeshRattle":  # the pinion moves on with its speed, as driven
            self.u.set({"pinion.phi": INPUTS[self.model]["pinion.w"] * t})
        st = status_of(self.u.slave.doStep, t, H)
        if st == 0:
            self.k += 1
        return st

    def message(self) -> str:
        return self.u.messages[-1][1] if self.u.messages else ""

    def close(self) -> None:
        self.u.close()


def run_case(fmu, name, action, raw=False, expect_state_kept=True) -> dict:
    """Run ``action(case) -> status``; record status, message, whether outputs and the
    continuation are unchanged, and whether freeing worked."""
    c = Case(fmu, raw)
    before = None if raw else c.outputs()
    status = action(c)
    rec = {"case": name, "status": status, "message": c.message()}
    if not raw and expect_state_kept:
        rec["outputs_kept"] = c.outputs() == before
        # The rejected call left nothing behind: continuing gives what a clean instance gives.
        c.u.set(INPUTS[c.model])
        ref = Case(fmu)
        ours = [c.step() for _ in range(5)] + [c.outputs()]
        theirs = [ref.step() for _ in range(5)] + [ref.outputs()]
        rec["continuation_kept"] = ours == theirs
        ref.close()
    c.close()
    rec["freed"] = True
    return rec


def cases(fmu: Path) -> list[dict]:
    model = Unit(fmu, "probe")
    names = model.model_name
    variables = model.variables
    model.close()
    out = []
    for inp in INPUTS[names]:
        for bad in BAD_VALUES:
            def act(c, inp=inp, bad=bad):
                c.u.set({inp: bad})
                return status_of(c.u.slave.doStep, c.k * H, H)
            out.append(run_case(fmu, f"input {inp} = {bad!r}", act))
    for h in (0.0, -H, math.nan, math.inf, 1e300, 2.0):  # solver.h_comm_max = 1 s
        out.append(run_case(fmu, f"step size {h!r}",
                            lambda c, h=h: status_of(c.u.slave.doStep, c.k * H, h)))
    for label, t in (("gap", lambda k: (k + 10) * H), ("backwards", lambda k: (k - 1) * H),
                     ("nan", lambda k: math.nan)):
        out.append(run_case(fmu, f"communication point {label}",
                            lambda c, t=t: status_of(c.u.slave.doStep, t(c.k), H)))
    # Calls out of order.
    out.append(run_case(fmu, "doStep before initialization",
                        lambda c: status_of(c.u.slave.doStep, 0.0, H), raw=True))
    out.append(run_case(fmu, "exitInitializationMode before enterInitializationMode",
                        lambda c: status_of(c.u.slave.exitInitializationMode), raw=True))
    out.append(run_case(fmu, "enterInitializationMode twice",
                        lambda c: status_of(c.u.slave.enterInitializationMode)))
    out.append(run_case(fmu, "setupExperiment after initialization",
                        lambda c: status_of(c.u.slave.setupExperiment, None, 0.0)))
    param = next(v for v in variables.values() if v.causality == "parameter"
                 and v.fmi_type == "Real")
    out.append(run_case(fmu, f"fixed parameter {param.name} set after initialization",
                        lambda c: status_of(c.u.slave.setReal, [param.vr], [1.0])))
    out.append(run_case(fmu, "getReal of an unknown value reference",
                        lambda c: status_of(c.u.slave.getReal, [99999])))
    out.append(run_case(fmu, "setReal of an output",
                        lambda c: status_of(c.u.slave.setReal, [next(
                            v.vr for v in variables.values() if v.causality == "output")],
                            [1.0])))

    def after_terminate(c):
        c.u.slave.terminate()
        return status_of(c.u.slave.doStep, c.k * H, H)
    out.append(run_case(fmu, "doStep after terminate", after_terminate,
                        expect_state_kept=False))
    return out


def parameter_cases(fmu: Path) -> list[dict]:
    """Every numeric parameter at and beyond its limits, at exitInitializationMode."""
    from fmpy import read_model_description

    md = read_model_description(str(fmu))
    out = []
    for v in md.modelVariables:
        if v.causality == "parameter" and v.type == "String":
            c = Case(fmu, raw=True)
            c.u.slave.setupExperiment(startTime=0.0)
            c.u.slave.enterInitializationMode()
            c.u.set({**INPUTS[c.model], v.name: "/nonexistent/table.csv"})
            out.append({"case": f"parameter {v.name} names a missing file", "parameter": v.name,
                        "kind": "beyond", "status": status_of(c.u.slave.exitInitializationMode),
                        "message": c.message()})
            c.close()
        if v.causality != "parameter" or v.type not in ("Real", "Integer", "Enumeration"):
            continue
        cast = float if v.type == "Real" else int
        trials = []
        lo, hi = v.min, v.max
        if v.type == "Enumeration" and lo is None and hi is None:  # the codes are its items
            codes = [int(item.value) for item in v.declaredType.items]
            lo, hi = min(codes), max(codes)
        for bound, side in ((lo, -1), (hi, +1)):
            if bound is None:
                continue
            b = cast(bound)
            beyond = b + side * (max(abs(b), 1.0) * 1e-3 if v.type == "Real" else 1)
            trials += [("at", b), ("beyond", beyond)]
        if v.type == "Real":
            trials.append(("beyond", math.nan))
        for kind, value in trials:
            c = Case(fmu, raw=True)
            c.u.slave.setupExperiment(startTime=0.0)
            c.u.slave.enterInitializationMode()
            c.u.set({**INPUTS[c.model], v.name: value})
            st = status_of(c.u.slave.exitInitializationMode)
            rec = {"case": f"parameter {v.name} {kind} limit: {value!r}", "parameter": v.name,
                   "kind": kind, "status": st, "message": c.message()}
            if st == 0:  # accepted: a few steps must give finite outputs or a clean refusal
                steps = [c.step() for _ in range(3)]
                rec["steps"] = steps
                rec["step_message"] = c.message() if any(steps) else ""
                rec["finite"] = all(math.isfinite(float(x)) for x in c.outputs())
            c.close()
            out.append(rec)
    return out


if __name__ == "__main__":
    fmu = Path(sys.argv[1])
    results = cases(fmu) + parameter_cases(fmu)
    # Finally the process still makes healthy instances.
    c = Case(fmu)
    results.append({"case": "healthy instance afterwards", "status": c.step(), "message": ""})
    c.close()
    print(json.dumps(results))
