"""The build's command line: ``drive-rattle-build`` (``python build_fmu.py`` in a clone).

    drive-rattle-build [--out dist] [--update-templates] [--no-fmutool] [--no-native]
    drive-rattle-build --update-docs            # regenerate the interface tables of docs/fmi.md
    drive-rattle-build --update-kernel-header   # regenerate fmu_src/native/rattle_kernel_layout.h

Besides the pythonfmu FMUs, the same two units implemented entirely in C (no Python at run
time; linux64 and win64 binaries and the C sources) are built into ``<out>/native/`` with their
own system files (``native``; ``--no-native`` skips them).  The system files: ``DriveRattle.ssp``
and ``DriveRattle_outputs.ssp`` (the same with every output a system output, ``system``).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from drive_rattle.interface import MODELS

from . import kernel
from .compiler import BuildError
from .documentation import interface_docs
from .fmu import build, slave_class
from .native import NATIVE_SUBDIR, build_native
from .paths import DIST, FMI_DOCS
from .system import write_systems

DESCRIPTION = ("Build dist/GearMeshRattle.fmu and dist/Driveline.fmu (FMI 2.0 co-simulation), "
               "validate them, and write the systems dist/DriveRattle.ssp and "
               "dist/DriveRattle_outputs.ssp")


def update_docs() -> None:
    """Regenerate the interface tables of docs/fmi.md from the specs."""
    text = FMI_DOCS.read_text(encoding="utf-8")
    classes = {name: slave_class(name) for name in MODELS}
    FMI_DOCS.write_text(interface_docs(text, classes), encoding="utf-8")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="drive-rattle-build", description=DESCRIPTION)
    ap.add_argument("--out", type=Path, default=DIST, help="output folder")
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
    try:
        if args.update_kernel_header:
            kernel.update_header()
            return 0
        if args.update_docs:
            update_docs()
            print(f"updated {FMI_DOCS}")
            return 0
        fmus = build(args.out, args.update_templates, not args.no_fmutool)
        for fmu in fmus:
            print(f"built and validated {fmu}")
        for system in write_systems(fmus, args.out):
            print(f"wrote the system {system}")
        if not args.no_native:
            native = build_native(args.out / NATIVE_SUBDIR, not args.no_fmutool)
            for fmu in native:
                print(f"built and validated {fmu} (native: C only, linux64 and win64)")
            for system in write_systems(native, args.out / NATIVE_SUBDIR):
                print(f"wrote the system {system}")
    except BuildError as err:
        print(f"drive-rattle-build: {err}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
