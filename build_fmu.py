"""Build dist/GearMeshRattle.fmu and dist/Driveline.fmu, validate them, and write the system
dist/DriveRattle.ssp: the build's command line (``drive_rattle_build.cli``, installed as
``drive-rattle-build``), kept here for running from a clone.

    python build_fmu.py [--out dist] [--update-templates] [--no-fmutool]
    python build_fmu.py --library | --update-docs
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent / "fmu_src"))

from drive_rattle_build.cli import main

if __name__ == "__main__":
    sys.exit(main())
