"""Adapter contract and shared losses against thesis 5.1-5.3 and Table 5.3."""

import importlib
import subprocess
import sys

import numpy as np
import pytest
import torch
import torch.nn.functional as F
from torch import nn

from gearlab.errors import GearlabInputError
from gearlab.learn.adapters import SUPERVISIONS, TRAIN_ON, Adapter, lambda_schedule
from gearlab.learn.losses import (
    GradientReversal,
    coral_loss,
    grad_reverse,
    median_distance,
    mmd2,
)
from gearlab.learn.networks import build_network
from gearlab.registry import Registry
from gearlab.settings import declared

# The entry points are registered in pyproject.toml separately; import the modules directly.
PLUGINS = ["source_only", "target_only", "mmd", "dann", "coral", "finetune"]
CALIBRATED = {
    "source_only": False,
    "target_only": False,
    "mmd": True,
    "dann": True,
    "coral": True,
    "finetune": True,
}
DA = ["mmd", "dann", "coral"]


def adapter(name: str) -> Adapter:
    module = importlib.import_module(f"gearlab_plugins.adapters.{name}")
    objects = module.gearlab_adapters()
    assert len(objects) == 1
    return objects[0]


def sample(n, d, shift=0.0, seed=0):
    g = torch.Generator().manual_seed(seed)
    return torch.randn(n, d, generator=g, dtype=torch.float64) + shift


# ----------------------------------------------------------------------------- MMD


def test_mmd2_zero_for_identical_samples():
    x = sample(20, 8)
    assert float(mmd2(x, x.clone())) == pytest.approx(0.0, abs=1e-12)
    assert float(mmd2(x, x, bandwidths=1.5)) == pytest.approx(0.0, abs=1e-12)


def test_mmd2_symmetric_and_nonnegative():
    x, y = sample(15, 6, seed=1), sample(25, 6, shift=0.5, seed=2)
    assert float(mmd2(x, y)) == pytest.approx(float(mmd2(y, x)), rel=1e-12)
    assert float(mmd2(x, y, bandwidths=[0.5, 2.0])) == pytest.approx(
        float(mmd2(y, x, bandwidths=[0.5, 2.0])), rel=1e-12
    )
    assert float(mmd2(x, y)) > 0.0


@pytest.mark.parametrize("bandwidths", [None, 2.0])
def test_mmd2_grows_with_shift(bandwidths):
    x, base = sample(40, 5, seed=3), sample(40, 5, seed=4)
    same = float(mmd2(x, base, bandwidths))
    values = [float(mmd2(x, base + s, bandwidths)) for s in (0.25, 0.5, 1.0, 2.0)]
    assert same < values[0]
    assert values == sorted(values) and values[-1] > 3 * values[0]


def test_mmd2_matches_brute_force_eq_5_9():
    x, y = sample(7, 4, seed=5).numpy(), sample(11, 4, shift=0.3, seed=6).numpy()  # M != N
    sigma = 1.3

    def k(a, b):
        return np.exp(-np.sum((a - b) ** 2) / (2 * sigma**2))

    m, n = len(x), len(y)
    expected = (
        sum(k(x[i], x[j]) for i in range(m) for j in range(m)) / m**2
        + sum(k(y[i], y[j]) for i in range(n) for j in range(n)) / n**2
        - 2 * sum(k(x[i], y[j]) for i in range(m) for j in range(n)) / (m * n)
    )
    assert float(mmd2(torch.from_numpy(x), torch.from_numpy(y), bandwidths=sigma)) == pytest.approx(expected, rel=1e-10)
    # several bandwidths: the sum of the single-bandwidth values
    both = float(mmd2(torch.from_numpy(x), torch.from_numpy(y), bandwidths=[sigma, 2 * sigma]))
    parts = [float(mmd2(torch.from_numpy(x), torch.from_numpy(y), bandwidths=s)) for s in (sigma, 2 * sigma)]
    assert both == pytest.approx(sum(parts), rel=1e-10)


