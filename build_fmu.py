"""Build dist/GearMeshRattle.fmu and dist/Driveline.fmu (FMI 2.0 co-simulation), validate
them, and write the system dist/DriveRattle.ssp (both FMUs, their connections, every parameter
and every input's start value bound).

    python build_fmu.py [--out dist] [--update-templates] [--no-fmutool] [--no-native]
    python build_fmu.py --update-docs     # regenerate the interface tables of docs/fmi.md
    python build_fmu.py --update-kernel-header  # regenerate fmu_src/native/rattle_kernel_layout.h

Each FMU bundles the slave module, the runtime part of the physics core (standard library
only), the FMI glue, generated documentation and the native status shim.  The kernel and the
shim are compiled with gcc, or, where there is none, the clang of the ``ziglang`` package
(``c_compiler``).  The normalised
modelDescription of each build is compared with the committed one in
modelDescription_templates/: an interface change fails the build until the template is
updated (--update-templates) and the diff committed.  Every FMU is checked with fmpy's
validate_fmu and, when installed, fmu-manipulation-toolbox's `fmutool -check`; any problem
fails the build.

The same two units implemented entirely in C (no Python at run time; linux64 and win64
binaries and the C sources) are built into ``<out>/native/`` with their own system
``DriveRattle.ssp`` (``drive_rattle_fmi.native_fmu``; ``--no-native`` skips them).
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path
from xml.etree import ElementTree

ROOT = Path(__file__).resolve().parent
SRC = ROOT / "fmu_src"
TEMPLATES = ROOT / "modelDescription_templates"
MODELS = ("GearMeshRattle", "Driveline")

#: Modules of the core that run inside the FMUs (the rest needs numpy/scipy or is tooling).
CORE_RUNTIME = ("__init__", "parameters", "geometry", "hertz", "lubrication", "mesh", "roots",
                "stepper", "driveline", "interface", "kernel", "kernel_layout")
FMI_RUNTIME = ("__init__", "slave", "model_description", "units", "boundary")

sys.path.insert(0, str(SRC))


class BuildError(RuntimeError):
    pass


#: ziglang's clang targets the build machine's CPU unless told otherwise: a baseline x86-64
#: (instructions every x86-64 host has) with glibc, whose libm is the one CPython uses (the
#: kernel's results are bit-identical to the Python core's only with the same libm).
ZIG_TARGET = {"x86_64": "x86_64-linux-gnu"}
_ZIG_WRAPPER: list[str] = []


def c_compiler() -> str:
    """The C compiler of the build, as one executable: ``$CC`` if set, else ``gcc`` or ``cc``
    on ``PATH``, else the clang of the ``ziglang`` package (a dependency of this project:
    ``python -m ziglang cc``, through a small wrapper script).  BuildError when none works."""
    import platform

    requested = os.environ.get("CC")
    if requested:
        found = shutil.which(requested)
        if found is None:
            raise BuildError(f"CC = {requested!r} is not an executable on PATH; allowed: a C "
                             "compiler such as gcc, or unset CC to use gcc or ziglang's clang")
        return found
    for name in ("gcc", "cc"):
        found = shutil.which(name)
        if found:
            return found
    if _ZIG_WRAPPER:
        return _ZIG_WRAPPER[0]
    try:
        import ziglang  # noqa: F401  (only its presence: it runs as python -m ziglang)
    except ImportError:
        raise BuildError(
            "no C compiler: gcc (or cc) is not on PATH and the ziglang package is not "
            "installed. Install one: `pip install ziglang` (a dependency of this project: "
            "reinstall it with `pip install -e .`) or your system's gcc (Debian/Ubuntu: "
            "`apt-get install gcc`), or set CC to a C compiler") from None
    import atexit
    import shlex

    folder = Path(tempfile.mkdtemp(prefix="drive_rattle_cc_"))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    target = ZIG_TARGET.get(platform.machine())
    args = ["-target", target] if target else []
    wrapper = folder / "zig-cc"
    wrapper.write_text(
        "#!/bin/sh\n# ziglang's C compiler (drive-rattle build: no gcc on PATH)\n"
        f"exec {shlex.join([sys.executable, '-m', 'ziglang', 'cc', *args])} \"$@\"\n",
        encoding="utf-8")
    wrapper.chmod(0o755)
    probe = subprocess.run([str(wrapper), "--version"], capture_output=True, text=True)
    if probe.returncode != 0:
        raise BuildError(f"no working C compiler: gcc is not on PATH and ziglang's clang "
                         f"fails:\n{probe.stderr}")
    _ZIG_WRAPPER.append(str(wrapper))
    return str(wrapper)


def _stage_references(name: str, staging: Path) -> list[Path]:
    """The committed regression references of the model, staged for resources/regression/."""
    from drive_rattle_cosim.regression import reference_files

    files = reference_files(name)
    if not all(f.is_file() for f in files):
        print(f"build_fmu.py: no regression references for {name} yet "
              "(python -m drive_rattle_cosim.regression generate)", file=sys.stderr)
        return []
    dest = staging / "regression"
    dest.mkdir(parents=True)
    for f in files:
        shutil.copy2(f, dest / f.name)
    return [dest]


def _stage_packages(staging: Path, cc: str) -> list[Path]:
    """The runtime packages, with the kernel compiled by ``cc`` next to
    drive_rattle/kernel.py."""
    from drive_rattle.kernel import LIBRARY_NAME, compile_kernel

    update_kernel_header()

    out = []
    for package, modules in (("drive_rattle", CORE_RUNTIME), ("drive_rattle_fmi", FMI_RUNTIME)):
        dest = staging / package
        dest.mkdir(parents=True)
        for m in modules:
            shutil.copy2(SRC / package / f"{m}.py", dest / f"{m}.py")
        out.append(dest)
    try:
        compile_kernel(staging / "drive_rattle" / LIBRARY_NAME, cc=cc)
    except RuntimeError as err:
        raise BuildError(str(err)) from None
    return out


def update_kernel_header() -> None:
    """Write fmu_src/native/rattle_kernel_layout.h from drive_rattle/kernel_layout.py when it
    differs (the generated header is committed; the kernel tests fail while it is stale)."""
    from drive_rattle import kernel_layout

    if kernel_layout.write_header():
        print(f"build_fmu.py: regenerated {kernel_layout.HEADER}; commit it", file=sys.stderr)


def _slave_class(name: str, script: Path | None = None):
    if script is not None and str(script.parent) not in sys.path:
        sys.path.insert(0, str(script.parent))
    module = __import__(name)
    return getattr(module, name)


def package(script: Path, out_dir: Path, references: bool = True) -> Path:
    """Build the slave module ``script`` (class = file stem) into ``out_dir/<stem>.fmu`` with
    the runtime packages, generated documentation and the native status shim."""
    from pythonfmu.builder import FmuBuilder

    from drive_rattle_fmi.documentation import HOW_TO_RUN, html_page
    from drive_rattle_fmi.native import install_shim
    from drive_rattle_fmi.slave import (
        LAST_SUCCESSFUL_TIME_VARIABLE,
        MESSAGE_VARIABLE,
        STATUS_ADDRESS_VARIABLE,
    )

    name = script.stem
    cls = _slave_class(name, script)
    cc = c_compiler()
    out_dir.mkdir(parents=True, exist_ok=True)
    fmu = out_dir / f"{name}.fmu"
    with tempfile.TemporaryDirectory(prefix=f"build_{name}_") as tmp:
        tmp = Path(tmp)
        packages = _stage_packages(tmp / "stage", cc)
        if references:
            packages += _stage_references(name, tmp / "stage")
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
    from drive_rattle_fmi.model_description import normalised_xml

    fmu = package(SRC / f"{name}.py", out_dir)

    with zipfile.ZipFile(fmu) as z:
        xml = ElementTree.fromstring(z.read("modelDescription.xml"))
    text = normalised_xml(xml)
    template = TEMPLATES / f"{name}.xml"
    if update_templates:
        TEMPLATES.mkdir(exist_ok=True)
        template.write_text(text, encoding="utf-8")
    elif not template.exists() or template.read_text(encoding="utf-8") != text:
        raise BuildError(
            f"{name}: the interface differs from {template}; review the "
            "change, run `python build_fmu.py --update-templates` and commit the template diff")
    validate(fmu, use_fmutool)
    return fmu


def validate(fmu: Path, use_fmutool: bool = True) -> None:
    """fmpy's validate_fmu and (if installed) `fmutool -check`; raises BuildError on problems."""
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


