"""Session fixtures: the FMUs are built once per test session, into a temporary folder."""

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _load_build_script():
    spec = importlib.util.spec_from_file_location("build_fmu", ROOT / "build_fmu.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["build_fmu"] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="session")
def build_script():
    return _load_build_script()


@pytest.fixture(scope="session")
def fmus(tmp_path_factory, build_script):
    """{'GearMeshRattle': path, 'Driveline': path}, built and validated for this session."""
    out = tmp_path_factory.mktemp("dist")
    paths = build_script.build(out)
    return {p.stem: p for p in paths}