def test_default_bandwidths_from_median_heuristic():
    x, y = sample(6, 3, seed=12), sample(9, 3, shift=1.0, seed=13)
    pooled = torch.cat([x, y]).numpy()
    i, j = np.triu_indices(len(pooled), k=1)
    median = np.median(np.linalg.norm(pooled[i] - pooled[j], axis=1))
    assert median_distance(x, y) == pytest.approx(median, rel=0.05)  # torch takes the lower middle value
    sigmas = [median_distance(x, y) * s for s in (0.25, 0.5, 1.0, 2.0, 4.0)]
    assert float(mmd2(x, y)) == pytest.approx(float(mmd2(x, y, bandwidths=sigmas)), rel=1e-12)
    assert float(mmd2(x, y, scale=2.0)) == pytest.approx(
        float(mmd2(x, y, bandwidths=[2 * s for s in sigmas])), rel=1e-12
    )


def written_out_mmd2(x: torch.Tensor, y: torch.Tensor) -> torch.Tensor:
    """Eq. 5.9 as written, block by block and bandwidth by bandwidth: the mean kernel within x,
    within y and twice across, at the median heuristic's bandwidths of the pooled pairs."""

    def sq(a, b):
        return ((a[:, None, :] - b[None, :, :]) ** 2).sum(-1)

    with torch.no_grad():
        pooled = torch.cat([sq(x, x)[tuple(torch.triu_indices(len(x), len(x), 1))],
                            sq(y, y)[tuple(torch.triu_indices(len(y), len(y), 1))], sq(x, y).reshape(-1)])  # fmt: skip
        median = float(pooled.median().sqrt())
    total = x.new_zeros(())
    for s in (0.25, 0.5, 1.0, 2.0, 4.0):
        gamma = 1.0 / (2.0 * (median * s) ** 2)
        total = total + sum(w * torch.exp(-gamma * sq(a, b)).mean() for w, a, b in ((1, x, x), (1, y, y), (-2, x, y)))
    return total


@pytest.mark.parametrize("m, n", [(40, 40), (7, 11), (1, 2)])
def test_mmd2_and_its_gradients_are_eq_5_9_written_out(m, n):
    """mmd2 computes the pooled sample's kernel at once (one matrix of distances, every bandwidth
    in one call, eq. 5.9 as a quadratic form): the value and both samples' gradients of the
    equation written out, to float64 rounding."""
    x, y = sample(m, 6, seed=20).requires_grad_(), sample(n, 6, shift=0.4, seed=21).requires_grad_()
    value = mmd2(x, y)
    gx, gy = torch.autograd.grad(value, (x, y))
    expected = written_out_mmd2(x, y)
    ex, ey = torch.autograd.grad(expected, (x, y))
    assert float(value.detach()) == pytest.approx(float(expected.detach()), rel=1e-12)
    assert torch.allclose(gx, ex, rtol=0, atol=1e-12 * ex.abs().max())
    assert torch.allclose(gy, ey, rtol=0, atol=1e-12 * ey.abs().max())


def test_mmd2_takes_every_bandwidth_in_one_kernel_call(monkeypatch):
    """The five bandwidths' kernels of the pooled sample in one exponential (a joint step's MMD
    took 0.97 ms forward and backward as fifteen, 0.40 ms as one: 40 + 40 x 64, one thread)."""
    calls = []
    real = torch.exp
    monkeypatch.setattr(torch, "exp", lambda t: calls.append(t.shape) or real(t))
    mmd2(sample(40, 64, seed=22), sample(40, 64, seed=23))
    assert calls == [(5, 80, 80)]


def test_mmd2_gradient_finite_and_pulls_domains_together():
    x = sample(10, 3, seed=7).float().requires_grad_()
    y = sample(10, 3, shift=1.0, seed=8).float()
    y[0] = x[0].detach()  # a zero distance must not give NaN gradients
    mmd2(x, y).backward()
    assert torch.isfinite(x.grad).all()
    # a small step against the gradient brings x towards y
    with torch.no_grad():
        moved = x - 0.5 * x.grad
    assert float(mmd2(moved, y)) < float(mmd2(x.detach(), y))


# ----------------------------------------------------------------------------- GRL, CORAL


@pytest.mark.parametrize("coeff", [1.0, 0.3, 0.0])
def test_gradient_reversal_flips_and_scales(coeff):
    x = torch.randn(5, 3, requires_grad=True)
    w = torch.randn(5, 3)
    out = GradientReversal.apply(x, coeff)
    assert torch.equal(out, x)
    (out * w).sum().backward()
    assert torch.allclose(x.grad, -coeff * w)
    x.grad = None
    (grad_reverse(x, coeff) * w).sum().backward()
    assert torch.allclose(x.grad, -coeff * w)


