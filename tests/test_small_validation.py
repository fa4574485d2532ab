"""Early stopping on a validation set too small for Table 5.3's rule (gearlab.learn.training._chance).

A source of a few dozen samples (a slow shaft's chip: 65 samples, 6 held out) trains 2 steps an
epoch, and a network's batch-normalisation statistics (momentum 0.1 a step, from a variance of 1)
lag signals of small size for tens of epochs: until they catch up it calls every validation sample
one class. Patience 20 then stopped at epoch 20 with the epoch-0 model (validation accuracy 0.5
throughout); the same training left to run reached 1.0."""

from __future__ import annotations

import numpy as np


def _rows(n: int, seed: int, length: int = 256, size: float = 1e-3):
    """*n* rows of white noise of RMS *size*, every other one with a bump of 10 x *size* somewhere."""
    rng = np.random.default_rng(seed)
    y = np.arange(n) % 2
    X = rng.normal(0.0, size, (n, length))
    t = np.arange(length)
    for i in np.flatnonzero(y):
        X[i] += 10 * size * np.exp(-0.5 * ((t - rng.integers(20, length - 20)) / 3) ** 2)
    return X.astype(np.float32), y


def _fit(n_val: int):
    import torch

    from gearlab.learn.networks import build_network
    from gearlab.learn.training import accuracy, fit_supervised

    X, y = _rows(59, 1)
    val = _rows(n_val, 2)
    test = _rows(200, 3)
    torch.manual_seed(0)
    net = build_network("fast", 2, length=256)
    cpu = torch.device("cpu")
    history = fit_supervised(net, X, y, rng=np.random.default_rng(0), device=cpu, epochs=200, batch=40, val=val)
    return history, accuracy(net, *test, cpu)


def test_a_six_sample_validation_set_does_not_stop_an_untrained_network():
    """Before: best epoch 0, stopped at epoch 20, validation 0.5 throughout, test accuracy 0.50.
    Now the patience starts once the network beats the validation set's majority class (3 of 6)."""
    history, test = _fit(6)
    assert max(history.val_acc[:21]) == 0.5  # what stopped it before
    assert history.best_epoch > 20 and history.val_acc[history.best_epoch] == 1.0, history.best_epoch
    assert history.stopped_epoch == history.best_epoch + 20  # then Table 5.3's patience
    assert test >= 0.7, test


def test_twelve_validation_samples_keep_table_5_3s_rule():
    """From 12 validation samples (10 % of the thesis protocol's 120, the smallest set the shipped
    scenarios use) nothing changes: the same stall stops at epoch 20 with the epoch-0 model."""
    history, _ = _fit(12)
    assert (history.best_epoch, history.stopped_epoch) == (0, 20)
