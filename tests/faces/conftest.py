"""The faces of the model library, each question of tests/faces asked of every one: the
``face`` fixture runs a test once per face, on the FMUs the session built (tests/conftest.py),
with what differs between them as the face's parameters.  A face added later is one more
entry of FACES."""

from __future__ import annotations

from dataclasses import dataclass

import pytest

from .calls import loaded
from .raw_fmi import DIALECTS, Model


@dataclass(frozen=True)
class Face:
    """One face: its name, its FMI standard, the session fixture that builds its FMUs, and
    what its FMUs show of themselves."""

    name: str
    standard: str  # "2.0" or "3.0"
    fixture: str  # of tests/conftest.py
    #: the prefix of instantiation's refusals (before any instance exists)
    instantiate: str
    #: the file that marks the resources folder of an FMU of this face
    marker: str
    #: the folder of the x86-64 Linux and Windows binaries
    linux: str
    windows: str | None

    @property
    def native(self) -> bool:
        """C only: sources in the FMU, no Python where it runs."""
        return self.name != "pythonfmu"

    @property
    def dialect(self):
        return DIALECTS[self.standard]

    @property
    def prefix(self) -> str:
        """The prefix of the standard's functions ("fmi2", "fmi3")."""
        return self.dialect.prefix

    def needs_native(self, what: str) -> None:
        """Skip: ``what`` is a C-only face's (the pythonfmu FMUs carry Python, not C)."""
        if not self.native:
            pytest.skip(f"the pythonfmu face has no {what}: its FMUs carry the Python slaves")


FACES = {
    "pythonfmu": Face("pythonfmu", "2.0", "fmus", "rattle FMI shim: fmi2Instantiate: ",
                      "slavemodule.txt", "linux64", None),
    "native": Face("native", "2.0", "native_fmus", "rattle native FMU: fmi2Instantiate: ",
                   "model_identifier.txt", "linux64", "win64"),
    "fmi3": Face("fmi3", "3.0", "fmi3_fmus",
                 "rattle native FMU: fmi3InstantiateCoSimulation: ",
                 "model_identifier.txt", "x86_64-linux", "x86_64-windows"),
}


@pytest.fixture(scope="session", params=list(FACES))
def face(request) -> Face:
    return FACES[request.param]


@pytest.fixture(scope="session")
def native_face(face):
    """The face, if it is C only (skipped before its FMUs are built otherwise)."""
    face.needs_native("C sources and no binary that runs without Python")
    return face


@pytest.fixture(scope="session")
def windows_face(face):
    """The face, if it ships a Windows binary (skipped before its FMUs are built otherwise;
    the binary is in ``shipped_face_fmus``)."""
    if face.windows is None:
        pytest.skip("the pythonfmu face ships no Windows binary (why: "
                    "tests/fmu/test_windows_binary.py)")
    return face


@pytest.fixture(scope="session")
def face_fmus(request, face) -> dict:
    """{'GearMeshRattle': path, 'Driveline': path}: the face's FMUs, built for this session."""
    return request.getfixturevalue(face.fixture)


@pytest.fixture(scope="session")
def shipped_face_fmus(request, face) -> dict:
    """The face's FMUs as shipped, with the binaries of every platform (tests marked
    ``cross``; the pythonfmu face ships the build machine's alone)."""
    return request.getfixturevalue(face.fixture if face.name == "pythonfmu"
                                   else f"shipped_{face.fixture}")


@pytest.fixture(scope="module")
def models(face, face_fmus, tmp_path_factory) -> dict:
    """The face's FMUs unpacked and loaded in the raw driver, by model."""
    return loaded(face_fmus, tmp_path_factory, face.name)


@pytest.fixture
def mesh(models) -> Model:
    return models["GearMeshRattle"]
