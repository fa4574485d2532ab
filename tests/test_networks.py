"""Networks against thesis 3.1.3-3.1.6 (CNN3, Table 3.1) and the fast CPU default."""

import math

import pytest
import torch
from torch import nn

from gearlab.errors import GearlabInputError
from gearlab.learn.networks import DEFAULT_NETWORK, NETWORKS, TORCH_INIT, Network, build_network

NAMES = ["cnn3", "fast", "burst", "shapes"]


@pytest.fixture(scope="module")
def cnn3():
    torch.manual_seed(0)
    return build_network("cnn3", 2)


def test_registered_names():
    assert set(NAMES) <= set(NETWORKS)
    assert DEFAULT_NETWORK == "shapes"  # the transfer kind's default (docs/learning.md, section 6)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("n_classes", [2, 5])
def test_output_shapes(name, n_classes):
    torch.manual_seed(0)
    net = build_network(name, n_classes)
    assert isinstance(net, Network)
    x = torch.randn(3, 4096)
    net.eval()
    with torch.no_grad():
        logits = net(x)
        z = net.embed(x)
        z_channels = net.embed(x.unsqueeze(1))
        assert torch.equal(net(x.unsqueeze(1)), logits)  # (B, L) and (B, 1, L) are the same batch
        # the modules themselves: `fast` embeds with frozen normalisation by one function (learn/fast_frozen.py),
        # the same sums in another order
        z_modules = net.features(x.unsqueeze(1))
    assert logits.shape == (3, n_classes) and logits.dtype == torch.float32
    assert z.shape == (3, net.latent_dim)
    assert torch.equal(z, z_channels)
    assert (
        torch.equal(z, z_modules) if name != "fast" else torch.allclose(z, z_modules, rtol=0, atol=1e-6 * z.abs().max())
    )
    assert torch.allclose(net.classifier(z), logits)


def test_cnn3_latent_about_30000(cnn3):
    assert 20_000 <= cnn3.latent_dim <= 40_000
    assert cnn3.latent_dim == 8 * 3984


def _blocks(features: nn.Sequential) -> list[list[nn.Module]]:
    blocks: list[list[nn.Module]] = []
    for layer in features:
        if isinstance(layer, nn.Conv1d):
            blocks.append([])
        if blocks:
            blocks[-1].append(layer)
    return blocks


def test_cnn3_block_structure(cnn3):
    layers = list(cnn3.features.modules())
    convs = [m for m in layers if isinstance(m, nn.Conv1d)]
    pools = [m for m in layers if isinstance(m, nn.MaxPool1d)]
    drops = [m for m in layers if isinstance(m, nn.Dropout)]
    assert (len(convs), len(pools), len(drops)) == (3, 3, 2)
    for conv in convs:  # Table 3.1: stride 1, no padding
        assert conv.stride == (1,) and conv.padding == (0,)
    for pool in pools:  # size 2, stride 1 (Table 3.1)
        assert pool.kernel_size == 2 and pool.stride == 1
    blocks = _blocks(cnn3.features)
    assert [any(isinstance(m, nn.Dropout) for m in b) for b in blocks] == [True, False, True]
    for block in blocks:  # conv -> ReLU -> max-pool (-> dropout)
        assert isinstance(block[1], nn.ReLU) and isinstance(block[2], nn.MaxPool1d)
    counts = [c.out_channels for c in convs]
    sizes = [c.kernel_size[0] for c in convs]
    assert counts == sorted(counts) and counts[0] < counts[-1]
    assert sizes == sorted(sizes, reverse=True) and sizes[0] > sizes[-1]
    assert not any(isinstance(m, nn.BatchNorm1d) for m in cnn3.modules())  # dropout, not BN (3.1.3)


def test_cnn3_classifier_120_64(cnn3):
    dense = [m for m in cnn3.classifier.modules() if isinstance(m, nn.Linear)]
    assert [m.out_features for m in dense] == [120, 64, 2]
    assert dense[0].in_features == cnn3.latent_dim
    assert sum(isinstance(m, nn.Dropout) for m in cnn3.classifier.modules()) == 2
    assert sum(isinstance(m, nn.ReLU) for m in cnn3.classifier.modules()) == 2


