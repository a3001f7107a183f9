"""The packages by job (docs/architecture.md): the import graph of every module under fmu_src/
has no cycle, each layer imports only what it may, nothing is imported from a file path, and
the physics exists once, in the model library -- no Python module outside tests/ computes it.

Imports are read from the source (``ast``), at module level and inside functions alike (a cycle
through a function-level import is still a cycle).  A submodule's implicit import of its own
package's ``__init__`` is not an edge: that is how packages load, not a dependency."""

from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SOURCE = ROOT / "fmu_src"
ORACLE = ROOT / "tests" / "oracle"
RUNTIME = ("drive_rattle", "drive_rattle_fmi")
PACKAGES = (*RUNTIME, "drive_rattle_build", "drive_rattle_cosim")
#: The slave modules (fmu_src/slaves/<Model>.py): runtime, next to the packages in each FMU.
SLAVES = ("GearMeshRattle", "Driveline")
#: The modules of the Python API: specs and the binding, no physics (the model is the C
#: library).  A new module here is either physics, which belongs in fmu_src/rattle_model, or
#: a face, which belongs in its own package; extend the list only for neither.
API_MODULES = {"__init__", "catalog", "interface", "library", "parameters", "units"}

#: What each layer may import besides the standard library: the runtime ships in the FMUs
#: (the FMI glue and the slaves also use pythonfmu, whose runtime is bundled); the studies run
#: the FMUs (in fmpy and the other masters); the build assembles the runtime, the studies'
#: SSP writer and regression references, and the C sources.
ALLOWED = {
    "drive_rattle": {"drive_rattle"},
    "drive_rattle_fmi": {"drive_rattle", "drive_rattle_fmi", "pythonfmu"},
    "slaves": {"drive_rattle", "drive_rattle_fmi", "pythonfmu"},
    "drive_rattle_cosim": {"drive_rattle", "drive_rattle_cosim", "numpy", "scipy", "fmpy",
                           "tqdm", "dask", "distributed", "libcosimpy", "lxml", "gemseo_fmu",
                           "fmu_manipulation_toolbox", "ecospy", "cofmupy", "pathsim",
                           "pathsim_fmi", "matplotlib"},
    "drive_rattle_build": {"drive_rattle", "drive_rattle_fmi", "drive_rattle_build",
                           "drive_rattle_cosim", "pythonfmu", "fmpy", "ziglang"},
}

#: Functions of math (and numpy) that compute physics: none in the runtime, whose numbers all
#: come from the library (pi, isfinite, ulp, nan and the like are fine).
PHYSICS_MATH = {"sqrt", "cbrt", "pow", "exp", "expm1", "log", "log1p", "log2", "log10", "sin",
                "cos", "tan", "asin", "acos", "atan", "atan2", "hypot", "sinh", "cosh", "tanh",
                "asinh", "acosh", "atanh", "gamma", "lgamma", "erf", "erfc"}


def module_files() -> dict[str, Path]:
    """``{module name: file}`` of every first-party module."""
    out = {name: SOURCE / "slaves" / f"{name}.py" for name in SLAVES}
    for package in PACKAGES:
        for path in sorted((SOURCE / package).glob("*.py")):
            name = package if path.stem == "__init__" else f"{package}.{path.stem}"
            out[name] = path
    return out


MODULES = module_files()


def layer(module: str) -> str:
    return "slaves" if module in SLAVES else module.split(".")[0]