def _coral_direct(x, y):
    d = x.shape[1]
    return np.sum((np.cov(x, rowvar=False) - np.cov(y, rowvar=False)) ** 2) / (4 * d * d)


@pytest.mark.parametrize("d", [3, 50])  # direct covariances and the Gram-matrix route
def test_coral_loss_matches_definition(d):
    x, y = sample(10, d, seed=9), sample(12, d, seed=10) * 1.7
    assert float(coral_loss(x, y)) == pytest.approx(_coral_direct(x.numpy(), y.numpy()), rel=1e-9)


@pytest.mark.parametrize("d", [3, 50])
def test_coral_loss_zero_for_identical_covariances(d):
    x = sample(12, d, seed=11)
    assert float(coral_loss(x, x.clone())) == pytest.approx(0.0, abs=1e-15)
    permuted_and_shifted = x[torch.randperm(12)] + 3.0  # same covariance, other order and mean
    assert float(coral_loss(x, permuted_and_shifted)) == pytest.approx(0.0, abs=1e-12)
    assert float(coral_loss(x, 2.0 * x)) > 0.0


def test_coral_loss_float32_wide_latent():
    x = torch.randn(40, 31_872)
    value = coral_loss(x, x * 1.1)
    assert value.dtype == torch.float32 and torch.isfinite(value) and float(value) > 0


# ----------------------------------------------------------------------------- DANN


def test_dann_domain_loss_gradients():
    dann = adapter("dann")
    torch.manual_seed(0)
    modules = dann.extra_modules(4)
    z_s = torch.randn(6, 4, requires_grad=True)
    z_t = (torch.randn(6, 4) + 1.0).requires_grad_()
    lam = 0.3
    loss = dann.domain_loss(z_s, z_t, modules, lam)
    loss.backward()

    # the same binary cross-entropy without the reversal layer
    ref_s, ref_t = z_s.detach().clone().requires_grad_(), z_t.detach().clone().requires_grad_()
    ref_modules = dann.extra_modules(4)
    ref_modules.load_state_dict(modules.state_dict())
    logits = ref_modules["domain"](torch.cat([ref_s, ref_t])).squeeze(1)
    labels = torch.cat([torch.zeros(6), torch.ones(6)])
    ref = F.binary_cross_entropy_with_logits(logits, labels)
    ref.backward()

    assert float(loss.detach()) == pytest.approx(float(ref.detach()), rel=1e-6)
    # domain classifier: plain gradient of the domain loss -> descent makes it discriminate
    for p, q in zip(modules.parameters(), ref_modules.parameters()):
        assert torch.allclose(p.grad, q.grad, atol=1e-7)
    # features: reversed and scaled by λ -> descent makes them confuse the classifier
    assert torch.allclose(z_s.grad, -lam * ref_s.grad, atol=1e-7)
    assert torch.allclose(z_t.grad, -lam * ref_t.grad, atol=1e-7)


def test_dann_adversarial_game_directions():
    dann = adapter("dann")
    torch.manual_seed(1)
    modules = dann.extra_modules(8)
    z_s, z_t = torch.randn(40, 8), torch.randn(40, 8) + 0.7

    # descending the domain loss trains the domain classifier to discriminate
    opt = torch.optim.SGD(modules.parameters(), lr=0.1)
    start_loss, start_gap = (
        float(dann.domain_loss(z_s, z_t, modules, 1.0).detach()),
        dann.discrepancy(z_s, z_t, modules),
    )
    for _ in range(100):
        opt.zero_grad()
        dann.domain_loss(z_s, z_t, modules, 1.0).backward()
        opt.step()
    trained_loss = float(dann.domain_loss(z_s, z_t, modules, 1.0).detach())
    assert trained_loss < start_loss
    assert dann.discrepancy(z_s, z_t, modules) > start_gap
    assert dann.domain_accuracy(z_s, z_t, modules) > 0.7

    # descending the same loss with respect to the features raises the domain loss (confusion)
    feats_s, feats_t = z_s.clone().requires_grad_(), z_t.clone().requires_grad_()
    opt = torch.optim.SGD([feats_s, feats_t], lr=0.5)
    for _ in range(20):
        opt.zero_grad()
        dann.domain_loss(feats_s, feats_t, modules, 1.0).backward()
        opt.step()
    assert float(dann.domain_loss(feats_s, feats_t, modules, 1.0).detach()) > trained_loss
    assert dann.discrepancy(feats_s.detach(), feats_t.detach(), modules) < dann.discrepancy(z_s, z_t, modules)