def test_dropout_default_and_setting():
    net = build_network("cnn3", 2)
    assert {m.p for m in net.modules() if isinstance(m, nn.Dropout)} == {0.005}
    net = build_network("fast", 2, dropout=0.1)
    assert {m.p for m in net.modules() if isinstance(m, nn.Dropout)} == {0.1}


@pytest.mark.parametrize("name", [n for n in NAMES if n not in TORCH_INIT])
def test_he_uniform_init(name):
    torch.manual_seed(1)
    net = build_network(name, 5)
    layers = [m for m in net.modules() if isinstance(m, (nn.Conv1d, nn.Linear))]
    assert layers
    for layer in layers:
        fan_in = layer.weight[0].numel()
        bound = math.sqrt(6.0 / fan_in)  # TensorFlow he_uniform
        w = layer.weight.detach()
        assert w.abs().max() <= bound + 1e-6
        if w.numel() >= 200:  # uniform over the whole range, not PyTorch's default (bound / sqrt(6))
            assert w.abs().max() > 0.8 * bound
            assert w.std() == pytest.approx(bound / math.sqrt(3.0), rel=0.2)
        if layer.bias is not None:
            assert torch.count_nonzero(layer.bias) == 0


@pytest.mark.parametrize("name", NAMES)
def test_deterministic_given_seed(name):
    x = torch.randn(4, 4096)

    def run(seed):
        torch.manual_seed(seed)
        net = build_network(name, 2)
        return net(x)  # training mode: dropout draws from the seeded generator too

    assert torch.equal(run(3), run(3))
    assert not torch.equal(run(3), run(4))
    a = build_network(name, 2, seed=7).state_dict()
    torch.manual_seed(123)
    b = build_network(name, 2, seed=7).state_dict()
    assert all(torch.equal(a[k], b[k]) for k in a)


def _toy(length: int, n: int = 32):
    """Two separable classes: a low and a high tone in noise."""
    g = torch.Generator().manual_seed(0)
    t = torch.arange(length, dtype=torch.float32)
    y = torch.arange(n) % 2
    freq = torch.where(y == 0, 0.01, 0.08).unsqueeze(1)
    x = torch.sin(2 * math.pi * freq * t) + 0.3 * torch.randn(n, length, generator=g)
    return x, y


def test_burst_uses_pytorch_default_init():
    net = build_network("burst", 5, seed=3)
    for layer in [m for m in net.modules() if isinstance(m, (nn.Conv1d, nn.Linear))]:
        bound = 1.0 / math.sqrt(layer.weight[0].numel())
        w = layer.weight.detach()
        assert w.abs().max() <= bound + 1e-6 and w.abs().max() > 0.8 * bound
    again = build_network("burst", 5, seed=3)
    assert all(torch.equal(a, b) for a, b in zip(net.state_dict().values(), again.state_dict().values()))


# burst starts from PyTorch's smaller weights and its batch norm's running statistics lag
# behind in ten steps (eval loss 0.69 -> 0.54 at 10 steps, 0.13 at 30); shapes from its random start
# learns its templates at a tenth of the step, each over an eighth of the revolution, where a
# whole-revolution tone is the worst case for it (0.69 -> 0.61 at 100 steps, 0.33 at 500)
STEPS = {"cnn3": 10, "fast": 10, "burst": 30, "shapes": 500}


@pytest.mark.parametrize("name", NAMES)
def test_adam_reduces_loss_on_toy_problem(name):
    length = 256
    x, y = _toy(length, n=16)
    torch.manual_seed(0)
    net = build_network(name, 2, length=length)
    opt = torch.optim.Adam(net.parameters(), lr=1e-3)
    loss_fn = nn.CrossEntropyLoss()

    def eval_loss():
        net.eval()
        with torch.no_grad():
            value = float(loss_fn(net(x), y))
        net.train()
        return value

    before = eval_loss()
    for _ in range(STEPS[name]):
        opt.zero_grad()
        loss_fn(net(x), y).backward()
        opt.step()
    after = eval_loss()
    assert after < 0.5 * before


def test_unknown_name_lists_known():
    with pytest.raises(GearlabInputError) as err:
        build_network("cnn", 2)
    message = str(err.value)
    assert "unknown network 'cnn'" in message and "did you mean 'cnn3'" in message
    assert "cnn3" in message and "fast" in message


