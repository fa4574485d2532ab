"""The faster paths of a training step give the very numbers of the paths they replace (issue 42):
the compiled lower median, the gradient clipping, and the rows a batch gathers."""

import numpy as np
import pytest
import torch
from torch import nn

from gearlab.learn.bounds import lower_median
from gearlab.learn.training import MAX_GRAD_NORM, _clip, _rows


@pytest.mark.parametrize(
    "rows",
    [
        np.random.default_rng(0).standard_normal((7, 4096)),
        np.random.default_rng(1).laplace(size=(3, 1, 4095)),  # the burst network's (B, 1, L)
        np.random.default_rng(2).integers(-3, 3, (5, 17)).astype(float),  # ties
        np.zeros((2, 8)),
        -np.abs(np.random.default_rng(3).standard_normal((4, 9))),
        np.random.default_rng(4).standard_normal((6, 2)) * 1e-40,  # subnormal in float32
        np.array([[1.0, np.nan, 2.0, 3.0, np.inf], [-np.inf, np.nan, np.nan, 0.0, 1.0]]),
    ],
)
def test_the_compiled_median_is_numpys_element(rows):
    x = torch.as_tensor(rows, dtype=torch.float32)
    middle = (x.shape[-1] - 1) // 2
    expected = np.partition(x.numpy(), middle, axis=-1)[..., middle : middle + 1]
    np.testing.assert_array_equal(lower_median(x).numpy(), expected)  # NaN where numpy has NaN


@pytest.mark.parametrize("scale", [1.0, 1e3, float("nan")])  # not clipped, clipped, a NaN gradient
def test_clipping_gives_torchs_gradients(scale):
    torch.manual_seed(0)
    mine = [nn.Parameter(torch.randn(5, 7)), nn.Parameter(torch.randn(3)), nn.Parameter(torch.randn(2))]
    torchs = [nn.Parameter(p.detach().clone()) for p in mine]
    for p, q in zip(mine[:2], torchs[:2]):
        p.grad = torch.randn_like(p) * 3  # a norm of about 18: below MAX_GRAD_NORM
        p.grad[0] *= scale
        q.grad = p.grad.clone()
    _clip(mine)
    nn.utils.clip_grad_norm_(torchs, MAX_GRAD_NORM, foreach=True)
    for p, q in zip(mine, torchs):
        assert (p.grad is None and q.grad is None) or torch.equal(p.grad.nan_to_num(7.0), q.grad.nan_to_num(7.0))
    norm = float(torch.linalg.vector_norm(torch.cat([p.grad.flatten() for p in mine[:2]])))
    assert norm < 30 if scale == 1.0 else (abs(norm - MAX_GRAD_NORM) < 1e-3 if scale > 1 else np.isnan(norm))


def test_batch_rows_are_the_indexed_rows():
    X = torch.randn(10, 3, 8)
    index = torch.tensor([4, 0, 9, 4])
    rows, flat = _rows(X[:, 0], index, None)
    np.testing.assert_array_equal(rows, X[:, 0][index])
    np.testing.assert_array_equal(flat, index)
    rng = np.random.default_rng(5)
    pick = torch.as_tensor(np.random.default_rng(5).integers(3, size=4))
    rows, flat = _rows(X, index, rng)
    np.testing.assert_array_equal(rows, X[index, pick])
    np.testing.assert_array_equal(flat, 3 * index + pick)  # where they lie among the (n x D, L) rows
