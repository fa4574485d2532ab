"""The engine (x-domain cumulative integrals) against the thesis's equations integrated in alpha."""

import numpy as np
import pytest
from pem_reference import tooth_pair_stiffness

from gearlab.physics.presets import gear_pair
from gearlab.physics.stiffness import MeshStiffnessModel, StiffnessOptions


@pytest.mark.parametrize("preset", ["luo2019", "meng2020"])
@pytest.mark.parametrize("fillet", [True, False])
def test_healthy_tooth_pair_matches_direct_quadrature(preset, fillet):
    pair = gear_pair(preset)
    model = MeshStiffnessModel(pair, StiffnessOptions(fillet=fillet))
    phi = np.linspace(0.0, pair.theta_t, 25)[1:-1]
    ours = model.tooth_pair_stiffness(phi)
    reference = np.array([tooth_pair_stiffness(pair, p, fillet) for p in phi])
    assert np.max(np.abs(ours / reference - 1)) < 1e-4
