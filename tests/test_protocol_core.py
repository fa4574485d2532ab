"""The one core of both protocols (gearlab.learn.runner): the chapter-5 transfer protocol and the
chapter-4 noise study split a repetition's data by the same cut and run a unit by the same
runner, which gives the training no test row."""

from types import SimpleNamespace

import numpy as np
import pytest
from tiny import bare_dataset, protocol

from gearlab.learn import noise_study, runner
from gearlab.learn import protocol as transfer
from gearlab.learn.noise_study import NoiseProtocol


def test_cut_is_per_class_stretches_sorted_and_disjoint():
    label = np.array([0, 1, 0, 2, 1, 0, 2, 0, 1, 0])
    drawn = runner.orders(label, (0, 1, 2), runner.generator(3, 1))
    train, val, test = runner.cut(drawn, {0: (2, 1), 1: (1, 1), 2: (1, 0)})
    assert [len(train), len(val), len(test)] == [4, 2, 4]
    assert np.array_equal(np.sort(np.concatenate([train, val, test])), np.arange(len(label)))
    for part in (train, val, test):
        assert np.array_equal(part, np.sort(part))
    assert np.array_equal(np.sort(train[label[train] == 0]), np.sort(drawn[0][:2]))  # the order's first stretch
    with pytest.raises(ValueError, match="counts"):
        runner.cut(drawn, {0: (2, 1), 1: (1,), 2: (1, 0)})


def test_put_first_keeps_the_rest_in_order():
    order = np.array([5, 3, 9, 1, 7])
    out = runner.put_first(order, np.array([9, 1]), np.random.default_rng(0))
    assert set(out[:2]) == {9, 1} and list(out[2:]) == [5, 3, 7]


@pytest.mark.parametrize("which", ["transfer", "noise_study"])
def test_both_protocols_split_through_the_one_cut(which, monkeypatch):
    """Neither protocol keeps a split of its own: each one's split is a cut of gearlab.learn.runner."""
    calls = []
    module = transfer if which == "transfer" else noise_study
    real = runner.cut
    monkeypatch.setattr(module, "cut", lambda *a: calls.append(a) or real(*a))
    if which == "transfer":
        fault = (np.arange(40) < 12).astype(np.int8)
        data = SimpleNamespace(X=np.zeros((40, 4)), fault=fault)
        transfer.split(protocol((), ks=(0, 2)), data, data, 0, 2)
    else:
        noise_study.split(np.repeat([0, 1, 2], 12), NoiseProtocol(), 0)
    assert calls


def test_a_noise_study_split_is_stratified_and_seeded_per_run():
    label = np.repeat([0, 1, 2], [30, 12, 9])
    p = NoiseProtocol(seed=4)
    s = noise_study.split(label, p, 2)
    for c, n in zip((0, 1, 2), (30, 12, 9)):
        sizes = noise_study.part_sizes(n, p)
        assert [int((label[part] == c).sum()) for part in (s.train, s.val, s.test)] == list(sizes)
    rng = runner.generator(4, 2)  # the run's generator, the classes drawn in order
    first = rng.permutation(np.flatnonzero(label == 0))
    assert np.array_equal(s.train[label[s.train] == 0], np.sort(first[: noise_study.part_sizes(30, p)[0]]))


class Stop(Exception):
    pass


@pytest.mark.parametrize("which", ["transfer", "noise_study"])
def test_both_protocols_run_a_unit_through_the_one_runner_without_test_rows(which, monkeypatch):
    """Each protocol's run_unit is the common runner's: what trains gets the split without its test part."""
    seen = []

    def runner(split, fit, score, device):
        seen.append((split.test, split.training().test))
        raise Stop

    module = transfer if which == "transfer" else noise_study
    monkeypatch.setattr(module, "held_out", runner)
    fault = (np.arange(40) < 12).astype(np.int8)
    data = bare_dataset(np.zeros((40, 64), np.float32), fault)
    with pytest.raises(Stop):
        if which == "transfer":
            p = protocol((), ks=(0, 2))
            transfer.run_unit(p, data, data, 0, 2, None, transfer.StateStore(None))
        else:
            noise_study.run_unit(NoiseProtocol(device="cpu"), data, 0)
    ((test, hidden),) = seen
    assert len(test) and hidden is None


def test_the_runner_scores_only_after_fitting_and_fit_sees_no_test():
    label = np.repeat([0, 1], 10)
    s = noise_study.split(label, NoiseProtocol(), 0)
    steps = []

    def fit(split, device):
        steps.append(("fit", split.test))
        return "model"

    def score(fitted, test, device):
        steps.append(("score", fitted, test))
        return {"n": len(test)}

    assert runner.run_unit(s, fit, score, "cpu") == {"n": len(s.test)}
    assert steps[0] == ("fit", None) and steps[1][:2] == ("score", "model") and steps[1][2] is s.test
