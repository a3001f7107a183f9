"""Fixtures of the model tests."""

import pytest

from drive_rattle import MeshParameters
from tests.oracle.mesh import MeshModel

from .helpers import PARAMETER_SETS, Probe


@pytest.fixture(scope="module", params=range(len(PARAMETER_SETS)),
                ids=[",".join(c) or "defaults" for c in PARAMETER_SETS])
def pair(request):
    """(library probe, oracle mesh) of one parameter set."""
    p = MeshParameters(**PARAMETER_SETS[request.param])
    probe = Probe(p)
    yield probe, MeshModel(p)
    probe.close()
