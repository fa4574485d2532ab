"""The chapter-4 Bayes bound (gearlab.learn.bounds.class_bound): the classifier that knows
every class's noise-free shapes and the noise law."""

import numpy as np
import pytest
import torch

from gearlab.errors import GearlabInputError
from gearlab.learn.bounds import _log_density, class_bound

LENGTH = 64


def problem(kind: str, level: float, seed: int = 0, n: int = 60, sizes=(0.5, 1.0), teeth=1):
    """Three classes: a mesh sine (healthy) and two bursts at two sizes each; noise of *kind*
    at *level* times each revolution's RMS, the noisy rows standardised by 0.7 (as a noisy
    chapter-4 dataset is against its twin)."""
    rng = np.random.default_rng(seed)
    t = np.arange(LENGTH)
    mesh = np.sin(2 * np.pi * 4 * t / LENGTH)
    shapes = {0: [mesh]}
    for c, where in ((1, 10), (2, 40)):  # a class's bursts on *teeth* teeth, 6 samples apart
        shapes[c] = [mesh + a * np.exp(-0.5 * ((t - where - 6 * z) / 2.0) ** 2) for z in range(teeth) for a in sizes]
    label = np.repeat([0, 1, 2], n)
    clean = np.stack([shapes[c][i % len(shapes[c])] for i, c in enumerate(label)])
    draw = {
        "gaussian": rng.standard_normal,
        "laplace": lambda s: rng.laplace(size=s),
        "student_t": lambda s: rng.standard_t(2, s),
    }[kind]
    rms = np.sqrt((clean**2).mean(1, keepdims=True))
    X = 0.7 * (clean + level * rms * draw(clean.shape))
    return X.astype(np.float32), clean.astype(np.float32), label, shapes


def brute_force(X, label, shapes, kind, alpha, ratio):
    """The class posterior's arg max, elementwise, from the true shapes."""
    out = []
    for x in torch.as_tensor(X, dtype=torch.float64):
        post = []
        for c in sorted(shapes):
            ll = []
            for s in shapes[c]:
                scale = torch.tensor(ratio * np.sqrt((s**2).mean()), dtype=torch.float64)
                n = x - alpha * torch.as_tensor(s)
                ll.append(_log_density(n, scale, kind).sum() - LENGTH * torch.log(scale))
            post.append(torch.logsumexp(torch.stack(ll), 0) - np.log(len(ll)) + np.log((label == c).mean()))
        out.append(int(torch.stack(post).argmax()))
    return np.array(out)


def test_noise_free_rows_are_all_classified():
    X, clean, label, _ = problem("gaussian", 1e-3)
    assert (class_bound(X, clean, label, "gaussian") == label).all()


@pytest.mark.parametrize("kind", ["gaussian", "laplace", "student_t"])
def test_the_distance_forms_give_the_elementwise_posterior(kind):
    """Laplace and Gaussian go through distances, Student-t elementwise: every law picks the
    class the elementwise posterior picks (with the scale read off the data, 0.7 and the level)."""
    X, clean, label, shapes = problem(kind, 0.8, seed=3, n=12)
    pred = class_bound(X, clean, label, kind, chunk=7)
    # the data's own estimates, as class_bound reads them: alpha exactly 0.7 only in expectation
    alpha = float(np.median((X * clean).sum(1) / (clean * clean).sum(1)))
    from gearlab.learn.bounds import noise_scale

    R = torch.as_tensor(X - alpha * clean, dtype=torch.float64)
    ratio = float(
        torch.median(noise_scale(R, kind) / torch.as_tensor(np.sqrt((clean**2).mean(1)), dtype=torch.float64))
    )
    assert (pred == brute_force(X, label, shapes, kind, alpha, ratio)).all()
    assert 0.5 < (pred == label).mean() < 1.0  # noisy enough to err, clean enough to learn


def test_more_noise_lowers_the_bound():
    acc = {
        lvl: (class_bound(*problem("laplace", lvl, seed=1)[:3], "laplace") == problem("laplace", lvl, 1)[2]).mean()
        for lvl in (0.5, 1.5)
    }
    assert acc[0.5] > acc[1.5]


def test_an_unknown_law_is_refused():
    X, clean, label, _ = problem("gaussian", 0.1)
    with pytest.raises(GearlabInputError, match="unknown noise kind 'cauchy'"):
        class_bound(X, clean, label, "cauchy")