def imports(module: str, path: Path, known=MODULES) -> list[str]:
    """Absolute names of everything ``module`` imports, anywhere in it (a name imported from
    a package is the submodule when there is one)."""
    package = module if path.stem == "__init__" else module.rpartition(".")[0]
    names = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names += [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module
            names.append(target)
            names += [f"{target}.{alias.name}" for alias in node.names
                      if f"{target}.{alias.name}" in known]
    return names


GRAPH = {m: sorted({name for name in imports(m, p) if name in MODULES and name != m
                    and not m.startswith(f"{name}.")})  # not the own package's __init__
         for m, p in MODULES.items()}


def test_every_package_and_slave_module_is_seen():
    assert {"drive_rattle.parameters", "drive_rattle.units", "drive_rattle.library",
            "drive_rattle_fmi.slave", "drive_rattle_build.cli", "drive_rattle_cosim.harness",
            "GearMeshRattle", "Driveline"} <= set(MODULES)


def test_the_import_reader_sees_relative_and_function_level_imports(tmp_path):
    path = tmp_path / "mod.py"
    path.write_text("from . import a\n\ndef f():\n    from .b import c\n    import x.y\n")
    known = {"pkg.a", "pkg.b", "pkg.b.c"}
    assert imports("pkg.mod", path, known) == ["pkg", "pkg.a", "pkg.b", "pkg.b.c", "x.y"]


def test_the_import_graph_has_no_cycle():
    """Depth-first search over the first-party import graph; a cycle is reported whole."""
    state: dict[str, int] = {}  # 1 on the stack, 2 done
    stack: list[str] = []

    def visit(m: str) -> None:
        state[m] = 1
        stack.append(m)
        for n in GRAPH[m]:
            if state.get(n) == 1:
                cycle = [*stack[stack.index(n):], n]
                pytest.fail("import cycle: " + " -> ".join(cycle))
            if n not in state:
                visit(n)
        stack.pop()
        state[m] = 2

    for m in sorted(GRAPH):
        if m not in state:
            visit(m)


@pytest.mark.parametrize("module", sorted(MODULES))
def test_each_layer_imports_only_what_it_may(module):
    allowed = ALLOWED[layer(module)]
    for name in imports(module, MODULES[module]):
        top = name.split(".")[0]
        if top in sys.stdlib_module_names or top == "__future__":
            continue
        assert top in allowed, (
            f"{module} imports {name}: the {layer(module)} layer may import the standard "
            f"library and {sorted(allowed)} (docs/architecture.md)")


@pytest.mark.parametrize("module", sorted(MODULES))
def test_nothing_is_imported_from_a_file_path(module):
    text = MODULES[module].read_text(encoding="utf-8")
    for needle in ("spec_from_file_location", "runpy", "exec_module", "SourceFileLoader"):
        assert needle not in text, f"{module} uses {needle}"


def test_the_runtime_is_shipped_whole_and_knows_no_tooling():
    """The build copies the runtime packages whole, so they must hold nothing but runtime
    modules (their imports are checked above), and the build names exactly these."""
    from drive_rattle_build.paths import RUNTIME_PACKAGES

    assert RUNTIME_PACKAGES == RUNTIME


# ------------------------------------------------------------------ physics exists once
def test_the_python_api_package_holds_only_its_known_modules():
    found = {p.stem for p in (SOURCE / "drive_rattle").glob("*.py")}
    assert found == API_MODULES, (
        f"drive_rattle holds {sorted(found - API_MODULES)} beyond the specs and the binding: "
        "physics belongs in the model library (fmu_src/rattle_model), faces in their packages")


def runtime_modules():
    return sorted(m for m in MODULES if layer(m) in (*RUNTIME, "slaves"))


@pytest.mark.parametrize("module", runtime_modules())
def test_the_runtime_computes_no_physics(module):
    """No math of the laws (roots, powers, transcendental functions) in the runtime: its
    numbers come from the library.  A power of a variable (``x ** y``) counts too; powers of
    literals (``2**31``) do not."""
    tree = ast.parse(MODULES[module].read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and node.attr in PHYSICS_MATH and isinstance(
                node.value, ast.Name) and node.value.id in ("math", "cmath", "np", "numpy"):
            pytest.fail(f"{module}:{node.lineno} calls {node.value.id}.{node.attr}")
        if isinstance(node, ast.ImportFrom) and node.module in ("math", "cmath"):
            bad = {a.name for a in node.names} & (PHYSICS_MATH | {"*"})
            assert not bad, f"{module}:{node.lineno} imports {sorted(bad)} from {node.module}"
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Pow):
            literal = all(isinstance(x, ast.Constant) or (isinstance(x, ast.UnaryOp)
                          and isinstance(x.operand, ast.Constant))
                          for x in (node.left, node.right))
            assert literal, f"{module}:{node.lineno} raises a variable to a power"


def oracle_names() -> set[str]:
    """The functions and classes of the readable equations (tests/oracle, the reference
    apart), private ones included."""
    names = set()
    for path in ORACLE.glob("*.py"):
        if path.stem in ("__init__", "reference"):
            continue
        for node in ast.parse(path.read_text(encoding="utf-8")).body:
            if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
                names.add(node.name)
    return names


def python_outside_tests() -> list[Path]:
    """The project's Python outside tests/: the sources, the examples, the benchmarks and the
    build's entry point (not whatever else lies in the folder: environments, build output)."""
    return sorted([*(p for folder in ("fmu_src", "examples", "benchmarks")
                     for p in (ROOT / folder).rglob("*.py")), ROOT / "build_fmu.py"])


def test_no_python_outside_tests_defines_a_law_of_the_oracle():
    """The laws are in the library once; the readable equations live under tests/oracle
    only.  A function or class of the oracle's names defined anywhere else outside tests/ is
    a second copy."""
    names = oracle_names()
    assert {"exact_ellipse", "hunt_crossley_restitution", "HelicalPairGeometry",
            "friction_force", "MeshModel"} <= names
    copies = [f"{path.relative_to(ROOT)}:{node.lineno} {node.name}"
              for path in python_outside_tests()
              for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
              if isinstance(node, (ast.FunctionDef, ast.ClassDef)) and node.name in names]
    assert not copies, f"the oracle's laws defined outside tests/: {copies}"


@pytest.mark.parametrize("path", sorted(p.name for p in ORACLE.glob("*.py")))
def test_the_oracle_is_independent_of_the_library(path):
    """The readable equations import only the standard library and each other (the reference
    takes the co-simulation's start from the library, and uses numpy and scipy)."""
    allowed = {"tests"} | ({"drive_rattle", "numpy", "scipy"} if path == "reference.py"
                           else set())
    module = f"tests.oracle.{Path(path).stem}"
    for name in imports(module, ORACLE / path, known=set()):
        top = name.split(".")[0]
        if top in sys.stdlib_module_names or top == "__future__":
            continue
        assert top in allowed, f"tests/oracle/{path} imports {name}"


# ------------------------------------------------------------------ the tests' map
TESTS_MAP = ROOT / "tests" / "README.md"


def test_every_room_of_the_model_library_is_in_the_tests_map():
    """tests/README.md names each C file of the model library, and each test or oracle file it
    names exists: the map a maintainer reads to find a room's tests cannot go stale."""
    text = TESTS_MAP.read_text(encoding="utf-8")
    rooms = sorted(p.name for p in (SOURCE / "rattle_model").glob("*.[ch]"))
    assert [r for r in rooms if f"`{r}`" not in text] == []
    named = set(re.findall(r"`((?:\w+/)*\w+\.py)`", text))
    paths = [n for n in named if "/" in n]
    assert paths, "no test file named in tests/README.md"
    # (relative to tests/, to fmu_src/ for a source, or to the repository where it says so)
    assert [n for n in paths if not any((base / n).is_file()
                                        for base in (ROOT / "tests", SOURCE, ROOT))] == []


def test_every_test_file_of_the_model_is_in_the_tests_map():
    text = TESTS_MAP.read_text(encoding="utf-8")
    files = sorted(p.relative_to(ROOT / "tests").as_posix()
                   for p in (ROOT / "tests" / "model").glob("test_*.py"))
    assert [f for f in files if f"`{f}" not in text] == []
