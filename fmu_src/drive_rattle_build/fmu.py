"""Building, checking and validating the FMUs.

Each FMU bundles its slave module (``fmu_src/<Model>.py``), the runtime packages whole
(``paths.RUNTIME_PACKAGES``: the physics core and the FMI glue, standard library only), the
compiled kernel next to ``drive_rattle/kernel.py``, the regression references, generated
documentation and the native status shim.  Its normalised modelDescription is held against the
committed template (``templates``), and every FMU is checked with fmpy's ``validate_fmu`` and,
when installed, fmu-manipulation-toolbox's ``fmutool -check``; any problem fails the build.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path
from xml.etree import ElementTree

from drive_rattle.interface import MODELS
from drive_rattle.kernel import LIBRARY_NAME

from . import kernel, templates
from .compiler import BuildError, c_compiler
from .documentation import HOW_TO_RUN, html_page
from .paths import DIST, RUNTIME_PACKAGES, SOURCE, slave_module
from .shim import install_shim

#: What is never copied from a runtime package: caches and a kernel built in place.
_NOT_SHIPPED = shutil.ignore_patterns("__pycache__", "*.pyc", "*.so", ".*")


def slave_class(name: str, script: Path | None = None):
    """The slave class ``name`` from its module (``script``, default ``fmu_src/<name>.py``)."""
    script = Path(script) if script is not None else slave_module(name)
    if str(script.parent) not in sys.path:
        sys.path.insert(0, str(script.parent))
    module = __import__(name)
    return getattr(module, name)


def stage_runtime(staging: Path, cc: str) -> list[Path]:
    """Copy every runtime package whole into ``staging`` and compile the kernel next to
    ``drive_rattle/kernel.py``; the staged package folders."""
    kernel.update_header()
    out = []
    for package in RUNTIME_PACKAGES:
        dest = staging / package
        shutil.copytree(SOURCE / package, dest, ignore=_NOT_SHIPPED)
        out.append(dest)
    try:
        kernel.compile_kernel(staging / "drive_rattle" / LIBRARY_NAME, cc=cc)
    except RuntimeError as err:
        raise BuildError(str(err)) from None
    return out


def stage_references(name: str, staging: Path) -> list[Path]:
    """The committed regression references of ``name``, staged for resources/regression/."""
    from drive_rattle_cosim.regression import reference_files

    files = reference_files(name)
    if not all(f.is_file() for f in files):
        print(f"drive-rattle-build: no regression references for {name} yet "
              "(python -m drive_rattle_cosim.regression generate)", file=sys.stderr)
        return []
    dest = staging / "regression"
    dest.mkdir(parents=True)
    for f in files:
        shutil.copy2(f, dest / f.name)
    return [dest]


def package(script: Path, out_dir: Path, references: bool = True) -> Path:
    """Build the slave module ``script`` (class = file stem) into ``out_dir/<stem>.fmu`` with
    the runtime packages, generated documentation and the native status shim."""
    from pythonfmu.builder import FmuBuilder

    from drive_rattle_fmi.slave import (
        LAST_SUCCESSFUL_TIME_VARIABLE,
        MESSAGE_VARIABLE,
        STATUS_ADDRESS_VARIABLE,
    )

    script = Path(script)
    name = script.stem
    cls = slave_class(name, script)
    cc = c_compiler()
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    fmu = out_dir / f"{name}.fmu"
    with tempfile.TemporaryDirectory(prefix=f"build_{name}_") as tmp:
        tmp = Path(tmp)
        packages = stage_runtime(tmp / "stage", cc)
        if references:
            packages += stage_references(name, tmp / "stage")
        doc = tmp / "documentation"
        doc.mkdir()
        (doc / "index.html").write_text(
            html_page(cls, HOW_TO_RUN.format(name=name)), encoding="utf-8")
        FmuBuilder.build_FMU(script, dest=fmu, project_files=packages,
                             documentation_folder=doc, canGetAndSetFMUstate=True,
                             canSerializeFMUstate=True)
    slave = cls(instance_name="build")
    vrs = {v.name: v.value_reference for v in slave.vars.values()}
    try:
        install_shim(fmu, vrs[STATUS_ADDRESS_VARIABLE], vrs[MESSAGE_VARIABLE],
                     vrs[LAST_SUCCESSFUL_TIME_VARIABLE], cc=cc)
    except RuntimeError as err:
        raise BuildError(str(err)) from None
    return fmu


def build_one(name: str, out_dir: Path, update_templates: bool = False,
              use_fmutool: bool = True) -> Path:
    """Build, shim, check against the template and validate one FMU; returns its path."""
    fmu = package(slave_module(name), out_dir)
    with zipfile.ZipFile(fmu) as z:
        root = ElementTree.fromstring(z.read("modelDescription.xml"))
    templates.check_template(name, root, update=update_templates)
    validate(fmu, use_fmutool)
    return fmu


def validate(fmu: Path, use_fmutool: bool = True) -> None:
    """fmpy's validate_fmu and (if installed) `fmutool -check`; BuildError on problems."""
    from fmpy.validation import validate_fmu

    problems = validate_fmu(str(fmu))
    if problems:
        raise BuildError(f"{fmu.name}: fmpy validate_fmu found problems:\n" + "\n".join(problems))
    tool = shutil.which("fmutool") or (Path(sys.executable).parent / "fmutool")
    if use_fmutool and Path(tool).exists():
        run = subprocess.run([str(tool), "-input", str(fmu), "-check"], capture_output=True,
                             text=True)
        report = run.stdout + run.stderr
        if run.returncode != 0 or "ERROR" in report:
            raise BuildError(f"{fmu.name}: fmutool -check failed:\n{report}")


def build(out_dir: Path = DIST, update_templates: bool = False,
          use_fmutool: bool = True) -> list[Path]:
    """Build and validate every FMU of ``interface.MODELS``."""
    return [build_one(name, Path(out_dir), update_templates, use_fmutool) for name in MODELS]


def build_fmus(out_dir: Path = DIST, use_fmutool: bool = False) -> dict[str, Path]:
    """Build the FMUs into ``out_dir``: ``{model: path}`` (for examples, benchmarks, tests)."""
    return {p.stem: p for p in build(Path(out_dir), use_fmutool=use_fmutool)}
