"""The packages by job (docs/architecture.md): the import graph of every module under fmu_src/
has no cycle, each layer imports only what it may, and nothing is imported from a file path.

Imports are read from the source (``ast``), at module level and inside functions alike (a cycle
through a function-level import is still a cycle).  A submodule's implicit import of its own
package's ``__init__`` is not an edge: that is how packages load, not a dependency."""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import pytest

SOURCE = Path(__file__).resolve().parents[2] / "fmu_src"
RUNTIME = ("drive_rattle", "drive_rattle_fmi")
PACKAGES = (*RUNTIME, "drive_rattle_build", "drive_rattle_cosim")
#: The slave modules (fmu_src/<Model>.py): runtime, next to the packages in each FMU.
SLAVES = ("GearMeshRattle", "Driveline")

#: What each layer may import besides the standard library: the runtime ships in the FMUs
#: (the FMI glue and the slaves also use pythonfmu, whose runtime is bundled); the studies run
#: the FMUs; the build assembles the runtime, the studies' SSP writer and regression
#: references, and the C sources.
ALLOWED = {
    "drive_rattle": {"drive_rattle"},
    "drive_rattle_fmi": {"drive_rattle", "drive_rattle_fmi", "pythonfmu"},
    "slaves": {"drive_rattle", "drive_rattle_fmi", "pythonfmu"},
    "drive_rattle_cosim": {"drive_rattle", "drive_rattle_cosim", "numpy", "scipy", "fmpy",
                           "tqdm", "dask", "distributed", "libcosimpy", "lxml", "gemseo_fmu",
                           "matplotlib"},
    "drive_rattle_build": {"drive_rattle", "drive_rattle_fmi", "drive_rattle_build",
                           "drive_rattle_cosim", "pythonfmu", "fmpy", "ziglang"},
}


def module_files() -> dict[str, Path]:
    """``{module name: file}`` of every first-party module."""
    out = {name: SOURCE / f"{name}.py" for name in SLAVES}
    for package in PACKAGES:
        for path in sorted((SOURCE / package).glob("*.py")):
            name = package if path.stem == "__init__" else f"{package}.{path.stem}"
            out[name] = path
    return out


MODULES = module_files()


def layer(module: str) -> str:
    return "slaves" if module in SLAVES else module.split(".")[0]


def imports(module: str, path: Path) -> list[str]:
    """Absolute names of everything ``module`` imports (a name imported from a package is the
    submodule when there is one)."""
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
                      if f"{target}.{alias.name}" in MODULES]
    return names


GRAPH = {m: sorted({name for name in imports(m, p) if name in MODULES and name != m
                    and not m.startswith(f"{name}.")})  # not the own package's __init__
         for m, p in MODULES.items()}


def test_every_package_and_slave_module_is_seen():
    assert {"drive_rattle.parameters", "drive_rattle.geometry", "drive_rattle.stepper",
            "drive_rattle.kernel", "drive_rattle_fmi.slave", "drive_rattle_build.cli",
            "drive_rattle_cosim.harness", "GearMeshRattle", "Driveline"} <= set(MODULES)
    # the graph sees a function-level import (the build's packing of the references)
    assert "drive_rattle_cosim.regression" in GRAPH["drive_rattle_build.fmu"]


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
    for needle in ("importlib", "spec_from_file_location", "runpy", "exec_module"):
        assert needle not in text, f"{module} uses {needle}"


def test_the_runtime_is_shipped_whole_and_knows_no_tooling():
    """The build copies the runtime packages whole (drive_rattle_build.paths), so they must
    hold nothing but runtime modules: no module of theirs imports numpy, scipy, fmpy or the
    build/studies packages (checked above), and the build names exactly these packages."""
    from drive_rattle_build.paths import RUNTIME_PACKAGES

    assert RUNTIME_PACKAGES == RUNTIME