def build(out_dir: Path = ROOT / "dist", update_templates: bool = False,
          use_fmutool: bool = True) -> list[Path]:
    """Build and validate both FMUs."""
    return [build_one(name, out_dir, update_templates, use_fmutool) for name in MODELS]


#: The system file written next to the FMUs.
SYSTEM_NAME = "DriveRattle.ssp"


def write_system(fmus: list[Path], out_dir: Path) -> Path:
    """``out_dir/DriveRattle.ssp``: both FMUs, their connections, every parameter at its
    default and every input's start value at what its partner outputs at the start (so it
    also runs in masters that exchange nothing during initialization), at the FMUs' default
    experiment; validated against the SSP 1.0 schema."""
    from fmpy import read_model_description

    from drive_rattle_cosim.ssp import (
        SSD_NAME,
        default_parameters,
        validate_ssd,
        write_ssp,
    )

    by_name = {p.stem: p for p in fmus}
    experiment = read_model_description(str(by_name[MODELS[0]])).defaultExperiment
    path = write_ssp(out_dir / SYSTEM_NAME, by_name["GearMeshRattle"], by_name["Driveline"],
                     default_parameters(by_name), step=float(experiment.stepSize),
                     start_time=float(experiment.startTime),
                     stop_time=float(experiment.stopTime), input_starts="consistent")
    with tempfile.TemporaryDirectory() as tmp, zipfile.ZipFile(path) as z:
        z.extract(SSD_NAME, tmp)
        try:
            validate_ssd(Path(tmp) / SSD_NAME)
        except Exception as err:
            raise BuildError(f"{path.name}: the SSD is not valid SSP 1.0: {err}") from None
    return path


