"""The training loops' optimiser (gearlab.learn.training._Fused): torch.optim's fused Adam and SGD
bit for bit, without importing torch._dynamo (torch.optim's Optimizer does on first use, seconds
in every process that trains)."""

import sys

import numpy as np
import pytest
import torch

from gearlab.learn import training
from gearlab.learn.networks import build_network
from gearlab.learn.training import fit_supervised


def _train(make_optimizer, name: str, lr: float, frozen: bool) -> list[torch.Tensor]:
    """Six steps of *name* on a small cnn3: the classifier's parameters only when *frozen*, and
    in the fourth step the last layer gets no gradient (torch leaves such a parameter out of the
    step, its moments and step count included)."""
    torch.manual_seed(0)
    net = build_network("cnn3", 3, length=128, seed=1)
    params = list(net.classifier.parameters() if frozen else net.parameters())
    last = list(net.classifier[-1].parameters())
    opt = make_optimizer(name, params, lr)
    X, y = torch.randn(8, 128), torch.tensor([0, 1, 2, 0, 1, 2, 0, 1])
    for step in range(6):
        opt.zero_grad()
        loss = torch.nn.functional.cross_entropy(net(X), y)
        training._step(opt, params, loss)
        if step == 3:
            for p in last:
                p.grad = None
            opt.step()
    return [p.detach().clone() for p in net.parameters()]


def _torch_fused(name, params, lr):
    return (torch.optim.Adam if name == "adam" else torch.optim.SGD)(params, lr=lr, fused=True)


@pytest.mark.parametrize(("name", "lr", "frozen"), [("adam", 1e-3, False), ("sgd", 0.01, False), ("adam", 1e-3, True)])
def test_fused_is_torch_optim_fused_bit_for_bit(name, lr, frozen):
    ours = _train(training._optimizer, name, lr, frozen)
    theirs = _train(_torch_fused, name, lr, frozen)
    assert isinstance(training._optimizer(name, [torch.zeros(1, requires_grad=True)], lr), training._Fused)
    assert all(torch.equal(a, b) for a, b in zip(ours, theirs, strict=True))
    start = _train(lambda *a: _NoStep(), name, lr, frozen)
    assert not all(torch.equal(a, b) for a, b in zip(ours, start, strict=True))  # the steps moved the weights


class _NoStep:
    def zero_grad(self):
        pass

    def step(self):
        pass


def test_training_imports_no_dynamo(monkeypatch):
    """Both loops' optimisers train with torch._dynamo made unimportable (a None in sys.modules
    makes `import torch._dynamo` fail, whether or not another test imported it before);
    torch.optim's own cannot."""
    X, y = np.random.default_rng(0).standard_normal((8, 128)).astype(np.float32), np.arange(8) % 2
    monkeypatch.setitem(sys.modules, "torch._dynamo", None)
    for optimizer in ("adam", "sgd"):
        net = build_network("cnn3", 2, length=128, seed=1)
        fit_supervised(net, X, y, rng=np.random.default_rng(1), device=torch.device("cpu"), epochs=1, batch=4,
                       optimizer=optimizer)  # fmt: skip
    with pytest.raises(ImportError):  # in its constructor or, once another test has made one, its step
        _torch_fused("adam", list(net.parameters()), 1e-3).step()
