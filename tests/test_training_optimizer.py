"""The training loops' optimiser (gearlab.learn.training._Fused): torch.optim's fused Adam and SGD
(per parameter bit for bit; on the parameters as one flat vector bit for bit with torch's kernel
on that vector, to rounding with its per-parameter call), without importing torch._dynamo
(torch.optim's Optimizer does on first use, seconds in every process that trains)."""

import sys

import numpy as np
import pytest
import torch
from torch import nn

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
def test_fused_is_torch_optim_fused_bit_for_bit(name, lr, frozen, monkeypatch):
    """Per parameter (the flat vector off): torch's fused optimiser, bit for bit."""
    monkeypatch.setattr(training, "FLAT_MIN", 10**9)
    ours = _train(training._optimizer, name, lr, frozen)
    theirs = _train(_torch_fused, name, lr, frozen)
    assert isinstance(training._optimizer(name, [torch.zeros(1, requires_grad=True)], lr), training._Fused)
    assert all(torch.equal(a, b) for a, b in zip(ours, theirs, strict=True))
    start = _train(lambda *a: _NoStep(), name, lr, frozen)
    assert not all(torch.equal(a, b) for a, b in zip(ours, start, strict=True))  # the steps moved the weights


@pytest.mark.parametrize(("name", "lr", "frozen"), [("adam", 1e-3, False), ("sgd", 0.01, False), ("adam", 1e-3, True)])
def test_the_flat_path_is_torch_optim_fused_to_rounding(name, lr, frozen):
    """The flat vector, with a step in which a parameter has no gradient (left out of that step,
    its moments and step count too, then per parameter): torch's per-parameter fused optimiser to
    rounding (Adam's kernel rounds a moment's element by 1 ulp in its scalar pass, which takes
    other elements of a flat vector than of each parameter)."""
    ours = _train(training._optimizer, name, lr, frozen)
    theirs = _train(_torch_fused, name, lr, frozen)
    start = _train(lambda *a: _NoStep(), name, lr, frozen)
    for a, b in zip(ours, theirs, strict=True):
        assert torch.allclose(a, b, rtol=0.0, atol=1e-6 * lr / 1e-3)  # Adam moves a weight by ~lr a step
    assert not all(torch.equal(a, s) for a, s in zip(ours, start, strict=True))


@pytest.mark.parametrize(("name", "lr"), [("adam", 1e-3), ("sgd", 0.01)])
def test_the_flat_step_is_torch_optim_fused_on_the_flat_vector(name, lr):
    """While every parameter has a gradient, a training step (clipping and update) is torch's
    fused optimiser on one parameter holding them all, bit for bit; the parameters are views of
    that vector, and each has its own memory again after a training."""
    torch.manual_seed(0)
    net, twin = build_network("cnn3", 3, length=128, seed=1), build_network("cnn3", 3, length=128, seed=1)
    params, twins = list(net.parameters()), list(twin.parameters())
    opt = training._optimizer(name, params, lr)
    # each parameter from a multiple of training.ALIGN elements, zeros between
    spans = [-(-p.numel() // training.ALIGN) * training.ALIGN for p in twins]
    vector = torch.nn.Parameter(_padded([p.detach() for p in twins], spans))
    theirs = _torch_fused(name, [vector], lr)
    assert len({p.untyped_storage().data_ptr() for p in params}) == 1  # one vector
    X, y = torch.randn(8, 128), torch.tensor([0, 1, 2, 0, 1, 2, 0, 1])
    for _ in range(5):
        torch.manual_seed(1)  # the same dropout masks
        opt.zero_grad()
        training._step(opt, params, torch.nn.functional.cross_entropy(net(X), y))
        torch.manual_seed(1)
        twin.zero_grad()
        torch.nn.functional.cross_entropy(twin(X), y).backward()
        vector.grad = _padded([p.grad for p in twins], spans)
        theirs.step()
        with torch.no_grad():
            for p, view in zip(twins, vector.split(spans)):
                p.copy_(view[: p.numel()].view_as(p))
        assert torch.equal(_padded([p.detach() for p in params], spans), vector.detach())
    X8 = np.random.default_rng(0).standard_normal((8, 128)).astype(np.float32)
    fit_supervised(net, X8, np.arange(8) % 3, rng=np.random.default_rng(1), device=torch.device("cpu"), epochs=1,
                   batch=4, optimizer=name)  # fmt: skip
    assert len({p.untyped_storage().data_ptr() for p in net.parameters()}) == len(params)


def _padded(tensors: list[torch.Tensor], spans: list[int]) -> torch.Tensor:
    return torch.cat([nn.functional.pad(t.reshape(-1), (0, n - t.numel())) for t, n in zip(tensors, spans)])


@pytest.mark.parametrize("scale", [1e4, float("nan")])
def test_a_flat_step_near_the_limit_is_clipped_as_torch_clips(scale):
    """A gradient norm beyond MAX_GRAD_NORM (or NaN) is clipped by torch's clipping of the
    parameters' gradients, not the flat vector's norm: the step equals torch's clip_grad_norm_ and
    fused SGD, bit for bit."""
    torch.manual_seed(0)
    net, twin = build_network("cnn3", 3, length=128, seed=1), build_network("cnn3", 3, length=128, seed=1)
    net.eval(), twin.eval()
    X, y = torch.randn(8, 128), torch.tensor([0, 1, 2, 0, 1, 2, 0, 1])
    params, twins = list(net.parameters()), list(twin.parameters())
    loss = torch.nn.functional.cross_entropy(net(X), y) * scale
    training._step(training._optimizer("sgd", params, 0.01), params, loss)
    (torch.nn.functional.cross_entropy(twin(X), y) * scale).backward()
    torch.nn.utils.clip_grad_norm_(twins, training.MAX_GRAD_NORM, foreach=True)
    _torch_fused("sgd", twins, 0.01).step()
    for a, b in zip(params, twins, strict=True):
        assert torch.equal(a.nan_to_num(7.0), b.nan_to_num(7.0))
    if scale == scale:
        assert not torch.equal(params[0], build_network("cnn3", 3, length=128, seed=1).features[1].weight)


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
