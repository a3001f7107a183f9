"""One reader for both flavours: a shared corpus of speed tables
and state records (corpus.py: line ends, a byte-order mark, blank lines, quoting, cells of
512 characters and more, a long first row, Unicode digits, huge numbers; records truncated,
extended, edited and large) read by the pythonfmu FMUs, the native FMUs and the model library
in process, each in a child process (readers_run.py).  Every item gives the same status,
message, outputs (bit for bit) and state in all three; the readers take time linear in their
input (an input 10 times larger takes at most about 10 times as long, with generous bounds),
and the table's and record's sizes are capped (row 9, test_library_boundary.py)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from .corpus import TABLES, write_corpus

HERE = Path(__file__).resolve().parent

#: The tables the reader accepts (every other one of corpus.TABLES is refused).
ACCEPTED = {
    "plain", "no header", "crlf", "cr only", "no final newline", "bom header", "bom data",
    "empty lines", "blank lines", "quoted", "quoted spaces", "quoted doubled quote header",
    "spaces around", "extra columns", "trailing comma", "cell 512 time", "cell 512 speed",
    "cell 512 first row data", "cell 512 header", "long first row header",
    "long first row data", "plus and dot", "exponents", "tiny numbers", "negative",
    "many rows"}
#: Tables whose first row is data: it is read, never dropped as a header (their first
#: speed, 80 rad/s, is the pinion speed at the start).
FIRST_ROW_DATA = ("no header", "bom data", "cell 512 first row data", "long first row data")


def _child(args: list, timeout: float = 600) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(HERE), *(
        os.path.abspath(p) for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p)])}
    return subprocess.run([sys.executable, *map(str, args)], capture_output=True, text=True,
                          timeout=timeout, cwd=HERE, env=env)


@pytest.fixture(scope="module")
def corpus(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("corpus")
    index = {name: [item.kind, item.model, str(item.path)]
             for name, item in write_corpus(folder).items()}
    path = folder / "corpus.json"
    path.write_text(json.dumps(index))
    return path


def _read(corpus: Path, fmus, out: Path) -> dict:
    args = ([fmus["GearMeshRattle"], fmus["Driveline"]] if fmus else ["library", "library"])
    run = _child([HERE / "readers_run.py", *args, corpus, out, out.parent / "work"])
    assert run.returncode == 0, f"exit {run.returncode}\n{run.stdout[-2000:]}\n{run.stderr[-4000:]}"
    return json.loads(out.read_text())


@pytest.fixture(scope="module")
def library_results(corpus, tmp_path_factory) -> dict:
    return _read(corpus, None, tmp_path_factory.mktemp("library") / "results.json")


def test_the_library_reads_the_tables_as_documented(library_results):
    for name in TABLES:
        result = library_results[f"table {name}"]
        assert (result["status"] == 0) == (name in ACCEPTED), (name, result)
        if result["status"] != 0:  # a refusal names the table and what is allowed or wrong
            assert "speed table" in result["message"] or "engine.speed_table" in \
                result["message"], (name, result["message"])
    for name in FIRST_ROW_DATA:
        outputs = dict((n, v) for n, _, v in library_results[f"table {name}"]["outputs"])
        plain = dict((n, v) for n, _, v in library_results["table no header"]["outputs"])
        assert outputs["pinion.w"] == plain["pinion.w"], name


def test_the_library_refuses_broken_records_with_a_reason(library_results):
    for name, result in library_results.items():
        if not name.startswith("state "):
            continue
        if " cut at " in name:
            cut = int(name.rsplit(" ", 1)[1])
            assert result["status"] == 3 and (
                "the record ends before" in result["message"] if cut else
                "the record is empty" in result["message"]), (name, result)
        elif name.endswith((" extended", " newer version", " start 1e308", " time nan",
                            " as driveline")):
            assert result["status"] == 3, (name, result)
        elif name.startswith(("state mesh ", "state driveline ", "state large_table",
                              "state large_string")):
            assert result["status"] == 0, (name, result)


@pytest.mark.parametrize("reader", ["pythonfmu", "native"])
@pytest.mark.slow
def test_both_flavours_read_the_corpus_as_the_library_does(reader, corpus, library_results,
                                                           request, tmp_path):
    fmus = request.getfixturevalue("fmus" if reader == "pythonfmu" else "native_fmus")
    results = _read(corpus, fmus, tmp_path / "results.json")
    differ = []
    for name, expected in library_results.items():
        got = {k: v for k, v in results[name].items() if k != "seconds"}
        want = {k: v for k, v in expected.items() if k != "seconds"}
        if got != want:
            differ.append(f"{name}:\n  {reader}: {got}\n  library: {want}")
    assert not differ, f"{len(differ)} of {len(library_results)} items differ:\n" + \
        "\n".join(differ[:8])
    _linear(results, reader)


def test_the_library_reads_in_linear_time(library_results):
    _linear(library_results, "library")


def _linear(results: dict, who: str) -> None:
    """Each large input, 10 times as large, costs at most ~10 times as much (30 allowed, plus
    50 ms of noise; quadratic reading would be ~100 times) and under 10 s."""
    for name, result in results.items():
        if not name.endswith(" 1x"):
            continue
        small, large = result["seconds"], results[name[:-3] + " 10x"]["seconds"]
        assert large <= 30 * small + 0.05 and large < 10.0, (
            f"{who}: {name[:-3]} took {small:.4f} s at 1x and {large:.4f} s at 10x")
