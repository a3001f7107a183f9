"""The status shim (fmu_src/fmi2/rattle_fmi_shim.c) around pythonfmu's binary.

The probe slave (shim_probe/ShimProbe.py) is built with pythonfmu, the shim is installed with
``drive_rattle_build.shim.install_shim`` and the FMU is driven through fmpy's low-level
``FMU2Slave``.  Every FMU run happens in a child process (this file run as a script): without
a working shim several scenarios crash the process (segfault), and that must show up as a
failed test, not as a dead pytest session.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
PROBE = HERE / "shim_probe" / "ShimProbe.py"
OK, WARNING, DISCARD, ERROR, FATAL = range(5)
PERCENT = "%s %d 100%"  # in every message of the probe
RESULT_MARK = "SHIM-SCENARIO-RESULT "
CYCLES = 20
FATAL_CYCLES = 50


# --------------------------------------------------------------- the host side (child process)
def _drive(unzipdir: str, scenario: str, logging_on: bool) -> dict:
    """Run one scenario against the extracted FMU and return what the host observed."""
    from ctypes import byref

    from fmpy import calloc, free, read_model_description
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi2 import (
        FMU2Slave,
        fmi2CallbackAllocateMemoryTYPE,
        fmi2CallbackFreeMemoryTYPE,
        fmi2CallbackFunctions,
        fmi2CallbackLoggerTYPE,
        fmi2String,
        fmi2ValueReference,
    )
    from fmpy.logging import addLoggerProxy

    md = read_model_description(unzipdir)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    log: list[list] = []
    steps: list[list] = []
    names: list[str] = []  # the instance name of each message
    out: dict = {"log": log, "steps": steps, "names": names}

    def logger(env, instance, status, category, message):
        log.append([status, category.decode() if category else None,
                    message.decode("utf-8", "replace") if message else None])
        names.append(instance.decode("utf-8", "replace") if instance else None)

    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(logger)
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    addLoggerProxy(byref(callbacks))  # fmpy's native proxy formats the variadic message

    def record(label, fn, *args):
        """The raw fmi2Status of an fmi2* call (fmpy raises above Warning)."""
        try:
            status = fn(*args)
        except FMICallException as e:
            status = e.status
        steps.append([label, status])
        return status

    def open_slave(mode, name="probe"):
        s = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir,
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
        s.instantiate(callbacks=callbacks, loggingOn=logging_on)
        if mode is not None:
            s.setInteger([vr["mode"]], [mode])
        return s

    def initialize(s):
        record("setup", s.fmi2SetupExperiment, s.component, 0, 0.0, 0.0, 0, 0.0)
        record("enter", s.fmi2EnterInitializationMode, s.component)
        return record("exit", s.fmi2ExitInitializationMode, s.component)

    def survive_cycles():
        """Instantiate, run and free the FMU CYCLES times: the process must survive."""
        done = 0
        for _ in range(CYCLES):
            s = open_slave(0)
            s.setupExperiment(startTime=0.0)
            s.enterInitializationMode()
            s.exitInitializationMode()
            s.doStep(0.0, 0.1)
            s.terminate()
            s.freeInstance()
            done += 1
        out["cycles"] = done

    def get_strings(s, names):
        refs = (fmi2ValueReference * len(names))(*[vr[n] for n in names])
        values = (fmi2String * len(names))()
        status = record("getString", s.fmi2GetString, s.component, refs, len(names), values)
        return status, [v.decode("utf-8") for v in values]

    if scenario == "normal":
        s = open_slave(0)
        out["version"] = s.getVersion()
        initialize(s)
        s.setReal([vr["u"]], [1.5])
        record("doStep", s.fmi2DoStep, s.component, 0.0, 0.1, 1)
        out["y"] = s.getReal([vr["y"]])[0]
        out["label"] = get_strings(s, ["label"])[1]
        state = s.getFMUstate()  # the FMUstate functions just pass the state through
        restored = s.deSerializeFMUstate(s.serializeFMUstate(state))
        s.setReal([vr["u"]], [5.0])
        s.doStep(0.1, 0.1)
        out["y_later"] = s.getReal([vr["y"]])[0]
        s.setFMUstate(restored)
        out["y_restored"] = s.getReal([vr["y"]])[0]
        s.freeFMUstate(state)
        s.freeFMUstate(restored)
        record("terminate", s.fmi2Terminate, s.component)
        s.freeInstance()
    elif scenario == "misaddressed_state":
        from ctypes import POINTER, c_void_p, cast

        s = open_slave(0)
        initialize(s)
        state = s.getFMUstate()
        wrong = cast(state, POINTER(c_void_p))  # the state where its address belongs
        record("getMisaddressed", s.fmi2GetFMUstate, s.component, wrong)
        record("freeMisaddressed", s.fmi2FreeFMUstate, s.component, wrong)
        s.freeFMUstate(state)
        s.freeInstance()
    elif scenario == "exit_error":
        s = open_slave(1)
        initialize(s)
        s.freeInstance()
        survive_cycles()
    elif scenario == "step_error":
        s = open_slave(2)
        initialize(s)
        s.setReal([vr["u"]], [2.0])
        record("doStep", s.fmi2DoStep, s.component, 0.0, 0.1, 1)
        out["y"] = s.getReal([vr["y"]])[0]
        s.freeInstance()
        survive_cycles()
    elif scenario == "warning":
        s = open_slave(3)
        initialize(s)
        record("doStep", s.fmi2DoStep, s.component, 0.0, 0.1, 1)
        s.freeInstance()
    elif scenario == "getter_warning":
        s = open_slave(4)
        initialize(s)
        out["label"] = get_strings(s, ["label", "label"])[1]
        s.freeInstance()
    elif scenario == "reset":
        s = open_slave(1)
        initialize(s)
        record("reset", s.fmi2Reset, s.component)  # pythonfmu builds a new slave object
        out["mode_after_reset"] = s.getInteger([vr["mode"]])[0]
        s.setInteger([vr["mode"]], [1])
        initialize(s)
        s.freeInstance()
    elif scenario == "reuse":
        # a freed instance is kept idle and reset for the next one: a fresh slave, the new
        # instance's name on its messages
        first = open_slave(2, "first")
        initialize(first)
        first.setReal([vr["u"]], [1.0])
        record("doStep-first", first.fmi2DoStep, first.component, 0.0, 0.1, 1)
        first.freeInstance()
        second = open_slave(None, "second")
        out["mode_fresh"] = second.getInteger([vr["mode"]])[0]
        out["u_fresh"] = second.getReal([vr["u"]])[0]
        second.setInteger([vr["mode"]], [2])
        initialize(second)
        record("doStep-second", second.fmi2DoStep, second.component, 0.0, 0.1, 1)
        second.freeInstance()
    elif scenario == "inner_fatal":
        # pythonfmu releases the slave's Python objects at the Fatal and again when the
        # instance is freed.  Re-reading the model description each cycle (as a host opening
        # the FMU anew does) reuses the freed memory, so that double release crashes within a
        # few dozen cycles unless the shim keeps fmi2FreeInstance away from pythonfmu.
        for _ in range(FATAL_CYCLES):
            read_model_description(unzipdir)
            s = open_slave(5)
            initialize(s)
            record("doStep", s.fmi2DoStep, s.component, 0.0, 0.1, 1)
            record("doStep-after-fatal", s.fmi2DoStep, s.component, 0.1, 0.1, 1)
            s.freeInstance()
        survive_cycles()
    elif scenario == "uri_forms":
        from urllib.parse import quote

        resources = str(Path(unzipdir, "resources").resolve())
        forms = {"localhost": "file://localhost" + quote(resources),
                 "single-slash": "file:" + quote(resources),
                 "plain-path": resources}
        for label, uri in forms.items():
            s = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir,
                          modelIdentifier=md.coSimulation.modelIdentifier, instanceName="probe")
            s.callbacks = callbacks
            s.component = s.fmi2Instantiate(b"probe", 1, md.guid.encode(), uri.encode(),
                                            byref(callbacks), 0, 0)
            if not s.component:
                out[label] = None
                continue
            initialize(s)
            s.setReal([vr["u"]], [0.5])
            s.doStep(0.0, 0.1)
            out[label] = s.getReal([vr["y"]])[0]
            s.freeInstance()
    elif scenario == "missing_inner":
        try:
            open_slave(0)
            out["instantiated"] = True
        except Exception as e:  # fmpy raises a plain Exception for a NULL component
            out["instantiated"] = False
            out["error"] = str(e)
    else:
        raise ValueError(scenario)
    return out


# --------------------------------------------------------------- the test side
@pytest.fixture(scope="module")
def fmus(tmp_path_factory) -> dict:
    """The probe FMU built with pythonfmu, as is ("plain") and with the shim ("shim")."""
    if shutil.which("gcc") is None:
        pytest.skip("gcc is not installed: the status shim cannot be compiled")
    from fmpy import read_model_description

    from drive_rattle_build.shim import install_shim

    out = tmp_path_factory.mktemp("shim_fmus")
    build = subprocess.run(
        [sys.executable, "-m", "pythonfmu", "build", "-f", str(PROBE), "-d", str(out)],
        capture_output=True, text=True, check=False)
    assert build.returncode == 0, build.stdout + build.stderr
    shim = out / "ShimProbe.fmu"
    (out / "plain").mkdir()
    plain = Path(shutil.copy(shim, out / "plain" / "ShimProbe.fmu"))
    vr = {v.name: v.valueReference for v in read_model_description(shim).modelVariables}
    install_shim(shim, vr["_fmi.status_address"], vr["_fmi.message"])
    return {"plain": plain, "shim": shim, "vr": vr}


def run(fmu: Path, unzipdir: Path, scenario: str, logging_on: bool = False) -> dict:
    """Extract ``fmu`` into ``unzipdir`` and run ``scenario`` in a child process."""
    from fmpy import extract

    if not unzipdir.exists():
        extract(fmu, unzipdir)
    proc = subprocess.run(
        [sys.executable, __file__, str(unzipdir), scenario, "1" if logging_on else "0"],
        capture_output=True, text=True, check=False, timeout=300)
    results = [line for line in proc.stdout.splitlines() if line.startswith(RESULT_MARK)]
    assert proc.returncode == 0 and results, (
        f"scenario {scenario!r} died (exit {proc.returncode})\n"
        f"stdout:\n{proc.stdout[-3000:]}\nstderr:\n{proc.stderr[-3000:]}")
    return json.loads(results[0][len(RESULT_MARK):])


def statuses(result: dict) -> dict:
    return dict(result["steps"])


def test_install_shim_replaces_only_the_linux64_binary(fmus):
    from drive_rattle_build.shim import install_shim

    binary, inner = "binaries/linux64/ShimProbe.so", "binaries/linux64/ShimProbe_pythonfmu.so"
    with zipfile.ZipFile(fmus["plain"]) as z:
        before = {i.filename: z.read(i) for i in z.infolist()}
    with zipfile.ZipFile(fmus["shim"]) as z:
        after = {i.filename: z.read(i) for i in z.infolist()}
    assert set(after) - set(before) == {inner}
    assert after[inner] == before[binary]
    assert after[binary] != before[binary]
    assert after[binary][:4] == b"\x7fELF"
    assert {k: v for k, v in after.items() if k not in (binary, inner)} == \
        {k: v for k, v in before.items() if k != binary}
    with pytest.raises(ValueError, match="already contains the shim"):
        install_shim(fmus["shim"], fmus["vr"]["_fmi.status_address"], fmus["vr"]["_fmi.message"])


def test_normal_run_passes_through(fmus, tmp_path):
    r = run(fmus["shim"], tmp_path / "fmu", "normal")
    assert statuses(r) == {"setup": OK, "enter": OK, "exit": OK, "doStep": OK,
                           "getString": OK, "terminate": OK}
    assert r["y"] == 3.0
    assert (r["y_later"], r["y_restored"]) == (10.0, 3.0)
    assert r["label"] == ["probe label"]
    assert r["version"] == "2.0"
    assert r["log"] == []


def test_a_state_passed_where_its_address_belongs_is_refused(fmus, tmp_path):
    """fmusim 0.0.39 passes the state itself to fmi2FreeFMUstate (FMI asks for its address):
    refused with a message, never dereferenced (it crashed the FMU)."""
    r = run(fmus["shim"], tmp_path / "fmu", "misaddressed_state")
    assert statuses(r)["getMisaddressed"] == statuses(r)["freeMisaddressed"] == ERROR
    messages = [m for _, _, m in r["log"]]
    assert [m.split(":")[0] for m in messages] == ["fmi2GetFMUstate", "fmi2FreeFMUstate"]
    assert all("points to an FMU state, not to the host's variable that holds one" in m
               for m in messages)


def test_error_at_exit_initialization_is_returned_and_logged_without_debug_logging(fmus, tmp_path):
    r = run(fmus["shim"], tmp_path / "fmu", "exit_error", logging_on=False)
    assert statuses(r)["exit"] == ERROR
    assert r["log"] == [[ERROR, "logStatusError", f"exit refused {PERCENT}"]]
    assert r["cycles"] == CYCLES  # freeing after the Error and re-instantiating is safe


def test_error_at_do_step_is_returned_and_logged(fmus, tmp_path):
    r = run(fmus["shim"], tmp_path / "fmu", "step_error")
    assert statuses(r)["doStep"] == ERROR
    assert r["log"] == [[ERROR, "logStatusError", f"step refused at t=0.0 {PERCENT}"]]
    assert r["y"] == 4.0  # the instance stays usable after the Error
    assert r["cycles"] == CYCLES


def test_warning_and_pythonfmu_log_messages_arrive_verbatim(fmus, tmp_path):
    r = run(fmus["shim"], tmp_path / "fmu", "warning", logging_on=True)
    assert statuses(r)["doStep"] == WARNING
    # pythonfmu's own message (debug logging on) first, then the shim's status message
    assert [WARNING, "logStatusWarning", f"pythonfmu log {PERCENT}"] in r["log"]
    assert r["log"][-1] == [WARNING, "logStatusWarning", f"step warning {PERCENT}"]


def test_string_values_survive_the_message_fetch(fmus, tmp_path):
    r = run(fmus["shim"], tmp_path / "fmu", "getter_warning")
    assert statuses(r)["getString"] == WARNING
    assert r["label"] == ["probe label", "probe label"]
    assert r["log"] == [[WARNING, "logStatusWarning", f"label getter warning {PERCENT}"]]


def test_reset_reads_the_new_status_address(fmus, tmp_path):
    r = run(fmus["shim"], tmp_path / "fmu", "reset")
    exits = [status for label, status in r["steps"] if label == "exit"]
    assert exits == [ERROR, ERROR]
    assert statuses(r)["reset"] == OK
    assert r["mode_after_reset"] == 0
    assert [m[2] for m in r["log"]] == [f"exit refused {PERCENT}"] * 2


def test_a_freed_instance_is_reset_for_the_next_one(fmus, tmp_path):
    """pythonfmu's instantiation leaks: the shim keeps a freed instance idle and resets it for
    the next fmi2Instantiate of the same resources folder; the host sees a new instance."""
    r = run(fmus["shim"], tmp_path / "fmu", "reuse")
    assert statuses(r)["doStep-first"] == statuses(r)["doStep-second"] == ERROR
    assert (r["mode_fresh"], r["u_fresh"]) == (0, 0.0)  # a new slave object
    assert r["names"] == ["first", "second"]
    assert [m[2] for m in r["log"]] == [f"step refused at t=0.0 {PERCENT}"] * 2


def test_resource_directory_with_non_ascii_percent_and_space(fmus, tmp_path):
    unzipdir = tmp_path / "dïr 100% é" / "fmu"
    r = run(fmus["shim"], unzipdir, "normal")
    assert statuses(r)["exit"] == OK
    assert r["y"] == 3.0
    r = run(fmus["shim"], unzipdir, "exit_error")
    assert r["log"] == [[ERROR, "logStatusError", f"exit refused {PERCENT}"]]


def test_resource_uri_forms(fmus, tmp_path):
    r = run(fmus["shim"], tmp_path / "dïr 100% é" / "fmu", "uri_forms")
    assert (r["localhost"], r["single-slash"], r["plain-path"]) == (1.0, 1.0, 1.0)
    assert all(status == OK for _, status in r["steps"])


def test_missing_inner_library_is_reported(fmus, tmp_path):
    from fmpy import extract

    unzipdir = tmp_path / "fmu"
    extract(fmus["shim"], unzipdir)
    (unzipdir / "binaries" / "linux64" / "ShimProbe_pythonfmu.so").unlink()
    r = run(fmus["shim"], unzipdir, "missing_inner")
    assert r["instantiated"] is False
    [(status, category, message)] = r["log"]
    assert (status, category) == (FATAL, "logStatusFatal")
    assert message.startswith("rattle FMI shim: fmi2Instantiate: cannot load ")
    assert "ShimProbe_pythonfmu.so" in message


def test_fatal_from_pythonfmu_then_free_leaves_the_process_healthy(fmus, tmp_path):
    r = run(fmus["shim"], tmp_path / "fmu", "inner_fatal")
    assert [s for label, s in r["steps"] if label == "doStep"] == [FATAL] * FATAL_CYCLES
    # later calls are refused by the shim instead of reaching the broken instance
    assert [s for label, s in r["steps"] if label == "doStep-after-fatal"] == [FATAL] * FATAL_CYCLES
    assert r["cycles"] == CYCLES


def test_without_the_shim_the_error_is_lost(fmus, tmp_path):
    """Control: pythonfmu alone returns OK and, without debug logging, logs nothing."""
    r = run(fmus["plain"], tmp_path / "fmu", "exit_error")
    assert statuses(r)["exit"] == OK
    assert r["log"] == []


def test_compile_shim_reports_compiler_errors(tmp_path, monkeypatch):
    if shutil.which("gcc") is None:
        pytest.skip("gcc is not installed")
    from drive_rattle_build import shim

    broken = tmp_path / "broken.c"
    broken.write_text("int f(void) { return missing_symbol; }\n")
    monkeypatch.setattr(shim, "SHIM_SOURCE", broken)
    with pytest.raises(RuntimeError, match="missing_symbol"):
        shim.compile_shim(tmp_path / "x.so", "x_pythonfmu.so", 4, 5)
    with pytest.raises(ValueError):
        shim.compile_shim(tmp_path / "x.so", "../x.so", 4, 5)
    with pytest.raises(ValueError, match="model_identifier"):
        shim.compile_shim(tmp_path / "x.so", "x.so", 4, 5, model_identifier='a"; b')
    with pytest.raises(ValueError, match="vr_last_successful_time"):
        shim.compile_shim(tmp_path / "x.so", "x.so", 4, 5, vr_last_successful_time=-1)


if __name__ == "__main__":
    _unzipdir, _scenario, _logging_on = sys.argv[1:4]
    print(RESULT_MARK + json.dumps(_drive(_unzipdir, _scenario, _logging_on == "1")), flush=True)
