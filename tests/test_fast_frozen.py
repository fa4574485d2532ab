"""`fast` with frozen or training batch normalisation runs as one autograd function
(gearlab.learn.fast_frozen): the same latent features, gradients and running statistics as its
modules to rounding, and the modules wherever it does not apply."""

import copy

import numpy as np
import pytest
import torch
from torch.nn import functional as F
from torch.utils._python_dispatch import TorchDispatchMode

from gearlab.learn import fast_frozen
from gearlab.learn.networks import build_network, fast_parts
from gearlab.learn.training import fit_adaptation, fit_supervised, train_mode
from gearlab.registry import METHODS, get_registry


def primed(length: int, seed: int = 0, freeze: bool = True):
    """A `fast` network whose normalisations hold statistics of their own (not 0 and 1) and
    weights and biases away from 1 and 0, then frozen as a joint training freezes them (or left
    training, as a priming trains it)."""
    torch.manual_seed(seed)
    net = build_network("fast", 2, length=length, seed=seed)
    with torch.no_grad():
        for _ in range(3):
            net(torch.randn(16, length) * 3 + 1)
        for layer in net.features:
            if isinstance(layer, torch.nn.BatchNorm1d):
                layer.weight.uniform_(0.5, 1.5)
                layer.bias.uniform_(-0.5, 0.5)
    train_mode(net, freeze_norm=freeze)
    return net


def latent_and_grads(net, x, y, modules: bool):
    """The latent features of *x*, every weight's gradient and the buffers after one step, by the
    function or by the modules, from the same state (the network's buffers restored after)."""
    before = copy.deepcopy(net.state_dict())
    net.zero_grad(set_to_none=True)
    torch.manual_seed(1)  # the classifier's dropout draws alike
    z = net.features(x) if modules else net.embed(x)
    F.cross_entropy(net.classifier(z), y).backward()
    buffers = {n: b.clone() for n, b in net.named_buffers()}
    net.load_state_dict(before)
    return z.detach(), {n: p.grad.clone() for n, p in net.named_parameters()}, buffers


@pytest.mark.parametrize("freeze", [True, False], ids=["frozen", "training"])
@pytest.mark.parametrize("length,batch", [(2048, 80), (4096, 40), (2048, 2), (100, 3)])
def test_fast_equals_its_modules(length, batch, freeze):
    net = primed(length, freeze=freeze)
    x, y = torch.randn(batch, length) * 2 + 0.5, torch.randint(0, 2, (batch,))
    z, grads, buffers = latent_and_grads(net, x, y, modules=False)
    z0, grads0, buffers0 = latent_and_grads(net, x, y, modules=True)
    assert net.embed(x).grad_fn.name() == "_FrozenBackward"  # one node: the fused path ran
    assert torch.allclose(z, z0, rtol=0, atol=1e-6 * z0.abs().max())
    for name, g0 in grads0.items():
        assert torch.allclose(grads[name], g0, rtol=0, atol=2e-5 * g0.abs().max()), name
    for name, b0 in buffers0.items():  # training: the running statistics updated alike; frozen: kept
        assert torch.allclose(buffers[name].double(), b0.double(), rtol=0, atol=1e-6 * b0.abs().max()), name
    assert any(not torch.equal(b0, net.state_dict()[n]) for n, b0 in buffers0.items()) != freeze
    net.eval()
    with torch.no_grad():
        assert torch.allclose(net.embed(x), net.features(x), rtol=0, atol=1e-6 * z0.abs().max())
        assert net.embed(x[:, None, :]).shape == (batch, 64)  # (B, 1, L) as (B, L)


def test_modules_where_the_function_does_not_apply():
    net = primed(2048)
    x = torch.randn(8, 2048)
    net.features[6].train()  # one normalisation training, the others frozen
    assert fast_frozen.features(fast_parts(net.features), x) is None
    net.train()
    net.features[6].momentum = None  # a cumulative average of the batches' statistics
    assert fast_frozen.features(fast_parts(net.features), x) is None
    net.features[6].momentum = 0.1
    assert fast_frozen.features(fast_parts(net.features), x) is not None
    short = primed(64, freeze=False)  # one value per channel in the third map: torch refuses it
    assert fast_frozen.features(fast_parts(short.features), torch.randn(1, 64)) is None
    assert fast_frozen.features(fast_parts(short.features), torch.randn(2, 64)) is not None
    train_mode(net, freeze_norm=True)
    assert fast_frozen.features(fast_parts(net.features), x.double()) is None
    assert fast_frozen.features(fast_parts(net.features), x.clone().requires_grad_()) is None
    assert fast_frozen.features(fast_parts(net.features), x.to("meta")) is None  # CPU only: CUDA keeps the modules
    odd = primed(120)  # a first map of 7: MaxPool2's ceil-mode tail
    assert fast_frozen.features(fast_parts(odd.features), torch.randn(4, 120)) is None
    assert torch.equal(odd.embed(torch.randn(4, 120, generator=torch.Generator().manual_seed(0))),
                       odd.features(torch.randn(4, 120, generator=torch.Generator().manual_seed(0))))  # fmt: skip
    cnn = build_network("cnn3", 2, length=256, seed=0).eval()
    assert fast_parts(cnn.features) is None


