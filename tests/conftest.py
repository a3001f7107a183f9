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


@pytest.fixture(scope="session")
def native_fmus(tmp_path_factory, build_script):
    """{'GearMeshRattle': path, 'Driveline': path}: the native (C only) FMUs, linux64 and win64
    binaries and sources, built and validated for this session (build_fmu.build_native)."""
    out = tmp_path_factory.mktemp("dist_native")
    paths = build_script.build_native(out)
    return {p.stem: p for p in paths}


FLAVOURS = ("pythonfmu", "native")


@pytest.fixture(scope="session", params=FLAVOURS)
def flavour_fmus(request):
    """The FMUs of each flavour in turn: the pythonfmu FMUs and the native ones."""
    return request.getfixturevalue("fmus" if request.param == "pythonfmu" else "native_fmus")
