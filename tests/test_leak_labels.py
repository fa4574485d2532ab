"""Leaks the protocol's test-row check (tests/test_protocol.py) cannot see: an unsupervised method
handed the target training labels. On the same small synthetic data, with the split fixed."""

from dataclasses import replace

import pytest
import torch
from test_protocol import METHODS, SOURCE, TARGET, tiny

from gearlab.learn import protocol as P
from gearlab.learn.calibration import RECIPE, THESIS
from gearlab.learn.protocol import StateStore, run_unit, split

pytestmark = pytest.mark.usefixtures("one_torch_thread")

UNSUPERVISED = [m for m in METHODS if not m.supervised]


@pytest.mark.parametrize(
    "calibration, network",
    [(THESIS, "burst"), (RECIPE, "burst"), (RECIPE, "shapes")],
    ids=["thesis", "recipe", "recipe-shapes"],
)
@pytest.mark.parametrize("m", UNSUPERVISED, ids=lambda m: m.key)
def test_an_unsupervised_method_reads_no_target_training_label(m, calibration, network, monkeypatch):
    """With the split fixed, flipping the labels of the target *training* rows (k = 2: two faults
    among them) changes nothing an unsupervised method makes: its model, its training curves, its
    score. Its calibration, noise level and threshold take every training row as history, as a
    label-free stream gives them."""
    p, k = tiny(calibration=calibration, network=network), 2
    fixed = split(p, SOURCE, TARGET, 0, k)
    monkeypatch.setattr(P, "split", lambda *args: fixed)
    models = []
    train_method = P.train_method

    def keep_model(*args, **kwargs):
        model, history, extra = train_method(*args, **kwargs)
        models.append({name: t.clone() for name, t in model.state_dict().items()})
        return model, history, extra

    monkeypatch.setattr(P, "train_method", keep_model)
    fault = TARGET.fault.copy()
    fault[fixed.target_train] = 1 - fault[fixed.target_train]
    relabelled = replace(TARGET, fault=fault, label=fault.copy())
    plain, flipped = (run_unit(p, SOURCE, data, 0, k, m, StateStore(None)) for data in (TARGET, relabelled))

    assert models[1].keys() == models[0].keys()
    assert all(torch.equal(models[1][name], models[0][name]) for name in models[0])
    assert flipped["history"] == plain["history"]
    assert flipped["accuracy"] == plain["accuracy"] and flipped["confusion"] == plain["confusion"]