def test_a_joint_training_stays_within_rounding_of_the_modules(monkeypatch):
    """CORAL's joint training on the function and on the modules: the same course to rounding over
    a few epochs (the rounding grows as any training's does, never as a wrong gradient would)."""
    rng = np.random.default_rng(0)
    X = rng.standard_normal((80, 512)).astype(np.float32)
    y = (np.arange(80) % 2).astype(np.int64)
    X[y == 1, 100:140] += 2.0
    target = rng.standard_normal((80, 512)).astype(np.float32)
    plugin = get_registry().get(METHODS, "coral", "test")
    params = plugin.resolve({}, "test")
    losses = {}
    for path in ("function", "modules"):
        if path == "modules":
            monkeypatch.setattr(fast_frozen, "features", lambda *a: None)
        net = primed(512)
        history = fit_adaptation(
            net, plugin, plugin.extra_modules(net.latent_dim, params), (X, y), (X[:20], y[:20]), (target, None),
            rng=np.random.default_rng(0), device=torch.device("cpu"), batch=20, min_epochs=5, max_epochs=5,
            params=params,
        )  # fmt: skip
        losses[path] = np.array(history.train_loss)
    assert np.allclose(losses["function"], losses["modules"], rtol=1e-4)


def test_a_priming_stays_within_rounding_of_the_modules(monkeypatch):
    """A supervised training (batch normalisation in training mode) on the function and on the
    modules: the same losses to rounding over a few epochs, the same weights and running statistics
    after the first. Adam divides each gradient by its own running size, so the paths' float32
    rounding (1e-7) grows with every step: on an Intel Xeon the states differed by 1.4e-5 of their
    largest value after one epoch (4 steps) and by 3.6e-3 after five (a normalisation's bias, whose
    gradient is near zero); the losses over five epochs by 1.8e-5."""
    rng = np.random.default_rng(1)
    X = rng.standard_normal((80, 512)).astype(np.float32)
    y = (np.arange(80) % 2).astype(np.int64)
    X[y == 1, 100:140] += 2.0
    losses, states = {}, {}
    for path in ("function", "modules"):
        if path == "modules":
            monkeypatch.setattr(fast_frozen, "features", lambda *a: None)
        for epochs in (1, 5):
            net = build_network("fast", 2, length=512, seed=0)
            torch.manual_seed(0)  # the classifier's dropout draws alike
            history = fit_supervised(net, X, y, rng=np.random.default_rng(0), device=torch.device("cpu"),
                                     epochs=epochs, batch=20, val=None)  # fmt: skip
            losses[path, epochs], states[path, epochs] = np.array(history.train_loss), net.state_dict()
    assert np.allclose(losses["function", 5], losses["modules", 5], rtol=1e-4)
    first = states["function", 1]
    for name, value in states["modules", 1].items():
        assert torch.allclose(first[name].double(), value.double(), rtol=0, atol=1e-4 * value.abs().max())
    # the state moved in that epoch: the comparison is not of two untrained networks
    start = build_network("fast", 2, length=512, seed=0).state_dict()
    assert not torch.allclose(start["features.1.weight"], states["function", 1]["features.1.weight"], atol=1e-3)


class _Ops(TorchDispatchMode):
    """The operators a computation calls, by name."""

    def __init__(self):
        super().__init__()
        self.names: list[str] = []

    def __torch_dispatch__(self, func, types, args=(), kwargs=None):
        self.names.append(str(func.overloadpacket))
        return func(*args, **(kwargs or {}))


@pytest.mark.skipif(fast_frozen._INNER is None, reason="this torch has no oneDNN inner product")
@pytest.mark.parametrize("freeze", [True, False], ids=["frozen", "training"])
def test_the_products_run_by_onednn(freeze):
    """The function's 3 products forward and 5 backward at batch 40 are oneDNN's inner product, not
    torch's matrix product (MKL's AVX2 kernels on a CPU MKL does not take for Intel's)."""
    net = primed(2048, freeze=freeze)
    x, y = torch.randn(40, 2048), torch.randint(0, 2, (40,))
    with _Ops() as ops:
        F.cross_entropy(net.classifier(net.embed(x)), y).backward()
    z = net.embed(x).detach().requires_grad_()
    with _Ops() as classifier:  # the dense layers alone: addmm forward, mm for their gradients
        F.cross_entropy(net.classifier(z), y).backward()
    assert ops.names.count("mkldnn._linear_pointwise") == 8
    assert ops.names.count("aten.mm") == classifier.names.count("aten.mm")
    with _Ops() as small:  # batch 2: products of under INNER_MIN multiply-adds, where oneDNN's call costs more
        F.cross_entropy(net.classifier(net.embed(x[:2])), y[:2]).backward()
    assert "mkldnn._linear_pointwise" not in small.names


@pytest.mark.parametrize("m,k,n", [(5120, 64, 16), (16, 5120, 64), (640, 96, 64), (64, 640, 96), (3, 5, 2)])
def test_a_product_of_views_is_the_product(m, k, n):
    """product() of plain and transposed views (the windows, their gradients' transposes) equals the
    product in float64 to float32's rounding of a sum of k terms."""
    a, b = torch.randn(m, k), torch.randn(k, n)
    for left, right in ((a, b), (a.T.contiguous().T, b), (a, b.T.contiguous().T)):
        exact = left.double() @ right.double()
        scale = (left.double().abs() @ right.double().abs()).max()
        assert torch.allclose(fast_frozen.product(left, right).double(), exact, rtol=0, atol=1e-6 * k**0.5 * scale)
