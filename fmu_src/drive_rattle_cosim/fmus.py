"""The repository's build script (build_fmu.py) as a module, for examples, benchmarks and tests
that need freshly built FMUs."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def build_script():
    """build_fmu.py, imported once per process."""
    module = sys.modules.get("build_fmu")
    if module is None:
        spec = importlib.util.spec_from_file_location("build_fmu", ROOT / "build_fmu.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules["build_fmu"] = module
        spec.loader.exec_module(module)
    return module


def build_fmus(out_dir: Path = ROOT / "dist", use_fmutool: bool = False) -> dict[str, Path]:
    """Build GearMeshRattle.fmu and Driveline.fmu into ``out_dir``; ``{name: path}``."""
    return {p.stem: p for p in build_script().build(Path(out_dir), use_fmutool=use_fmutool)}
