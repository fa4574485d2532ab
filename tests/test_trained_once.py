"""The test-only training memo (tests/trained_once.py): what it gives back is what the training
leaves, bit for bit, and an input changed anywhere trains again."""

from dataclasses import replace

import numpy as np
import pytest
import torch
import trained_once as M
from test_protocol import SOURCE, TARGET, method, same_record, tiny

from gearlab.learn import training as T
from gearlab.learn.calibration import RECIPE
from gearlab.learn.networks import build_network
from gearlab.learn.protocol import StateStore, run_unit

pytestmark = pytest.mark.usefixtures("one_torch_thread")


def trained(fit, X, seed=3, on_epoch=None, dropout_seed=None):
    """A `burst` network (dropout: torch's generator is read) trained by *fit*: (net, history, rng);
    with *dropout_seed*, torch's generator set anew after the weights are drawn."""
    torch.manual_seed(seed)
    net = build_network("burst", 2, dropout=0.2, length=X.shape[1])
    if dropout_seed is not None:
        torch.manual_seed(dropout_seed)
    rng = np.random.default_rng(seed)
    val = (X[::5], SOURCE.fault[::5])
    history = fit(net, X, SOURCE.fault, rng=rng, device=torch.device("cpu"), epochs=6, batch=10, val=val,
                  on_epoch=on_epoch)  # fmt: skip
    return net, history, rng


def told(calls):
    return lambda epoch, history: calls.append((epoch, history, [*history.train_loss], history.best_epoch))


def test_a_remembered_training_gives_back_what_the_training_left():
    plain_calls, first_calls, given_calls = [], [], []
    net, history, rng = trained(T.fit_supervised, SOURCE.X, on_epoch=told(plain_calls))
    after = torch.get_rng_state()
    memo = M.remembered(T.fit_supervised, "fit_supervised", M.os.getpid())
    asked = dict(M.ASKED)
    trained(memo, SOURCE.X, on_epoch=told(first_calls))
    again, again_history, again_rng = trained(memo, SOURCE.X, on_epoch=told(given_calls))
    assert M.ASKED["trained"] == asked["trained"] + 1 and M.ASKED["given"] == asked["given"] + 1
    assert torch.equal(torch.get_rng_state(), after)  # torch's generator as the training left it
    assert again_rng.bit_generator.state == rng.bit_generator.state
    assert again_history == history
    for (name, p), q in zip(net.named_parameters(), again.parameters(), strict=True):
        assert torch.equal(p, q) and torch.equal(p.grad, q.grad), name
    assert all(torch.equal(a, b) for a, b in zip(net.buffers(), again.buffers(), strict=True))
    assert [m.training for m in again.modules()] == [m.training for m in net.modules()]
    # on_epoch: one History object, its curves as long as they were at each epoch
    seen = lambda calls: [(e, loss, best) for e, _, loss, best in calls]  # noqa: E731
    assert seen(given_calls) == seen(plain_calls)
    assert len({id(h) for _, h, _, _ in given_calls}) == 1 and given_calls[0][1] is again_history


def test_an_input_changed_anywhere_trains_again():
    memo = M.remembered(T.fit_supervised, "fit_supervised", M.os.getpid())
    trained(memo, SOURCE.X)
    X = SOURCE.X.copy()
    X[7, 100] += 1e-6
    for changed in (
        lambda: trained(memo, X),
        lambda: trained(memo, SOURCE.X, seed=4),
        lambda: trained(memo, SOURCE.X, dropout_seed=5),  # the same weights, other dropout masks
    ):
        before = M.ASKED["trained"]
        changed()
        assert M.ASKED["trained"] == before + 1


@pytest.mark.parametrize("m", [method("mmd"), method("finetune", True, variant="last")], ids=lambda m: m.key)
def test_a_unit_run_with_the_memo_keeps_its_record(m):
    """A protocol unit (calibrated: the priming, its noise augmentation, the adaptation or the fine-tuning)
    gives the record it gives without the memo, whether the memo trains it or answers it."""
    p = replace(tiny(calibration=RECIPE), methods=(m,))
    plain = run_unit(p, SOURCE, TARGET, 0, 2, m, StateStore(None))
    before = M.ASKED["given"]
    with M.trainings_remembered():
        first, given = (run_unit(p, SOURCE, TARGET, 0, 2, m, StateStore(None)) for _ in range(2))
    assert M.ASKED["given"] >= before + 2  # the priming and the unit's own training
    assert same_record(first, plain) and same_record(given, plain)
