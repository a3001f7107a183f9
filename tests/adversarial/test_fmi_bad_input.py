"""Bad input through the FMI interface of the built FMUs of both flavours, pythonfmu and native
(the battery runs in a subprocess: a crash of the host would be a failed test, not a dead
session)."""

import functools
import json
import subprocess
import sys
from pathlib import Path

import pytest

#: The battery takes 5-11 s per FMU: the whole file is in the slow layer.
pytestmark = pytest.mark.slow

BATTERY = Path(__file__).with_name("fmi_battery.py")
ERROR = 3


MODELS = ("GearMeshRattle", "Driveline")
CASES = [(flavour, model) for flavour in ("pythonfmu", "native") for model in MODELS]


@functools.cache
def run_battery(fmu: Path) -> list[dict]:
    """The battery's results for one built FMU (once per session)."""
    run = subprocess.run([sys.executable, str(BATTERY), str(fmu)],
                         capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, f"the host process died: rc {run.returncode}\n{run.stderr[-3000:]}"
    return json.loads(run.stdout.strip().splitlines()[-1])


def _fmus(request, flavour: str) -> dict:
    return request.getfixturevalue("fmus" if flavour == "pythonfmu" else "native_fmus")


@pytest.fixture(scope="module", params=CASES, ids=[f"{f}-{m}" for f, m in CASES])
def battery(request):
    flavour, model = request.param
    return model, run_battery(_fmus(request, flavour)[model])


@pytest.mark.parametrize("model", MODELS)
def test_both_flavours_answer_every_case_alike(request, model):
    """The native FMUs give every case of the battery the pythonfmu FMUs' status, message and
    outcome (state kept, continuation, limits accepted or refused)."""
    python = run_battery(_fmus(request, "pythonfmu")[model])
    native = run_battery(_fmus(request, "native")[model])
    assert [r["case"] for r in native] == [r["case"] for r in python]
    for p, n in zip(python, native, strict=True):
        assert n == p


def test_every_bad_call_is_refused_with_a_message_and_changes_nothing(battery):
    _, results = battery
    calls = [r for r in results
             if "parameter" not in r and r["case"] != "healthy instance afterwards"]
    assert len(calls) >= 20
    for r in calls:
        assert r["status"] == ERROR, r
        assert r["message"], r
        assert r["freed"]
        if "outputs_kept" in r:
            assert r["outputs_kept"] and r["continuation_kept"], r
    inputs = [r for r in calls if r["case"].startswith("input ")]
    for r in inputs:  # the message names the input and its value
        name, value = r["case"][len("input "):].split(" = ")
        assert f"input '{name}' = {value}" in r["message"], r


def test_every_parameter_at_and_beyond_its_limits(battery):
    _, results = battery
    params = [r for r in results if "parameter" in r]
    assert params
    for r in params:
        if r["kind"] == "beyond":
            assert r["status"] == ERROR, r
            assert f"'{r['parameter']}'" in r["message"] and "allowed" in r["message"], r
        elif r["status"] == 0:  # accepted at the limit: it runs with finite outputs, or its
            # steps are refused with the reason (e.g. solver.h_comm_max below the step)
            assert r["finite"], r
            assert r["steps"] == [0, 0, 0] or (
                set(r["steps"]) <= {0, ERROR} and "allowed" in r["step_message"]), r
        else:  # refused at the limit by a range or a combination check, with the reason
            assert r["status"] == ERROR and "allowed" in r["message"], r


def test_process_keeps_making_healthy_instances(battery):
    _, results = battery
    assert results[-1] == {"case": "healthy instance afterwards", "status": 0, "message": ""}
