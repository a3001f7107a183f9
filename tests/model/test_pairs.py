"""pairs.c, the tooth pairs in the zone of action at a roll coordinate with each pair's
contact point, engaged line, radii and load-approach law (what mesh.c's loads and
dissipation.c's film both read), against the oracle's pair set (tests/oracle/mesh.py,
``MeshModel.pair_laws``: the oracle builds the pairs inside its mesh, as one readable
function) at random pinion angles, for every parameter set of ``pair``."""

import numpy as np
import pytest

from drive_rattle import COAST, DRIVE

from .helpers import PAIR_LAW_FIELDS, close


@pytest.mark.parametrize("flank", [DRIVE, COAST])
def test_pair_laws_equal_the_oracle(pair, flank):
    # Every pair's contact point, engaged line, radii and law coefficients (rm_probe_pair_laws)
    # against the oracle's, at random pinion angles.
    probe, m = pair
    rng = np.random.default_rng(11)
    for phi in np.concatenate([rng.uniform(-3.0, 3.0, 150), rng.uniform(-1e3, 1e3, 50)]):
        got, want = probe.pair_laws(flank, phi), m.pair_laws(flank, phi)
        assert [r["slot"] for r in got] == [w.slot for w in want], phi
        for row, oracle in zip(got, want, strict=True):
            for name in PAIR_LAW_FIELDS[1:]:
                value, expected = row[name], getattr(oracle, name)
                # (roll coordinates and lengths: absolute, as the pairs' test)
                abs_ = 1e-15 if name in ("s", "length") else 1e-300
                assert close(value, expected, abs_=abs_), (name, phi, value, expected)
