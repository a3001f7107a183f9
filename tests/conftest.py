"""Session fixtures and the test layers.

Every test carries the marker of its layer, from its folder (registered in pyproject.toml;
``pytest -m model`` runs one layer, ``pytest -m "not slow"`` leaves the long ones out):

* ``model``: tests/model -- the model library against closed forms, properties, the readable
  equations of tests/oracle and the monolithic reference; the package structure;
* ``analysis``: tests/analysis -- the statistics and spectral lines of the studies;
* ``fmi``: tests/fmi -- the slave classes instantiated directly and the native shim;
* ``fmu``: tests/faces, tests/fmu, tests/cosim, tests/adversarial, tests/native, tests/fmi3 --
  the built FMUs (both flavours, and the FMI 3.0 FMUs) in fmpy, the other masters and native
  hosts;
* ``sanitize``: tests/sanitize -- the C built and run under AddressSanitizer and
  UndefinedBehaviorSanitizer;
* ``examples``: tests/test_*.py -- the README's commands and the examples.

``slow`` (tests that take more than about 10 s) is set on the tests themselves.

``seeded`` marks every test that draws at random (the property tests of hypothesis, found
here, and the boundary fuzzers, marked themselves): their seeds are fixed (the ``ci``
profile below, tests/seeds.py), so that one commit gives one answer; ``tests/soak.py`` runs
them on fresh seeds.
"""

import os
from pathlib import Path

import pytest
from hypothesis import settings

from drive_rattle_build import build

# The property tests draw the same examples on every run (derandomized: from each test's own
# code) and use no example database, so a run depends on the commit alone; the soak profile
# draws fresh examples from pytest's --hypothesis-seed (tests/soak.py).
settings.register_profile("ci", derandomize=True, database=None, print_blob=True)
settings.register_profile("soak", derandomize=False, database=None, print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


TESTS = Path(__file__).resolve().parent
#: Layer marker of each test folder (tests directly in tests/: "examples").
LAYERS = {"model": "model", "analysis": "analysis", "fmi": "fmi", "fmu": "fmu", "cosim": "fmu",
          "adversarial": "fmu", "faces": "fmu", "native": "fmu", "fmi3": "fmu",
          "sanitize": "sanitize"}


def pytest_configure(config):
    """The model library built from this checkout's sources before anything is collected (a
    fresh clone has none; the tests, the oracle's start and the studies load it)."""
    from drive_rattle_build.library import build_in_place

    build_in_place()


def pytest_collection_modifyitems(config, items):
    for item in items:
        folder = Path(str(item.fspath)).resolve().relative_to(TESTS).parts[0]
        item.add_marker(getattr(pytest.mark, LAYERS.get(folder, "examples")))
        if getattr(getattr(item, "obj", None), "is_hypothesis_test", False):
            item.add_marker(pytest.mark.seeded)


@pytest.fixture(scope="session")
def fmus(tmp_path_factory):
    """{'GearMeshRattle': path, 'Driveline': path}, built and validated for this session."""
    out = tmp_path_factory.mktemp("dist")
    paths = build(out)
    return {p.stem: p for p in paths}


@pytest.fixture(scope="session")
def native_fmus(tmp_path_factory):
    """{'GearMeshRattle': path, 'Driveline': path}: the native (C only) FMUs, linux64 and win64
    binaries and sources, built and validated for this session."""
    from drive_rattle_build.native import build_native  # on first use: the native build alone

    out = tmp_path_factory.mktemp("dist_native")
    paths = build_native(out)
    return {p.stem: p for p in paths}


@pytest.fixture(scope="session")
def fmi3_fmus(tmp_path_factory):
    """{'GearMeshRattle': path, 'Driveline': path}: the FMI 3.0 FMUs (C only, x86_64-linux and
    x86_64-windows binaries and sources), built, held against their templates and validated
    for this session."""
    from drive_rattle_build.fmi3 import build_fmi3  # on first use: the FMI 3.0 build alone

    out = tmp_path_factory.mktemp("dist_fmi3")
    return {p.stem: p for p in build_fmi3(out)}


@pytest.fixture(scope="session")
def wine_env(tmp_path_factory) -> dict:
    """The environment of every program run under wine this session: one wine prefix, made by
    the first run (a new prefix takes about a minute)."""
    prefix = tmp_path_factory.mktemp("wineprefix")
    return {**os.environ, "WINEPREFIX": str(prefix), "WINEDEBUG": "-all",
            "WINEDLLOVERRIDES": "mscoree,mshtml="}  # no .NET/Gecko installers in a new prefix


FLAVOURS = ("pythonfmu", "native")


@pytest.fixture(scope="session", params=FLAVOURS)
def flavour_fmus(request):
    """The FMUs of each flavour in turn: the pythonfmu FMUs and the native ones."""
    return request.getfixturevalue("fmus" if request.param == "pythonfmu" else "native_fmus")


#: Seconds spent in the tests (setup, call and teardown), split by whether they are slow.
_SECONDS = {"not slow": 0.0, "slow": 0.0}


def pytest_runtest_logreport(report):
    item_slow = "slow" in report.keywords
    _SECONDS["slow" if item_slow else "not slow"] += report.duration


def pytest_terminal_summary(terminalreporter):
    """The fast layer's time beside the slow one's (a session fixture's build counts for the
    first test that uses it)."""
    terminalreporter.write_line(
        f"time in tests: {_SECONDS['not slow']:.0f} s not slow, {_SECONDS['slow']:.0f} s slow")