def test_dann_discrepancy_is_distance_from_chance():
    dann = adapter("dann")
    modules = dann.extra_modules(2)
    with torch.no_grad():
        domain = modules["domain"]
        for layer in domain:
            if isinstance(layer, nn.Linear):
                layer.weight.zero_()
                layer.bias.zero_()
        domain[0].weight[0, 0] = 1.0
        domain[2].weight[0, 0] = 1.0
        domain[2].bias[0] = -0.5
    # logit = relu(z0) - 0.5: source at z0 = 0 -> source, target at z0 = 2 -> target
    z_s, z_t = torch.zeros(4, 2), torch.tensor([[2.0, 0.0]]).repeat(4, 1)
    assert dann.domain_accuracy(z_s, z_t, modules) == 1.0
    assert dann.discrepancy(z_s, z_t, modules) == 0.5
    assert dann.discrepancy(z_s, z_s, modules) == 0.0  # all called 'source': 50 % balanced accuracy


# ----------------------------------------------------------------------------- schedule, contract


@pytest.mark.parametrize("name", [None, *PLUGINS])
def test_lambda_schedule_table_5_3(name):
    schedule = lambda_schedule if name is None else adapter(name).lambda_schedule
    expected = {0: 0.0, 24: 0.0, 25: 0.05, 49: 0.05, 250: 0.5, 499: 0.95, 500: 1.0, 501: 1.0, 10_000: 1.0}
    for epoch, lam in expected.items():
        assert schedule(epoch) == pytest.approx(lam, abs=1e-12), epoch


def test_lambda_schedule_params():
    mmd = adapter("mmd")
    params = mmd.resolve({"lambda_step": 0.1, "lambda_every": 10, "lambda_max": 0.5})
    assert [mmd.lambda_schedule(e, params) for e in (0, 10, 30, 100)] == pytest.approx([0.0, 0.1, 0.3, 0.5])


@pytest.mark.parametrize("name", PLUGINS)
def test_plugin_contract(name):
    obj = adapter(name)
    assert isinstance(obj, Adapter) and obj.name == name
    registry = Registry()
    registry.add("adapter", obj, "gearlab", name)
    assert not registry.problems and registry.names("adapter") == [name]
    schema = declared(obj.params)
    for p, default in schema.values():
        assert p.unit == "" and p.low <= default <= p.high
    assert obj.calibrated is CALIBRATED[name]
    assert obj.supervision and set(obj.supervision) <= set(SUPERVISIONS)
    assert obj.train_on in TRAIN_ON and obj.optimizer in ("adam", "sgd")
    info = obj.describe()
    assert {"doc", "params", "calibrated", "supervision"} <= set(info)
    assert info["doc"] and info["calibrated"] is obj.calibrated
    assert [p["name"] for p in info["params"]] == list(schema)
    for method in ("extra_modules", "domain_loss", "discrepancy", "lambda_schedule", "trainable", "resolve"):
        assert callable(getattr(obj, method))
    assert obj.resolve() == {name: default for name, (_, default) in schema.items()}


def test_supervision_and_training_regimes():
    assert adapter("source_only").supervision == ("unsupervised",) and adapter("source_only").train_on == "source"
    assert adapter("target_only").supervision == ("supervised",) and adapter("target_only").train_on == "target"
    for name in DA:
        assert set(adapter(name).supervision) == set(SUPERVISIONS) and adapter(name).train_on == "joint"
        assert adapter(name).optimizer == "sgd"
    assert adapter("finetune").supervision == ("supervised",) and adapter("finetune").train_on == "target"
    assert not hasattr(adapter("mmd"), "detector")  # a method without a network is a detector plugin


@pytest.mark.parametrize("name", ["source_only", "target_only", "finetune"])
def test_methods_without_domain_loss(name):
    obj = adapter(name)
    z_s, z_t = torch.randn(4, 8), torch.randn(4, 8) + 1
    assert len(obj.extra_modules(8)) == 0
    assert float(obj.domain_loss(z_s, z_t, obj.extra_modules(8), 1.0)) == 0.0
    assert obj.discrepancy(z_s, z_t, obj.extra_modules(8)) >= 0.0


