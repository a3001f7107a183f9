"""Building, checking and validating the pythonfmu FMUs.

Each FMU bundles its slave module (``fmu_src/slaves/<Model>.py``), the runtime packages whole
(``paths.RUNTIME_PACKAGES``: the specs and the ctypes binding, the pythonfmu face; standard
library only), the model library compiled for linux64 next to the binding
(``resources/drive_rattle/rattle_model.so``, where the slave loads it from), the regression
references, generated documentation and the status shim.  linux64 only (``PLATFORMS``): the
win64 binary pythonfmu's builder adds is removed (``drop_other_platforms``), because it has
neither the shim nor a way to be tested here (it needs an installed Windows Python and the
VC++ runtime, and fails to load with error 126 without them); the native FMUs serve Windows.
Its GUID is derived from the model library's sources and the face's (``identity.fmu_guid``),
so that another build of the same sources accepts its FMU states.  Its normalised
modelDescription is held against the committed template (``templates``), and every FMU is
checked with fmpy's ``validate_fmu`` and, when installed, fmu-manipulation-toolbox's
``fmutool -check``; any problem fails the build.
"""

from __future__ import annotations

import contextlib
import hashlib
import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path
from xml.etree import ElementTree

from drive_rattle.catalog import UNITS
from drive_rattle.interface import MODELS

from . import library, model_description, templates
from .compiler import BuildError, c_compiler
from .documentation import HOW_TO_RUN, LICENSE_ENTRY, html_page, license_text
from .icon import add_icon
from .identity import fmu_guid
from .paths import DIST, RUNTIME_PACKAGES, runtime_package, slave_module
from .shim import COMMON_SOURCE, FMI2_COMMON_SOURCE, PORTABLE_SOURCE, SHIM_SOURCE, install_shim

#: What is never copied from a runtime package: caches and a library built in place (the
#: FMU gets its own, compiled for each platform).
_NOT_SHIPPED = shutil.ignore_patterns("__pycache__", "*.pyc", "*.so", "*.dll", "*.dylib",
                                      "*.id", ".*")
#: The folder of the model library inside the FMU's resources (next to the binding).
LIBRARY_FOLDER = "drive_rattle"
#: The platforms of the pythonfmu FMUs: where the status shim is built and the FMUs are tested.
PLATFORMS = ("linux64",)


def slave_class(name: str, script: Path | None = None):
    """The slave class ``name`` from its module (``script``, default
    ``fmu_src/slaves/<name>.py``)."""
    script = Path(script) if script is not None else slave_module(name)
    if str(script.parent) not in sys.path:
        sys.path.insert(0, str(script.parent))
    module = __import__(name)
    return getattr(module, name)


def compile_libraries(out_dir: Path, cc: str | None = None,
                      platforms: tuple[str, ...] = PLATFORMS) -> list[Path]:
    """The model library for ``platforms`` (of ``library.PLATFORMS``; default: the pythonfmu
    FMUs' ``PLATFORMS``) in ``out_dir``, under the names the binding loads
    (``rattle_model.so``, ``.dll``)."""
    return [library.compile_model_library(Path(out_dir) / name, platform,
                                          cc=cc if target is None else None)
            for platform, (name, target) in library.PLATFORMS.items()
            if platform in platforms]


def drop_other_platforms(fmu: Path, platforms: tuple[str, ...] = PLATFORMS) -> None:
    """Remove every ``binaries/<platform>/`` but ``platforms`` from ``fmu`` (rewritten in
    place): pythonfmu's builder adds its generic binary for every platform it ships."""
    fmu = Path(fmu)
    kept = tuple(f"binaries/{p}/" for p in platforms)
    part = fmu.with_name(f".{fmu.name}.part")
    with zipfile.ZipFile(fmu) as src, zipfile.ZipFile(part, "w") as dst:
        for info in src.infolist():
            if not info.filename.startswith("binaries/") or info.filename.startswith(kept):
                dst.writestr(info, src.read(info))
    shutil.copymode(fmu, part)
    part.replace(fmu)


def stage_runtime(staging: Path, libraries: list[Path]) -> list[Path]:
    """Copy every runtime package whole into ``staging`` and the compiled model ``libraries``
    next to the binding (``drive_rattle/``); the staged package folders."""
    out = []
    for package in RUNTIME_PACKAGES:
        dest = staging / package
        shutil.copytree(runtime_package(package), dest, ignore=_NOT_SHIPPED)
        out.append(dest)
    for lib in libraries:
        shutil.copy2(lib, staging / LIBRARY_FOLDER / Path(lib).name)
    return out


