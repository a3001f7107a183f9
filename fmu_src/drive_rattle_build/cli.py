"""The build's command line: ``drive-rattle-build`` (``python build_fmu.py`` in a clone).

    drive-rattle-build [--out dist] [--update-templates] [--no-fmutool] [--no-native]
                       [--no-fmi3] [--platform NAME ...]
    drive-rattle-build --platform NAME [--platform NAME ...] --fmu FMU [--fmu FMU ...]
    drive-rattle-build --library       # build the model library in place (fmu_src/drive_rattle/)
    drive-rattle-build --update-docs   # docs/fmi.md's tables; the numbers of tools.md, model.md

Besides the pythonfmu FMUs, the same two units implemented entirely in C (no Python at run
time; linux64 and win64 binaries and the C sources) are built into ``<out>/native/`` with their
own system files (``native``; ``--no-native`` skips them), and as FMI 3.0 co-simulation FMUs
(x86_64-linux, x86_64-windows and aarch64-linux binaries) into ``<out>/fmi3/`` with theirs
(``fmi3``; ``--no-fmi3`` skips them).  The system files: ``DriveRattle.ssp`` and
``DriveRattle_outputs.ssp`` (the same with every output a system output, ``system``); those of
the FMI 3.0 units run in ecos and fmu-manipulation-toolbox's container (libcosim and fmpy's SSP
runner read FMI 1.0 and 2.0 FMUs only).

``--platform`` (an FMI 3.0 platform tuple, ``platforms.PLATFORMS``) adds a binary for that
platform, cross-compiled by ziglang's clang: to the native and FMI 3.0 FMUs of the build, or,
with ``--fmu``, to existing FMUs from their own sources (nothing else is built).  The macOS
binaries are untested here (nothing runs them), and the command says so.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .compiler import BuildError
from .documentation import interface_docs
from .library import build_in_place
from .paths import DIST, FMI_DOCS, TOOLS_DOCS
from .platforms import (
    FMI2_SHIPPED,
    FMI3_SHIPPED,
    PLATFORMS,
    UNTESTED,
    UNTESTED_NOTE,
    add_binary,
)

DESCRIPTION = ("Build dist/GearMeshRattle.fmu and dist/Driveline.fmu (FMI 2.0 co-simulation), "
               "validate them, and write the systems dist/DriveRattle.ssp and "
               "dist/DriveRattle_outputs.ssp")


def update_docs() -> list[Path]:
    """Regenerate the interface tables of docs/fmi.md from the specs and the numbers of
    docs/tools.md and docs/model.md from the model library (``tools_doc``,
    ``drive_rattle_cosim.model_doc``: a few minutes of runs); the files."""
    from drive_rattle_cosim import model_doc

    from . import tools_doc

    build_in_place()
    text = FMI_DOCS.read_text(encoding="utf-8")
    FMI_DOCS.write_text(interface_docs(text), encoding="utf-8")
    text = TOOLS_DOCS.read_text(encoding="utf-8")
    TOOLS_DOCS.write_text(tools_doc.update(text), encoding="utf-8")
    text = model_doc.DOC.read_text(encoding="utf-8")
    model_doc.DOC.write_text(model_doc.update(text), encoding="utf-8")
    text = model_doc.ANALYSIS_DOC.read_text(encoding="utf-8")
    model_doc.ANALYSIS_DOC.write_text(
        model_doc.update(text, blocks=model_doc.ANALYSIS_BLOCKS), encoding="utf-8")
    return [FMI_DOCS, TOOLS_DOCS, model_doc.DOC, model_doc.ANALYSIS_DOC]


def with_extra(shipped: tuple[str, ...], extra: list[str]) -> tuple[str, ...]:
    """The shipped platforms and the requested ones, each once."""
    return tuple(dict.fromkeys((*shipped, *extra)))


def listing(platforms: tuple[str, ...], fmi_major: int) -> str:
    """The platforms' folders in an FMU of FMI version ``fmi_major``, the untested ones
    marked."""
    return ", ".join(PLATFORMS[p].folder(fmi_major) + (" (untested)" if p in UNTESTED else "")
                     for p in platforms)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="drive-rattle-build", description=DESCRIPTION)
    ap.add_argument("--out", type=Path, default=DIST, help="output folder")
    ap.add_argument("--update-templates", action="store_true",
                    help="write the normalised modelDescriptions to modelDescription_templates/")
    ap.add_argument("--no-fmutool", action="store_true", help="skip `fmutool -check`")
    ap.add_argument("--update-docs", action="store_true",
                    help="regenerate the interface tables in docs/fmi.md and the numbers "
                         "of docs/tools.md (after a change of the specs or the physics) "
                         "and exit")
    ap.add_argument("--library", action="store_true",
                    help="build the model library in place (next to fmu_src/drive_rattle, "
                         "where the Python API, the studies and the tests load it) and exit")
    ap.add_argument("--no-native", action="store_true",
                    help="skip the native (C only) FMUs of <out>/native/")
    ap.add_argument("--no-fmi3", action="store_true",
                    help="skip the FMI 3.0 (C only) FMUs of <out>/fmi3/")
    ap.add_argument("--platform", action="append", default=[], choices=list(PLATFORMS),
                    metavar="NAME",
                    help="also compile a binary for this platform (an FMI 3.0 platform tuple: "
                         f"{', '.join(PLATFORMS)}; repeatable), into the native and FMI 3.0 "
                         "FMUs of the build, or with --fmu into those FMUs; the macOS ones "
                         "are untested here")
    ap.add_argument("--fmu", action="append", default=[], type=Path, metavar="FMU",
                    help="with --platform: compile that FMU's own sources into it instead of "
                         "building (repeatable)")
    args = ap.parse_args(argv)
    if args.fmu and not args.platform:
        ap.error("--fmu needs --platform NAME: the platform to compile the FMU's sources for")
    try:
        if args.fmu:
            for fmu in args.fmu:
                for name in args.platform:
                    member = add_binary(fmu, name)
                    note = f" ({UNTESTED_NOTE})" if name in UNTESTED else ""
                    print(f"added {member} to {fmu}{note}")
            return 0
        if args.library:
            print(f"built the model library {build_in_place()}")
            return 0
        if args.update_docs:
            for path in update_docs():
                print(f"updated {path}")
            return 0
        # imported here: building the library alone needs none of the FMU tooling
        from .fmu import build
        from .system import write_systems

        fmus = build(args.out, args.update_templates, not args.no_fmutool)
        for fmu in fmus:
            print(f"built and validated {fmu}")
        for system in write_systems(fmus, args.out, not args.no_fmutool):
            print(f"wrote the system {system}")
        if not args.no_native:
            from .native import NATIVE_SUBDIR, build_native

            platforms = with_extra(FMI2_SHIPPED, args.platform)
            native = build_native(args.out / NATIVE_SUBDIR, not args.no_fmutool, platforms)
            for fmu in native:
                print(f"built and validated {fmu} (native: C only, "
                      f"{listing(platforms, 2)})")
            for system in write_systems(native, args.out / NATIVE_SUBDIR,
                                        not args.no_fmutool):
                print(f"wrote the system {system}")
        if not args.no_fmi3:
            from .fmi3 import FMI3_SUBDIR, build_fmi3

            platforms = with_extra(FMI3_SHIPPED, args.platform)
            fmi3 = build_fmi3(args.out / FMI3_SUBDIR, not args.no_fmutool, platforms,
                              update_templates=args.update_templates)
            for fmu in fmi3:
                print(f"built and validated {fmu} (FMI 3.0 co-simulation, C only, "
                      f"{listing(platforms, 3)})")
            for system in write_systems(fmi3, args.out / FMI3_SUBDIR, not args.no_fmutool):
                print(f"wrote the system {system} (of the FMI 3.0 units)")
    except BuildError as err:
        print(f"drive-rattle-build: {err}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