def test_mmd_and_coral_domain_losses():
    z_s, z_t = torch.randn(10, 6), torch.randn(10, 6) * 2 + 1
    mmd, coral = adapter("mmd"), adapter("coral")
    assert float(mmd.domain_loss(z_s, z_t, nn.ModuleDict(), 0.4)) == pytest.approx(
        0.4 * float(mmd2(z_s, z_t)), rel=1e-6
    )
    assert mmd.discrepancy(z_s, z_t, nn.ModuleDict()) == pytest.approx(float(mmd2(z_s, z_t)), rel=1e-6)
    assert float(mmd.domain_loss(z_s, z_s.clone(), nn.ModuleDict(), 1.0)) == pytest.approx(0.0, abs=1e-6)
    assert float(coral.domain_loss(z_s, z_t, nn.ModuleDict(), 0.4)) == pytest.approx(
        0.4 * float(coral_loss(z_s, z_t)), rel=1e-6
    )
    assert float(coral.domain_loss(z_s, z_s.clone(), nn.ModuleDict(), 1.0)) == pytest.approx(0.0, abs=1e-9)
    assert float(mmd.domain_loss(z_s, z_t, nn.ModuleDict(), 0.0)) == 0.0


@pytest.mark.parametrize("name", DA)
def test_joint_training_step(name):
    """One calibrated step (eq. 5.12 / 5.18) on the fast network: finite, and every part gets a gradient."""
    obj = adapter(name)
    torch.manual_seed(0)
    net = build_network("fast", 2, length=512)
    modules = obj.extra_modules(net.latent_dim)
    x_s, x_t = torch.randn(8, 512), torch.randn(8, 512) * 1.5
    y_s = torch.randint(0, 2, (8,))
    z = net.embed(torch.cat([x_s, x_t]))  # one joint batch
    z_s, z_t = z[:8], z[8:]
    loss = F.cross_entropy(net.classifier(z_s), y_s) + obj.domain_loss(z_s, z_t, modules, obj.lambda_schedule(100))
    loss.backward()
    assert torch.isfinite(loss)
    assert all(p.grad is not None and torch.isfinite(p.grad).all() for p in net.parameters())
    assert all(p.grad is not None for p in modules.parameters())


def test_finetune_variants():
    ft = adapter("finetune")
    net = build_network("fast", 2)
    ids = lambda params: {id(p) for p in params}  # noqa: E731
    assert ids(ft.trainable(net)) == ids(net.parameters())  # default: all
    assert ids(ft.trainable(net, ft.resolve({"variant": "classifier"}))) == ids(net.classifier.parameters())
    last = [m for m in net.classifier if isinstance(m, nn.Linear)][-1]
    assert ids(ft.trainable(net, ft.resolve({"variant": "last"}))) == ids(last.parameters())
    assert ids(ft.trainable(net, {"variant": 2})) == ids(last.parameters())
    assert ids(ft.trainable(net, {"variant": "last"})) == ids(last.parameters())
    assert ft.resolve({"variant": 1}) == {"variant": 1}
    with pytest.raises(GearlabInputError, match="did you mean 'classifier'"):
        ft.resolve({"variant": "clasifier"})
    with pytest.raises(GearlabInputError, match="outside"):
        ft.resolve({"variant": 3})


def test_unknown_adapter_parameter():
    with pytest.raises(GearlabInputError, match="did you mean 'bandwidth_scale'"):
        adapter("mmd").resolve({"bandwith_scale": 2})


# ----------------------------------------------------------------------------- startup


def test_registry_loads_without_torch():
    """Every gearlab command loads the registry, which imports every plugin module; torch
    (seconds to import) must wait until a network or a loss is actually needed."""
    code = (
        "import sys; from gearlab.registry import get_registry; r = get_registry(); "
        "assert 'torch' not in sys.modules, sorted(m for m in sys.modules if m.startswith('torch'))[:5]; "
        "assert not r.problems, r.problems; "
        "assert {'mmd', 'dann', 'coral', 'finetune', 'source_only', 'target_only'} <= set(r.names('adapter'))"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=False)
    assert result.returncode == 0, result.stderr


def test_contract_module_has_no_torch():
    code = "import sys, gearlab.learn.adapters, gearlab.learn; assert 'torch' not in sys.modules"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=False)
    assert result.returncode == 0, result.stderr