def test_bad_arguments():
    with pytest.raises(GearlabInputError, match="n_classes"):
        build_network("fast", 1)
    with pytest.raises(GearlabInputError, match="dropout"):
        build_network("fast", 2, dropout=1.5)
    with pytest.raises(GearlabInputError, match="at least"):
        build_network("cnn3", 2, length=50)
    net = build_network("cnn3", 2, length=1024)
    with pytest.raises(GearlabInputError, match="1024 samples"):
        net(torch.randn(2, 4096))


def test_fast_accepts_any_length():
    net = build_network("fast", 3).eval()
    with torch.no_grad():
        for length in (256, 4096, 5000):
            assert net(torch.randn(2, length)).shape == (2, 3)
    assert net.latent_dim == 64


def test_parameters_are_float32():
    net = build_network("fast", 2)
    assert all(p.dtype == torch.float32 for p in net.parameters())


@pytest.mark.skipif(not torch.cuda.is_available(), reason="no CUDA device")
@pytest.mark.parametrize("name", NAMES)
def test_cuda_forward_backward(name):
    net = build_network(name, 2).cuda()
    x = torch.randn(4, 4096, device="cuda")
    loss = net(x).logsumexp(1).mean()
    loss.backward()
    assert all(p.grad is not None and p.grad.is_cuda for p in net.parameters())


@pytest.mark.parametrize("frozen", [False, True], ids=["learning statistics", "statistics fixed"])
def test_burst_normalises_only_the_extremes_with_the_numbers_of_the_whole_map(frozen):
    """NormMaxAbs = BatchNorm1d, then |.| and the maximum over the revolution: the same output,
    gradients and running statistics, whether the statistics are learnt or fixed."""
    from gearlab.learn.networks import NormMaxAbs
    from gearlab.learn.training import train_mode

    torch.manual_seed(0)
    fused = NormMaxAbs(6)
    with torch.no_grad():
        fused.weight.copy_(torch.tensor([1.5, -0.7, 0.2, 1.0, -2.0, 0.9]))
        fused.bias.uniform_(-1, 1)
        fused.running_mean.uniform_(-0.5, 0.5)
        fused.running_var.uniform_(0.5, 2.0)
    whole = nn.BatchNorm1d(6)
    whole.load_state_dict(fused.state_dict())
    y = torch.randn(5, 6, 300, requires_grad=True)
    out = []
    for layer, reduce in ((whole, lambda z: z.abs().amax(dim=-1)), (fused, lambda z: z)):
        train_mode(nn.Sequential(layer), freeze_norm=frozen)
        y.grad = None
        r = reduce(layer(y))
        (r * torch.arange(1.0, 7.0)).sum().backward()
        out.append((r.detach(), y.grad.clone(), layer.weight.grad.clone(), layer.running_var.clone()))
    for a, b in zip(*out):
        assert torch.allclose(a, b, atol=1e-6)


def test_the_matched_start_puts_the_fault_bursts_into_burst_s_bank():
    """Two burst shapes at random places: after matched_start the bank holds both (at the bank's
    rate, normalised, at the random start's norm); the other filters keep their random start."""
    import numpy as np

    from gearlab.learn.networks import matched_start

    g = np.random.default_rng(0)
    shapes = [np.exp(-np.arange(60) / 10.0) * np.sin(np.arange(60) / 2.0), np.hanning(60) * np.cos(np.arange(60))]
    faults = np.zeros((40, 4096))
    for i, row in enumerate(faults):
        at = 2 * g.integers(0, 2000)  # on the pool's grid: each shape gives one window
        row[at : at + 60] = (1 + i % 3) * shapes[i % 2]
    net = build_network("burst", 2, seed=1)
    before = net.features[net.bank_layer].weight.detach().clone()
    assert matched_start(net, faults, seed=0)
    w = net.features[net.bank_layer].weight.detach()[:, 0, :].numpy().astype(float)
    assert np.allclose(np.linalg.norm(w[:2], axis=1), before.norm(dim=-1).mean().item(), rtol=1e-5)
    for shape in shapes:
        pooled = shape.reshape(-1, 2).mean(1)
        best = max(
            np.abs(np.correlate(row, pooled, "full")).max() / np.linalg.norm(row) / np.linalg.norm(pooled) for row in w
        )
        assert best > 0.99  # a filter lines up with the burst (up to its sign: the bank's |response| counts)
    assert torch.equal(net.features[net.bank_layer].weight[2:], before[2:])  # two distinct windows, two filters set
    fast = build_network("fast", 2, seed=1)
    state = {k: v.clone() for k, v in fast.state_dict().items()}
    assert not matched_start(fast, faults, seed=0)  # no bank: the random start stays
    assert all(torch.equal(v, fast.state_dict()[k]) for k, v in state.items())
    assert not matched_start(net, np.zeros((5, 4096)), seed=0)


