"""Many instances, instantiate/free cycles, a soak of 10^6 steps with resident memory measured,
rollback across processes, determinism.  Each scenario runs in its own process."""

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from drive_rattle_cosim.harness import CoSimulation

SCRIPT = Path(__file__).with_name("endurance.py")
PROBE = Path(__file__).resolve().parents[1] / "fmi" / "shim_probe" / "ShimProbe.py"


def scenario(*args, timeout=900) -> dict:
    run = subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], capture_output=True,
                         text=True, timeout=timeout)
    assert run.returncode == 0, f"rc {run.returncode}\n{run.stderr[-3000:]}"
    return json.loads(run.stdout.strip().splitlines()[-1])


def slope_kib_per_cycle(report) -> float:
    rss = np.asarray(report["rss_kib"], dtype=float)
    return float(np.polyfit(np.arange(len(rss)) * 100, rss, 1)[0])


@pytest.fixture(scope="module")
def probe_fmu(tmp_path_factory):
    """A trivial pythonfmu slave with the same shim: pythonfmu's own per-cycle baseline."""
    if shutil.which("gcc") is None:
        pytest.skip("gcc is not installed: the native shim cannot be compiled")
    from fmpy import read_model_description

    from drive_rattle_build.shim import install_shim

    out = tmp_path_factory.mktemp("probe")
    subprocess.run([sys.executable, "-m", "pythonfmu", "build", "-f", str(PROBE), "-d",
                    str(out)], check=True, capture_output=True)
    fmu = out / "ShimProbe.fmu"
    vr = {v.name: v.valueReference for v in read_model_description(str(fmu)).modelVariables}
    install_shim(fmu, vr["_fmi.status_address"], vr["_fmi.message"])
    return fmu


def test_instantiate_free_cycles_add_no_memory_beyond_pythonfmu(fmus, probe_fmu):
    """1000 cycles of each FMU.  pythonfmu's wrapper itself keeps about 10-20 kB per
    instantiation (measured with a trivial probe slave): our slaves must add nothing to it."""
    baseline = slope_kib_per_cycle(scenario("cycles", probe_fmu, 1000))
    for name in ("GearMeshRattle", "Driveline"):
        report = scenario("cycles", fmus[name], 1000)
        assert report["cycles"] == 1000
        slope = slope_kib_per_cycle(report)
        print(f"{name}: {slope:.1f} kiB/cycle, probe {baseline:.1f} kiB/cycle")
        assert slope <= 1.25 * baseline + 2.0, (name, slope, baseline)


def test_soak_of_a_million_steps_keeps_memory_flat(fmus):
    report = scenario("soak", fmus["GearMeshRattle"].parent, 1_000_000, timeout=1800)
    rss = report["rss_kib"]
    print(f"soak: {report['seconds']:.0f} s, RSS {rss[0]}..{rss[-1]} kiB, impacts "
          f"{report['impacts']}")
    assert report["finite"] and min(report["impacts"]) > 1000
    # After warm-up (the first sample), resident memory does not grow.
    assert max(rss[1:]) - rss[1] < 1024, rss


def test_several_instances_of_both_fmus_in_one_process(fmus):
    report = scenario("many", fmus["GearMeshRattle"].parent)
    assert report == {"same_as_twin": True, "differs": True}


def test_serialized_state_restored_in_another_process(fmus, tmp_path):
    blob = tmp_path / "state.bin"
    saved = scenario("save", fmus["GearMeshRattle"].parent, blob)
    restored = scenario("restore", fmus["GearMeshRattle"].parent, blob)
    assert restored["rows"] == saved["rows"]
    assert len(saved["rows"]) == 40


def test_same_run_twice_is_bit_identical(fmus):
    a = scenario("once", fmus["GearMeshRattle"].parent)
    b = scenario("once", fmus["GearMeshRattle"].parent)
    assert a == b
    with CoSimulation(fmus["GearMeshRattle"], fmus["Driveline"]) as sim:
        here = sim.run(0.05)
    assert {k: [repr(v) for v in c] for k, c in here.columns.items()} == a["columns"]
