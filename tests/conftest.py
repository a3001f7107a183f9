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

``cross`` is set on the tests of the binaries for other platforms than the build machine's
(the Windows and aarch64-linux binaries, under wine and qemu-user); it implies ``slow``.  They
alone ask for the FMUs of every shipped platform (``shipped_native_fmus``,
``shipped_fmi3_fmus``, tests/faces' ``shipped_face_fmus``), whose build needs zig's
x86_64-windows C runtime (86 s of a core on a new machine, in a CI run here); every other
test gets the FMUs built for the build machine alone, and never waits for a cross compiler.

``slow`` is set on the tests themselves: every test that takes more than about 5 s on a
2-core machine running the suite on both cores (``--durations`` of the README's command), so
that ``-m "not slow"`` is a loop of minutes (on 2026-12-02: 155 s on one such machine,
108-115 s on another; on 2026-12-03 131.6 s on a third, with zig's cache filled for this
clone, 323 s with zig building its x86_64-windows C runtime first; 1499 tests; 110.0 s on
that third machine once the run kept one object cache for its builds, 1500 tests; on
2026-12-04 73-87 s in the first session of the README's command on eight fresh clones of a
fourth, 67 s warm, 1504 tests).

``seeded`` marks every test that draws at random (the property tests of hypothesis, found
here, and the boundary fuzzers, marked themselves): their seeds are fixed (the ``ci``
profile below, tests/seeds.py), so that one commit gives one answer; ``tests/soak.py`` runs
them on fresh seeds.
"""

import contextlib
import fcntl
import importlib
import json
import os
import pkgutil
import shutil
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from hypothesis import settings

from drive_rattle_build import build
from drive_rattle_build.platforms import FMI2_SHIPPED, FMI3_SHIPPED, build_machine

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
    fresh clone has none; the tests, the oracle's start and the studies load it).  Under
    pytest-xdist the controller builds it before it starts the workers, which find it built.

    Every build of the run, in any worker or subprocess, keeps its compiled objects in one
    folder (``DRIVE_RATTLE_OBJECT_CACHE``, drive_rattle_build.compiler): the suite builds the
    same C with the same flags in many tests (the library, each face, the sanitizer builds),
    and a build finds an object compiled from the same inputs there.  The folder is pytest's
    cache's (``.pytest_cache/d/drive_rattle_objects``, emptied by ``--cache-clear``), so the
    README's second session (``-m slow``) finds the objects of the first; an object is keyed
    by every input of its compile, the compiler's identity included, and objects a day old
    are removed when a session starts.  tests/test_wheel.py's build from the installed wheel
    uses it too: the key holds every file a compile reads from the wheel, by name and bytes.

    OpenBLAS runs one thread in each process of the run (``OPENBLAS_NUM_THREADS=1`` unless
    set): the run already keeps every core busy with one worker each, and after each call an
    OpenBLAS pool keeps spinning on the other cores for a while (a 50 x 50 product followed by
    0.5 s of other work: 0.58-0.62 CPU-s against 0.34-0.44 with one thread).  The fast layer of
    tests/model, tests/analysis and tests/cosim on two workers: 158-163 CPU-s against 151-153
    with one thread, the same results."""
    from drive_rattle_build.compiler import OBJECT_CACHE
    from drive_rattle_build.library import build_in_place

    if not hasattr(config, "workerinput"):
        os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # inherited by workers, subprocesses
        if OBJECT_CACHE not in os.environ:
            os.environ[OBJECT_CACHE] = str(object_cache(config))
        build_in_place()


def object_cache(config) -> Path:
    """The folder of the compiled objects (pytest_configure): pytest's cache's, less the
    objects of a day ago (a folder of this session where pytest's cache is off)."""
    cache = getattr(config, "cache", None)
    if cache is None:  # -p no:cacheprovider
        folder = Path(tempfile.mkdtemp(prefix="drive_rattle_test_objects_"))
        config.add_cleanup(lambda: shutil.rmtree(folder, ignore_errors=True))
        return folder
    folder = cache.mkdir("drive_rattle_objects")
    old = time.time() - 24 * 3600
    for kept in folder.iterdir():
        with contextlib.suppress(OSError):  # another session may have removed it
            if kept.stat().st_mtime < old:
                kept.unlink()
    return folder


def made_once(tmp_path_factory, name: str, make):
    """What ``make(folder)`` returns (JSON: paths as strings), for a folder of this run that every
    pytest-xdist worker shares: the first worker to ask makes it while the others wait on a
    lock, then read its result.  Without workers, a folder of this session like any other.
    A build is costly and the same in every worker; doing it once keeps two workers from
    doubling the run's work."""
    base = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        base = base.parent  # the run's folder: each worker's own is a folder inside it
    folder = base / f"made-{name}"
    with open(base / f"made-{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes, even on an error
        result = folder / "made.json"
        if result.is_file():
            return json.loads(result.read_text(encoding="utf-8"))
        if folder.exists():  # a worker failed while making it: make it again, from nothing
            shutil.rmtree(folder)
        folder.mkdir()
        made = make(folder)
        result.write_text(json.dumps(made), encoding="utf-8")
        return made


#: The project's packages (fmu_src/): the modules hypothesis calls local.
PACKAGES = ("drive_rattle", "drive_rattle_build", "drive_rattle_cosim", "drive_rattle_fmi")


def pytest_collection_finish(session):
    """Every module of the project's packages imported before the first test, in every
    process.  Hypothesis draws some examples from the constants of the local modules imported
    so far (``hypothesis.internal.conjecture.providers._get_local_constants``), so a test's
    examples would otherwise depend on which tests ran before it in its process, which
    pytest-xdist decides anew in every run; imported up front, the constants are the same in
    every process and every order, and one commit draws one set of examples.  (Only where a
    property test is collected: the import costs seconds, and only hypothesis reads it.)"""
    if not any(getattr(getattr(item, "obj", None), "is_hypothesis_test", False)
               for item in session.items):
        return
    for package in PACKAGES:
        for module in pkgutil.walk_packages(importlib.import_module(package).__path__,
                                            f"{package}."):
            source = module.module_finder.find_spec(module.name).origin or ""
            # no __main__ (importing it runs the command), no shared library (rattle_model.so
            # is loaded by ctypes, not imported)
            if source.endswith(".py") and not module.name.endswith(".__main__"):
                importlib.import_module(module.name)


#: Seconds each of the longest files took in a fresh-clone CI run on two workers (--junitxml,
#: summed over the file's tests, builds counted where they fall, less a wait for the faces'
#: build), 2026-12-02: the run's schedule.
LONG_FILES = {
    "sanitize/test_boundary_sanitized.py": 150, "cosim/test_model_doc.py": 131,
    "analysis/test_multistability.py": 106, "adversarial/test_endurance.py": 88,
    "adversarial/test_fmi_boundary.py": 86, "test_wheel.py": 69, "cosim/test_tools_doc.py": 60,
    "adversarial/test_mutants.py": 58, "faces/test_hosts.py": 50, "test_examples.py": 43,
    "cosim/test_masters.py": 41, "analysis/test_spectral_lines.py": 36,
    "cosim/test_cluster.py": 35, "model/test_system.py": 32, "model/test_stepper.py": 28,
    "cosim/test_ssp.py": 26, "adversarial/test_fmi_bad_input.py": 18,
    "fmu/test_build_compiler.py": 17, "fmu/test_platforms.py": 16,
    "sanitize/test_native_sanitizers.py": 13,
}


def test_file(item) -> Path:
    """The file of ``item``, relative to tests/."""
    return Path(str(item.fspath)).resolve().relative_to(TESTS)


def pytest_itemcollected(item):
    """The markers of ``item``, set as it is collected (before ``-m`` deselects)."""
    item.add_marker(getattr(pytest.mark, LAYERS.get(test_file(item).parts[0], "examples")))
    if item.get_closest_marker("cross"):
        item.add_marker(pytest.mark.slow)
    elif CROSS_FIXTURES & set(getattr(item, "fixturenames", ())):
        asked = sorted(CROSS_FIXTURES & set(item.fixturenames))
        raise pytest.UsageError(f"{item.nodeid} asks for {', '.join(asked)}: a test of the "
                                "other platforms' binaries must be marked cross")
    if getattr(getattr(item, "obj", None), "is_hypothesis_test", False):
        item.add_marker(pytest.mark.seeded)


@pytest.hookimpl(trylast=True)
def pytest_collection_modifyitems(items):
    """The longest files first, each file's tests kept together and in order: pytest-xdist (the
    README's ``-n auto``, with ``--dist loadfile --no-loadscope-reorder`` in pyproject.toml)
    hands whole files to the workers in this order, so the long ones start early and the
    short ones fill in around them, instead of one worker finishing a long file alone at the
    end.  Ahead of them all the longest file with a selected ``cross`` test (last of the
    hooks, after ``-m`` has deselected): its worker builds the shipped FMUs first (zig's
    x86_64-windows C runtime on a new machine: a minute or more of its core) while the other
    starts on the long files; only the first file needs that, the others find the FMUs
    built.  Only the order depends on LONG_FILES, never a result."""
    files = {item: test_file(item).as_posix() for item in items}
    crossing = {files[item] for item in items if item.get_closest_marker("cross")}
    first = max(sorted(crossing), key=lambda f: LONG_FILES.get(f, 0.0), default=None)
    items.sort(key=lambda item: (files[item] != first, -LONG_FILES.get(files[item], 0.0)))


#: The fixtures of the other platforms' binaries: a test that asks for one is marked cross.
CROSS_FIXTURES = {"shipped_native_fmus", "shipped_fmi3_fmus", "shipped_face_fmus", "wine_env"}


def built_faces(tmp_path_factory, face: str, shipped: bool = False) -> dict[str, Path]:
    """{model: path} of ``face`` (pythonfmu, native, fmi3), built and validated once for this
    run: the C-only faces for the build machine alone, or (``shipped``) for every platform
    they ship (``platforms.FMI2_SHIPPED``, ``FMI3_SHIPPED``).  The pythonfmu face (for the
    build machine alone) is made apart from the others, so that a test of it never waits for
    a C-only build.  The native FMI 2.0 and FMI 3.0 faces are made together, each in a
    thread of its own, into a folder of its own: they compile the model library once per
    platform between them (``platforms.shared_objects``, under its lock), and much of a
    build is Python (validation, packing) or one compiler at a time, which alone leaves a
    core idle."""
    if face == "pythonfmu":
        made = made_once(tmp_path_factory, "dist-pythonfmu",
                         lambda out: {"pythonfmu": [str(p) for p in build(out)]})
        return {Path(p).stem: Path(p) for p in made[face]}
    machine = build_machine()
    fmi2, fmi3 = ((FMI2_SHIPPED, FMI3_SHIPPED) if shipped or machine is None
                  else ((machine,), (machine,)))

    def make(out: Path) -> dict:
        from drive_rattle_build.fmi3 import FMI3_SUBDIR, build_fmi3
        from drive_rattle_build.native import NATIVE_SUBDIR, build_native

        with ThreadPoolExecutor(max_workers=1) as pool:
            made3 = pool.submit(build_fmi3, out / FMI3_SUBDIR, platforms=fmi3)
            made2 = build_native(out / NATIVE_SUBDIR, platforms=fmi2)
            return {"native": [str(p) for p in made2], "fmi3": [str(p) for p in made3.result()]}

    made = made_once(tmp_path_factory, "dist-c-" + "-".join(fmi3), make)
    return {Path(p).stem: Path(p) for p in made[face]}


@pytest.fixture(scope="session")
def fmus(tmp_path_factory):
    """{'GearMeshRattle': path, 'Driveline': path}, built and validated for this session."""
    return built_faces(tmp_path_factory, "pythonfmu")


@pytest.fixture(scope="session")
def native_fmus(tmp_path_factory):
    """{'GearMeshRattle': path, 'Driveline': path}: the native (C only) FMUs, the build
    machine's binary (linux64) and sources, built and validated for this session."""
    return built_faces(tmp_path_factory, "native")


@pytest.fixture(scope="session")
def fmi3_fmus(tmp_path_factory):
    """{'GearMeshRattle': path, 'Driveline': path}: the FMI 3.0 FMUs (C only; the build
    machine's binary, x86_64-linux, and sources), built, held against their templates and
    validated for this session."""
    return built_faces(tmp_path_factory, "fmi3")


@pytest.fixture(scope="session")
def shipped_native_fmus(tmp_path_factory):
    """The native FMUs as shipped: linux64 and win64 binaries (tests marked ``cross``)."""
    return built_faces(tmp_path_factory, "native", shipped=True)


@pytest.fixture(scope="session")
def shipped_fmi3_fmus(tmp_path_factory):
    """The FMI 3.0 FMUs as shipped: x86_64-linux, x86_64-windows and aarch64-linux binaries
    (tests marked ``cross``)."""
    return built_faces(tmp_path_factory, "fmi3", shipped=True)


@pytest.fixture(scope="session")
def wine_env(tmp_path_factory) -> dict:
    """The environment of every program run under wine this session: one wine prefix, made
    (``wineboot --init``, 13 s on a 2-core machine) before the first program runs in it, so
    that two workers never both start a new prefix."""
    import subprocess

    from .faces.hosts import wine

    env = {**os.environ, "WINEDEBUG": "-all",
           "WINEDLLOVERRIDES": "mscoree,mshtml="}  # no .NET/Gecko installers in a new prefix

    def boot(prefix: Path) -> str:
        subprocess.run([wine(), "wineboot", "--init"], env={**env, "WINEPREFIX": str(prefix)},
                       check=True, capture_output=True, timeout=600)
        return str(prefix)

    return {**env, "WINEPREFIX": made_once(tmp_path_factory, "wineprefix", boot)}


FLAVOURS = ("pythonfmu", "native")


@pytest.fixture(scope="session", params=FLAVOURS)
def flavour_fmus(request):
    """The FMUs of each flavour in turn: the pythonfmu FMUs and the native ones."""
    return request.getfixturevalue("fmus" if request.param == "pythonfmu" else "native_fmus")


#: When the session started (time.monotonic()).
_STARTED = pytest.StashKey[float]()
#: Seconds spent in the tests (setup, call and teardown), split by whether they are slow.
_SECONDS = {"not slow": 0.0, "slow": 0.0}


def pytest_runtest_logreport(report):
    item_slow = "slow" in report.keywords
    _SECONDS["slow" if item_slow else "not slow"] += report.duration


def pytest_sessionstart(session):
    session.config.stash[_STARTED] = time.monotonic()


def pytest_terminal_summary(terminalreporter, config):
    """The session's time from its start (collection and the workers' start included), with
    the markers it selected, and the time in its tests, fast and slow (summed over the
    workers; a session fixture's build counts for the first test that uses it)."""
    selected = f'-m "{config.option.markexpr}"' if config.option.markexpr else "every test"
    terminalreporter.write_line(
        f"session: {time.monotonic() - config.stash[_STARTED]:.0f} s, {selected}; time in "
        f"tests: {_SECONDS['not slow']:.0f} s not slow, {_SECONDS['slow']:.0f} s slow")