#: Where the native (C only) FMUs go, below the output folder.
NATIVE_SUBDIR = "native"


def build_native(out_dir: Path = ROOT / "dist" / NATIVE_SUBDIR, use_fmutool: bool = True,
                 platforms=("linux64", "win64")) -> list[Path]:
    """Build and validate the native FMUs (drive_rattle_fmi.native_fmu) into ``out_dir``."""
    from drive_rattle_cosim.regression import reference_files
    from drive_rattle_fmi.native_fmu import build_native as build

    def references(name: str) -> list[Path]:
        files = reference_files(name)
        return files if all(f.is_file() for f in files) else []

    try:
        return build(Path(out_dir), cc=c_compiler(), templates=TEMPLATES,
                     validate=lambda fmu: validate(fmu, use_fmutool), references=references,
                     platforms=platforms)
    except RuntimeError as err:
        raise BuildError(str(err)) from None


DOCS = ROOT / "docs" / "fmi.md"


def interface_docs(text: str) -> str:
    """``text`` with each ``<!-- BEGIN <Model> interface -->`` ... ``<!-- END ... -->`` block
    replaced by the interface table generated from the specs."""
    from drive_rattle_fmi.documentation import markdown_interface

    for name in MODELS:
        begin, end = f"<!-- BEGIN {name} interface -->", f"<!-- END {name} interface -->"
        head, _, rest = text.partition(begin)
        _, _, tail = rest.partition(end)
        if not rest:
            raise BuildError(f"{DOCS} lacks the marker {begin}")
        text = f"{head}{begin}\n{markdown_interface(_slave_class(name))}{end}{tail}"
    return text


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "dist", help="output folder")
    ap.add_argument("--update-templates", action="store_true",
                    help="write the normalised modelDescriptions to modelDescription_templates/")
    ap.add_argument("--no-fmutool", action="store_true", help="skip `fmutool -check`")
    ap.add_argument("--update-docs", action="store_true",
                    help="regenerate the interface tables in docs/fmi.md and exit")
    ap.add_argument("--update-kernel-header", action="store_true",
                    help="regenerate the compiled kernel's layout header and exit")
    ap.add_argument("--no-native", action="store_true",
                    help="skip the native (C only) FMUs of <out>/native/")
    args = ap.parse_args(argv)
    if args.update_kernel_header:
        update_kernel_header()
        return 0
    if args.update_docs:
        DOCS.write_text(interface_docs(DOCS.read_text(encoding="utf-8")), encoding="utf-8")
        print(f"updated {DOCS}")
        return 0
    try:
        fmus = build(args.out, args.update_templates, not args.no_fmutool)
        for fmu in fmus:
            print(f"built and validated {fmu}")
        print(f"wrote the system {write_system(fmus, args.out)}")
        if not args.no_native:
            native = build_native(args.out / NATIVE_SUBDIR, not args.no_fmutool)
            for fmu in native:
                print(f"built and validated {fmu} (native: C only, linux64 and win64)")
            print(f"wrote the system {write_system(native, args.out / NATIVE_SUBDIR)}")
    except BuildError as err:
        print(f"build_fmu.py: {err}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
