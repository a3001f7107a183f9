"""Session fixtures: the FMUs are built once per test session, into a temporary folder."""

import pytest

from drive_rattle_cosim.fmus import build_script as _build_script


@pytest.fixture(scope="session")
def build_script():
    return _build_script()


@pytest.fixture(scope="session")
def fmus(tmp_path_factory, build_script):
    """{'GearMeshRattle': path, 'Driveline': path}, built and validated for this session."""
    out = tmp_path_factory.mktemp("dist")
    paths = build_script.build(out)
    return {p.stem: p for p in paths}
