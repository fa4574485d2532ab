"""The `shapes` network's noise scale reads each input revolution alone (its median |r|), so a
training computes it once per row, not at every step of every epoch (issue 42), and trains to the
very same numbers as when every step computed it."""

import numpy as np
import pytest
import torch

import gearlab.learn.bounds as bounds
from gearlab.learn.networks import Network, build_network
from gearlab.learn.training import fit_adaptation, fit_supervised
from gearlab.registry import METHODS, get_registry

CPU = torch.device("cpu")


def _data(shape, seed=0):
    rng = np.random.default_rng(seed)
    X = rng.laplace(size=shape).astype(np.float32)
    y = np.arange(shape[0]) % 2
    X[y == 1, ..., 40:60] += 3.0
    return X, y


def _supervised(X, y, epochs=3, augment=None):
    net = build_network("shapes", 2, length=X.shape[-1], seed=0)
    history = fit_supervised(
        net, X, y, rng=np.random.default_rng(1), device=CPU, epochs=epochs, batch=8, val=None, patience=None,
        augment=augment,
    )  # fmt: skip
    return history, net.state_dict()


def _adaptation(Xs, ys, Xt, augment=None):
    plugin = get_registry().get(METHODS, "mmd", "test")
    params = plugin.resolve({}, "test")
    net = build_network("shapes", 2, length=Xs.shape[-1], seed=0)
    history = fit_adaptation(
        net, plugin, plugin.extra_modules(net.latent_dim, params), (Xs, ys), (Xs[:8, ..., 0, :] if Xs.ndim == 3
        else Xs[:8], ys[:8]), (Xt, None), rng=np.random.default_rng(2), device=CPU, batch=8, min_epochs=2,
        max_epochs=3, params=params, augment=augment,
    )  # fmt: skip
    return history, net.state_dict()


def _noise(x, generator):
    return x + 0.1 * torch.randn(x.shape, generator=generator)


@pytest.fixture
def counted(monkeypatch):
    """The rows whose median the network computes."""
    rows = []
    median = bounds.lower_median
    monkeypatch.setattr(bounds, "lower_median", lambda x: rows.append(len(x)) or median(x))
    return rows


def test_a_training_computes_each_rows_median_once(counted):
    X, y = _data((24, 256))
    _supervised(X, y, epochs=3)
    assert sum(counted) == 24  # every step of 3 epochs computed its batch's: 72


def test_augmented_rows_are_computed_at_each_step(counted):
    X, y = _data((24, 256))
    _supervised(X, y, epochs=2, augment=_noise)
    assert sum(counted) == 48  # fresh noise each step: nothing to keep


def _same(a, b):
    assert a[0].as_dict() == b[0].as_dict()
    assert a[1].keys() == b[1].keys()
    for key in a[1]:
        assert torch.equal(a[1][key], b[1][key]), key


def _each_step(monkeypatch):
    monkeypatch.setattr(Network, "row_state", lambda self, X: None)


@pytest.mark.parametrize("draws", [False, True])
def test_supervised_training_is_the_same_as_computed_at_each_step(monkeypatch, draws):
    X, y = _data((24, 3, 256) if draws else (24, 256))
    once = _supervised(X, y)
    _each_step(monkeypatch)
    _same(once, _supervised(X, y))


@pytest.mark.parametrize("augment", [None, _noise])
def test_joint_training_is_the_same_as_computed_at_each_step(monkeypatch, augment):
    """The target's rows known, the source's too or (fresh noise) computed at each step."""
    Xs, ys = _data((24, 2, 256))
    Xt, _ = _data((24, 256), seed=3)
    once = _adaptation(Xs, ys, Xt, augment)
    _each_step(monkeypatch)
    _same(once, _adaptation(Xs, ys, Xt, augment))


def test_a_batch_of_known_and_unknown_rows():
    """Given medians for some rows (NaN for the others), the scores are those of none given."""
    net = build_network("shapes", 2, length=256, seed=0).eval()
    X = torch.as_tensor(_data((6, 256))[0])
    state = net.row_state(X)
    state[[1, 4]] = float("nan")
    net.give_rows(state)
    with torch.no_grad():
        given = net(X)
        assert torch.equal(given, net(X))  # the next forward computes them all again