def glue_sources(name: str) -> list[Path]:
    """What the pythonfmu flavour adds to the model library in the FMU of ``name``: the slave
    module, the face's package and the status shim's C."""
    face = sorted(runtime_package("drive_rattle_fmi").glob("*.py"))
    return [slave_module(name), *face, SHIM_SOURCE, COMMON_SOURCE,
            COMMON_SOURCE.with_suffix(".h"), FMI2_COMMON_SOURCE,
            FMI2_COMMON_SOURCE.with_suffix(".h"), PORTABLE_SOURCE,
            PORTABLE_SOURCE.with_name("rm_portable.h")]


def glue_id(name: str) -> str:
    """The hash of :func:`glue_sources` (by name and content), for the GUID."""
    digest = hashlib.sha256()
    for path in glue_sources(name):
        digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()[:16]


def guid(name: str) -> str:
    """The GUID of ``name``'s pythonfmu FMU: from the model library's sources and the face's
    (a build of the same sources gets the same GUID)."""
    return fmu_guid(name, "pythonfmu", glue_id(name))


#: The generation tool of the pythonfmu FMUs' modelDescription.
def generation_tool() -> str:
    from pythonfmu import __version__ as pythonfmu_version

    return f"drive-rattle-build (pythonfmu {pythonfmu_version})"


@contextlib.contextmanager
def _describing(cls, name: str):
    """Within the block, ``cls`` hands pythonfmu's builder the modelDescription of ``name``
    rendered from the specs (``model_description.render``) with its GUID."""
    cls.MODEL_DESCRIPTION = model_description.render(name, guid(name), generation_tool(),
                                                     needs_execution_tool=True)
    try:
        yield
    finally:
        cls.MODEL_DESCRIPTION = None


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


def package(script: Path, out_dir: Path, references: bool = True,
            libraries: list[Path] | None = None) -> Path:
    """Build the slave module ``script`` (class = file stem) into ``out_dir/<stem>.fmu`` with
    the runtime packages, the model library (``libraries``, compiled when not given),
    generated documentation and the status shim."""
    from pythonfmu.builder import FmuBuilder

    from drive_rattle_fmi.slave import (
        LAST_SUCCESSFUL_TIME_VARIABLE,
        MESSAGE_VARIABLE,
        STATUS_ADDRESS_VARIABLE,
    )

    script = Path(script)
    name = script.stem
    library.build_in_place()  # what the build process itself loads (specs, slave classes)
    cls = slave_class(name, script)
    cc = c_compiler()
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    fmu = out_dir / f"{name}.fmu"
    with tempfile.TemporaryDirectory(prefix=f"build_{name}_") as tmp:
        tmp = Path(tmp)
        if libraries is None:
            libraries = compile_libraries(tmp / "lib", cc)
        packages = stage_runtime(tmp / "stage", libraries)
        if references:
            packages += stage_references(name, tmp / "stage")
        doc = tmp / "documentation"
        doc.mkdir()
        (doc / "index.html").write_text(
            html_page(UNITS[name], HOW_TO_RUN.format(name=name)), encoding="utf-8")
        licenses = doc / Path(LICENSE_ENTRY).relative_to("documentation")
        licenses.parent.mkdir()
        licenses.write_text(license_text(), encoding="utf-8")
        with _describing(cls, name):
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
    drop_other_platforms(fmu)
    add_icon(fmu)
    return fmu


def build_one(name: str, out_dir: Path, update_templates: bool = False,
              use_fmutool: bool = True, libraries: list[Path] | None = None) -> Path:
    """Build, shim, check against the template and validate one FMU; returns its path."""
    fmu = package(slave_module(name), out_dir, libraries=libraries)
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
    """Build and validate every FMU of ``interface.MODELS`` (the model library compiled once
    for all)."""
    with tempfile.TemporaryDirectory(prefix="build_library_") as tmp:
        libraries = compile_libraries(Path(tmp), c_compiler())
        return [build_one(name, Path(out_dir), update_templates, use_fmutool, libraries)
                for name in MODELS]


def build_fmus(out_dir: Path = DIST, use_fmutool: bool = False) -> dict[str, Path]:
    """Build the FMUs into ``out_dir``: ``{model: path}`` (for examples, benchmarks, tests)."""
    return {p.stem: p for p in build(Path(out_dir), use_fmutool=use_fmutool)}
