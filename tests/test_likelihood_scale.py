"""likelihood_ratio's noise scale: each scored revolution's own (default) or the healthy
history's (``scale = "history"``), for faults that raise the whole residual (docs/real_data.md,
the PHM 2009 chip)."""

import numpy as np
import pytest
import torch

from gearlab.learn.bounds import noise_scale, shape_llr
from gearlab.learn.detectors import likelihood_detector

N = 256
SHAPE = np.zeros(N)
SHAPE[40:48] = [0.3, -0.5, 0.6, -0.4, 0.3, -0.2, 0.1, -0.05]  # a short ring


def _data(seed: int = 0):
    rng = np.random.default_rng(seed)
    Xs = np.concatenate([np.zeros((20, N)), np.zeros((10, N)) + 4.0 * SHAPE])
    ys = np.r_[np.zeros(20, int), np.ones(10, int)]
    history = 0.2 * rng.standard_normal((120, N))
    return Xs, ys, history, rng


@pytest.mark.parametrize("kind", ["gaussian", "laplace"])
def test_a_raised_residual_scores_lower_at_its_own_scale_and_higher_at_the_historys(kind):
    """A unit whose residual holds the shape over noise, and the same residual raised 2x (more
    shape and more noise, as the real chip raises the whole residual): at each unit's own noise
    scale the raised one scores *lower* (its size is read as noise); at the history's scale higher."""
    Xs, ys, history, rng = _data()
    if kind == "laplace":
        history = 0.2 * rng.laplace(size=(120, N)) / np.sqrt(2.0)
    r = 4.0 * SHAPE + history[0]  # a unit that fits the simulated shape
    X = np.stack([r, 2.0 * r])
    own = likelihood_detector(Xs, ys, history, None, 0.01)
    fixed = likelihood_detector(Xs, ys, history, None, 0.01, scale="history")
    assert own.kind == fixed.kind == kind
    with torch.no_grad():
        s_own = own.score(torch.as_tensor(X, dtype=torch.float32)).numpy()
        s_fixed = fixed.score(torch.as_tensor(X, dtype=torch.float32)).numpy()
    assert s_own[1] < s_own[0]
    assert s_fixed[1] > s_fixed[0]


def test_the_default_is_each_units_own_scale_and_history_is_the_historys_median():
    from gearlab.registry import get_registry

    Xs, ys, history, rng = _data(1)
    X = torch.as_tensor(history[:5] + 0.1 * rng.standard_normal((5, N)), dtype=torch.float32)
    own = likelihood_detector(Xs, ys, history, None, 0.01)
    fixed = likelihood_detector(Xs, ys, history, None, 0.01, scale="history")
    r = X - own.reference
    assert float(own.scale) == 0.0
    assert torch.allclose(own.embed(X), shape_llr(r, own.shapes, noise_scale(r, own.kind), own.kind))
    expected = float(noise_scale(torch.as_tensor(history, dtype=torch.float32) - fixed.reference, fixed.kind).median())
    assert float(fixed.scale) == pytest.approx(expected, rel=1e-6)
    assert torch.allclose(fixed.embed(X), shape_llr(r, fixed.shapes, fixed.scale.expand(5), fixed.kind))
    adapter = get_registry().get("detector", "likelihood_ratio")
    assert adapter.choices["scale"] == ("unit", "history")
    assert float(adapter.fit((Xs, ys), (history, None), {"scale": 1}).scale) == pytest.approx(expected, rel=1e-6)
    with pytest.raises(ValueError, match="scale"):
        likelihood_detector(Xs, ys, history, None, 0.01, scale="revolution")