def _faults_and_rows(length: int = 1024, n_faults: int = 12, n_rows: int = 8):
    """Bursts of 60 samples: each lies whole in a template's window (128 samples on a grid of 32)."""
    import numpy as np

    g = np.random.default_rng(4)
    faults = np.zeros((n_faults, length))
    for row in faults:
        at = g.integers(0, length - 60)
        row[at : at + 60] = g.normal(0, 2, 60) * np.hanning(60)
    X = g.laplace(0, 1, (n_rows, length))
    X[: n_rows // 2] += faults[: n_rows // 2]
    return faults, X


def test_shapes_started_on_the_faults_is_the_likelihood_ratio_detector():
    """Started on the fault shapes, the fault logit less the healthy one is the Bayes detector's
    log mixture likelihood ratio in Laplace noise (gearlab.learn.bounds.likelihood_ratio), to
    float32 rounding; the healthy logit is the zero shape's, 0."""
    import numpy as np

    from gearlab.learn.bounds import likelihood_ratio
    from gearlab.learn.networks import matched_start

    faults, X = _faults_and_rows()
    net = build_network("shapes", 2, length=1024, seed=0).eval()
    assert matched_start(net, faults, seed=0, law="laplace")
    with torch.no_grad():
        logits = net(torch.as_tensor(X, dtype=torch.float32)).double().numpy()
    want = likelihood_ratio(X, np.zeros(1024), faults, "laplace")
    assert np.allclose(logits[:, 0], 0.0)
    assert np.allclose(logits[:, 1], want, rtol=1e-4, atol=1e-2)
    assert (want[:4] > want[4:].max()).all()  # and it ranks the rows holding a fault first


def test_shapes_templates_learn_at_a_tenth_of_the_step_and_only_members_weigh():
    """One Adam step moves every weight by the learning rate: the templates by SHAPE_STEP of it;
    the log weights of templates outside a class's mixture (the healthy class's, and those beyond
    the faults in use) get no gradient."""
    from gearlab.learn.networks import SHAPE_STEP, matched_start

    faults, X = _faults_and_rows()
    net = build_network("shapes", 2, length=1024, seed=0)
    matched_start(net, faults, seed=0, law="laplace")
    before = net.features[1].shapes.detach().clone()
    opt = torch.optim.Adam(net.parameters(), lr=1e-2)
    y = torch.tensor([1, 1, 1, 1, 0, 0, 0, 0])
    nn.functional.cross_entropy(net(torch.as_tensor(X, dtype=torch.float32)), y).backward()
    grad = net.classifier.log_weight.grad
    assert torch.count_nonzero(grad[1:, 0]) == 0 and torch.count_nonzero(grad[0, 1:]) == 0
    assert torch.count_nonzero(grad[len(faults) + 1 :]) == 0
    opt.step()
    moved = (net.features[1].shapes.detach() - before).abs()
    assert moved.max() == pytest.approx(SHAPE_STEP * 1e-2, rel=1e-2)  # Adam: lr · g / (|g| + eps)


def test_shapes_with_classes_and_priors_is_the_bayes_classifier():
    """Started with per-class templates, a noise law and class priors, `shapes` outputs the
    Bayes classifier's log posteriors up to one constant per row: log p_c + log mean_j p(r | t_j)
    over class c's templates, healthy the zero shape (Gaussian law, scale from median|r|)."""
    import numpy as np

    from gearlab.learn.networks import matched_start

    rng = np.random.default_rng(0)
    faults, classes = rng.normal(size=(9, 64)), np.array([1, 1, 2, 2, 2, 3, 3, 3, 3])
    prior = np.array([0.4, 0.2, 0.3, 0.1])
    net = build_network("shapes", 4, length=64, seed=0)
    assert matched_start(net, faults, seed=0, classes=classes, law="gaussian", prior=prior)
    # the templates are the faults on their windows of an eighth of the revolution (these
    # whole-revolution noise "faults" lose the rest; the network is the Bayes classifier of what it holds)
    held = net.features[1].shapes.detach().double().numpy()[: len(faults)]  # the rest of the bank unused
    r = rng.normal(size=(6, 64)) + np.concatenate([np.zeros((2, 64)), faults[[0, 4, 8, 3]]])
    sigma = np.sort(np.abs(r), axis=1)[:, 31] / 0.6744897501960817  # torch's median: the lower middle
    held_class = net.classifier.member[1 : len(faults) + 1].numpy().argmax(1)
    for h, c in zip(held, held_class):  # each template is one of its class's faults, on its window
        on = h != 0
        assert on.sum() == net.features[1].width == 8 and any(
            np.allclose(h[on], f[on], atol=1e-6) for f in faults[classes == c]
        )
    llr = (2 * r @ held.T - (held**2).sum(1)) / (2 * sigma[:, None] ** 2)
    expected = np.stack(
        [np.log(prior[0]) + np.zeros(len(r))]
        + [np.log(prior[c]) + np.log(np.exp(llr[:, held_class == c]).mean(1)) for c in (1, 2, 3)],
        axis=1,
    )
    with torch.no_grad():
        got = net(torch.as_tensor(r, dtype=torch.float32)).double().numpy()
    assert np.allclose(got, expected, rtol=1e-4, atol=1e-3)
    assert net.classifier.member.sum(0).tolist() == [1, 2, 3, 4]  # healthy: the zero shape alone


@pytest.mark.parametrize("law", ["laplace", "gaussian", "student_t"])
def test_shapes_local_templates_are_the_whole_revolution_likelihood_exactly(law):
    """A template held on its window (a quarter revolution, wrapping round) scores a revolution
    exactly as the same template zero outside its window scored over the whole revolution."""
    import numpy as np

    from gearlab.learn.bounds import noise_scale, shape_llr
    from gearlab.learn.networks import ShapeLikelihood

    rng = np.random.default_rng(1)
    layer = ShapeLikelihood(5, 96, law=law, width=24)
    bursts = np.zeros((5, 96))
    for j, centre in enumerate([3, 30, 50, 80, 94]):  # the first and the last wrap round
        bursts[j, (centre + np.arange(-6, 6)) % 96] = rng.normal(size=12)
    layer.place(bursts)
    assert np.allclose(layer.shapes.detach().double().numpy(), bursts, atol=1e-6)  # each burst whole in its window
    r = torch.as_tensor(rng.laplace(size=(7, 96)), dtype=torch.float32)
    dense = shape_llr(r, layer.shapes, noise_scale(r, law), law)
    assert torch.allclose(layer(r), dense, rtol=1e-5, atol=1e-4)


@pytest.mark.parametrize("dtype", [torch.float32, torch.float64])
def test_shapes_compiled_laplace_scores_and_gradients_are_torch_s(dtype):
    """The compiled loops (LaplaceGain, taken for a CPU input that needs no gradient) give the
    gathered windows' torch path's scores and template gradients, wrapping windows included."""
    import numpy as np

    from gearlab.learn.networks import LaplaceGain, ShapeLikelihood

    rng = np.random.default_rng(2)
    layer = ShapeLikelihood(6, 96, law="laplace", width=24).to(dtype)
    bursts = np.zeros((6, 96))
    for j, centre in enumerate([2, 20, 30, 50, 80, 95]):  # two share a window, two wrap round
        bursts[j, (centre + np.arange(-5, 5)) % 96] = rng.normal(size=10)
    layer.place(bursts)
    r = torch.as_tensor(rng.laplace(size=(9, 96)), dtype=dtype)
    assert LaplaceGain.applies(r, layer.weight) and not LaplaceGain.applies(r.clone().requires_grad_(), layer.weight)
    g = torch.as_tensor(rng.normal(size=(9, 6)), dtype=dtype)
    scores, grads = [], []
    for x in (r, r.clone().requires_grad_()):  # compiled, then torch's path
        layer.weight.grad = None
        z = layer(x)
        (z * g).sum().backward()
        scores.append(z.detach())
        grads.append(layer.weight.grad.clone())
    tol = 1e-5 if dtype == torch.float32 else 1e-12
    assert torch.allclose(scores[0], scores[1], rtol=tol, atol=tol * scores[1].abs().max())
    assert torch.allclose(grads[0], grads[1], rtol=tol, atol=tol)
    assert grads[0].abs().sum() > 0


def test_shapes_torch_laplace_path_takes_as_many_operators_for_any_number_of_windows():
    """Where the compiled loops do not serve (a GPU; here an input that needs a gradient), a
    `shapes` layer's Laplace scores take the same few operators whether its templates sit in 2
    windows or 32: no loop over the windows, whose operators and device synchronisations each
    made a CUDA step 10 times a CPU core's."""
    from torch.utils._python_dispatch import TorchDispatchMode

    from gearlab.learn.networks import ShapeLikelihood

    class Count(TorchDispatchMode):
        def __torch_dispatch__(self, func, types, args=(), kwargs=None):
            self.calls = getattr(self, "calls", 0) + 1
            return func(*args, **(kwargs or {}))

    counts = []
    for windows in (2, 32):
        layer = ShapeLikelihood(64, 512, law="laplace", width=64)  # windows 16 samples apart
        with torch.no_grad():
            layer.offset.copy_(torch.arange(64) % windows * 16)
        r = torch.randn(4, 512, requires_grad=True)
        with Count() as count:
            layer(r)
        counts.append(count.calls)
    assert counts[0] == counts[1] < 40


@pytest.mark.parametrize("length", [2048, 2050, 256])
def test_fast_window_conv_and_pair_pool_are_conv1d_and_max_pool(length):
    """`fast`'s first convolution as a product of windows and its pool's gradient without
    indices: the outputs of nn.Conv1d and nn.MaxPool1d(2, ceil_mode=True) exactly, the same
    gradients to rounding (an odd map, 2050 samples, takes max_pool1d itself)."""
    import copy

    from gearlab.learn.networks import MaxPool2, WindowConv1d

    net = build_network("fast", 2, length=length, seed=0)
    assert isinstance(net.features[1], WindowConv1d) and isinstance(net.features[4], MaxPool2)
    reference = copy.deepcopy(net)
    reference.features[1].__class__ = nn.Conv1d
    reference.features[4] = nn.MaxPool1d(2, ceil_mode=True)
    x, y = torch.randn(8, length), torch.tensor([0, 1] * 4)
    outputs = []
    for model in (net, reference):
        torch.manual_seed(3)  # the same dropout
        out = model.classifier(model.features(x))  # the modules (embed: learn/fast_frozen.py)
        nn.functional.cross_entropy(out, y).backward()
        outputs.append(out.detach())
    assert torch.equal(outputs[0], outputs[1])
    for a, b in zip(net.parameters(), reference.parameters(), strict=True):
        assert torch.allclose(a.grad, b.grad, rtol=1e-4, atol=1e-6 * b.grad.abs().max())


def test_shapes_place_keeps_the_window_with_most_energy():
    """A template wider than its window keeps the grid window that holds most of its energy."""
    import numpy as np

    from gearlab.learn.networks import ShapeLikelihood

    layer = ShapeLikelihood(1, 64, width=16)
    shape = np.zeros((1, 64))
    shape[0, 40:52] = 1.0  # windows start on a grid of 4: 36 or 40 hold all of it, 40 the first
    shape[0, 5] = 0.5  # a small part elsewhere is left out
    layer.place(shape)
    assert layer.offset.tolist() == [36]
    kept = layer.shapes.detach().double().numpy()[0]
    assert np.allclose(kept[40:52], 1.0) and kept[5] == 0.0


def _plain_mixture(mixture, z: torch.Tensor, classes: int) -> torch.Tensor:
    """ShapeMixture's logits of its first *classes* classes the plain way: a logsumexp over
    (B, J + 1, C), non-members at -inf."""
    z = torch.cat([torch.zeros_like(z[:, :1]), z], dim=1)
    log_weight = mixture.log_weight.masked_fill(~mixture.member, -math.inf)[:, :classes]
    return torch.logsumexp(z[:, :, None] + log_weight[None], dim=1)


@pytest.mark.parametrize("dtype", [torch.float32, torch.float64])
def test_shapes_mixture_sums_each_class_over_its_own_members(dtype):
    """Each class's log-sum over its own templates gives the plain logsumexp's logits and
    gradients to rounding: random scores and weights, a class whose members all lie 1,000 below
    the others (finite, no NaN), templates in no class, one class with none (-inf, and no NaN in
    the gradients, where logsumexp's backward gives NaN: left out of its logits here)."""
    from gearlab.learn.networks import ShapeMixture

    g = torch.Generator().manual_seed(0)
    mixture = ShapeMixture(40, 5).to(dtype)
    classes = torch.randint(1, 4, (33,), generator=g)  # class 4 has no template, templates 33-39 no class
    mixture.use(classes.numpy(), prior=[0.3, 0.2, 0.2, 0.2, 0.1])
    with torch.no_grad():
        mixture.log_weight.add_(torch.randn(41, 5, generator=g, dtype=dtype))
    z = 30 * torch.randn(6, 40, generator=g, dtype=dtype)
    z[:, (classes == 2).nonzero().squeeze(1)] -= 1000.0  # class 2 far below the others
    outputs, grads = [], []
    for forward in (mixture, lambda x: _plain_mixture(mixture, x, 4)):
        mixture.log_weight.grad = None
        x = z.clone().requires_grad_()
        out = forward(x)
        out[:, :4].mul(torch.linspace(-1, 1, 4, dtype=dtype)).sum().backward()
        outputs.append(out.detach())
        grads.append((x.grad, mixture.log_weight.grad.clone()))
    ours, plain = outputs
    assert torch.isfinite(ours[:, :4]).all() and (ours[:, 2] < ours[:, 1] - 500).all()
    assert torch.equal(ours[:, 4], torch.full((6,), -math.inf, dtype=dtype))  # no member: -inf, as logsumexp
    tol = 1e-6 if dtype == torch.float32 else 1e-13
    assert torch.allclose(ours[:, :4], plain[:, :4], rtol=tol, atol=0)
    # logsumexp's backward takes exp(score - logit) with logits ~100: float32 rounds it by ~1e-5
    tol = 1e-4 if dtype == torch.float32 else 1e-12
    for mine, theirs in zip(*grads):
        assert torch.isfinite(mine).all()
        assert torch.allclose(mine, theirs, rtol=tol, atol=tol * theirs.abs().max())
    member = mixture.member
    assert torch.count_nonzero(grads[0][1][~member]) == 0 and torch.count_nonzero(grads[0][1][member]) > 0


def test_shapes_mixture_of_a_class_at_minus_infinity_is_minus_infinity():
    """A class whose weights are all -inf (a prior of 0) has logit -inf, as logsumexp's, and
    passes no NaN to the scores' gradient."""
    from gearlab.learn.networks import ShapeMixture

    mixture = ShapeMixture(6, 3)
    mixture.use([1, 1, 1, 2, 2, 2])
    with torch.no_grad():
        mixture.log_weight[4:, 2] = -math.inf
    z = torch.randn(4, 6, requires_grad=True)
    out = mixture(z)
    assert torch.equal(out[:, 2], torch.full((4,), -math.inf)) and torch.isfinite(out[:, :2]).all()
    assert torch.allclose(out[:, :2], _plain_mixture(mixture, z.detach(), 2), rtol=1e-6, atol=0)
    nn.functional.cross_entropy(out, torch.tensor([0, 1, 0, 1])).backward()
    assert torch.isfinite(z.grad).all()


@pytest.mark.parametrize("dtype", [torch.float32, torch.float64])
def test_shapes_compiled_loops_scale_the_templates_as_torch_s_product(dtype):
    """The loops scale each stored template by SHAPE_STEP as they use it: the scores and the
    stored templates' gradient of torch's ``weight * SHAPE_STEP`` scored at scale 1, bit for bit."""
    from gearlab.learn.networks import SHAPE_STEP, LaplaceGain

    g = torch.Generator().manual_seed(4)
    weight = torch.randn(12, 32, generator=g, dtype=dtype, requires_grad=True)
    offset = torch.arange(12) * 8 % 128
    r = torch.randn(9, 128, generator=g, dtype=dtype)
    padded, grad = torch.cat([r, r[:, :32]], dim=1), torch.randn(9, 12, generator=g, dtype=dtype)
    results = []
    for scaled_in_loops in (True, False):
        weight.grad = None
        if scaled_in_loops:
            z = LaplaceGain.apply(padded, weight, offset, SHAPE_STEP)
        else:
            z = LaplaceGain.apply(padded, weight * SHAPE_STEP, offset, 1.0)
        (z * grad).sum().backward()
        results.append((z.detach(), weight.grad.clone()))
    assert torch.equal(results[0][0], results[1][0]) and torch.equal(results[0][1], results[1][1])
    assert results[0][1].abs().sum() > 0
