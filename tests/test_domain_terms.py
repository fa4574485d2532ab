"""An adapter's domain loss and its batch's discrepancy from one computation (issue 42): CORAL and
MMD² are computed once a joint step, and the training is the very one of the loss and the
discrepancy computed apart (the adapter contract's default, which DANN keeps)."""

import numpy as np
import pytest
import torch

import gearlab.learn.losses as losses
from gearlab.learn.networks import build_network
from gearlab.learn.training import fit_adaptation
from gearlab.registry import METHODS, get_registry


def _train(adapter, counted=None, monkeypatch=None):
    rng = np.random.default_rng(0)
    Xs, Xt = rng.standard_normal((2, 24, 256)).astype(np.float32)
    ys = np.tile([0, 1], 12)
    net = build_network("fast", 2, length=256, seed=0)
    params = adapter.resolve({}, "test")
    modules = adapter.extra_modules(net.latent_dim, params)
    history = fit_adaptation(
        net, adapter, modules, (Xs, ys), (Xs[:8], ys[:8]), (Xt, None), rng=np.random.default_rng(1),
        device=torch.device("cpu"), batch=8, min_epochs=3, max_epochs=4, params=params, alignment="healthy",
    )  # fmt: skip
    return history, net.state_dict()


class Apart:
    """*adapter* with the contract's default domain_terms: the loss, then discrepancy() after the step."""

    def __init__(self, adapter):
        self.adapter = adapter

    def __getattr__(self, name):
        return getattr(self.adapter, name)

    def domain_terms(self, z_s, z_t, modules, lam, params=None):
        return self.adapter.domain_loss(z_s, z_t, modules, lam, params), None


@pytest.mark.parametrize("name", ["coral", "mmd", "dann"])
def test_one_computation_trains_as_two(name):
    adapter = get_registry().get(METHODS, name, "test")
    torch.manual_seed(0)
    once, state = _train(adapter)
    torch.manual_seed(0)
    apart, state_apart = _train(Apart(adapter))
    assert once.as_dict() == apart.as_dict()  # losses, validation accuracies, discrepancies: equal floats
    assert all(torch.equal(state[k], state_apart[k]) for k in state)


@pytest.mark.parametrize("name, loss", [("mmd", "mmd2"), ("coral", "coral_loss")])
def test_a_joint_step_computes_its_measure_once(name, loss, monkeypatch):
    calls = []
    real = getattr(losses, loss)
    monkeypatch.setattr(losses, loss, lambda *a, **k: calls.append(1) or real(*a, **k))
    monkeypatch.setattr(f"gearlab.api.{loss}", getattr(losses, loss))
    history, _ = _train(get_registry().get(METHODS, name, "test"))
    steps = len(history.train_loss) * 3  # 24 rows in batches of 8
    assert len(calls) == steps
