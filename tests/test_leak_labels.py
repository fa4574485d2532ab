"""Leaks the protocol's test-row check (tests/test_protocol.py) cannot see: in the adapter variants
its METHODS leave out, an unsupervised method handed the target training labels, and `shapes`
scoring in a noise law it was not read from the history. On the same small synthetic data."""

from dataclasses import replace

import numpy as np
import pytest
import torch
from test_protocol import METHODS, SOURCE, TARGET, method, synthetic, tiny
from test_protocol import test_target_test_samples_cannot_reach_training_stopping_or_selection as leak_check

from gearlab.learn import protocol as P
from gearlab.learn.calibration import RECIPE, THESIS, history_law
from gearlab.learn.networks import ShapeLikelihood
from gearlab.learn.protocol import StateStore, run_unit, split

pytestmark = pytest.mark.usefixtures("one_torch_thread", "trained_once")

# the adapter variants the protocol test's METHODS leave out (its leak check runs them below)
OTHER_VARIANTS = (
    method("coral"),
    method("dann", True),
    method("finetune", True, variant="all"),
    method("finetune", True, variant="last"),
)
UNSUPERVISED = [m for m in (*METHODS, *OTHER_VARIANTS) if not m.supervised]
CALIBRATIONS = pytest.mark.parametrize(
    "calibration, network",
    [(THESIS, "burst"), (RECIPE, "burst"), (RECIPE, "shapes")],
    ids=["thesis", "recipe", "recipe-shapes"],
)


@CALIBRATIONS
@pytest.mark.parametrize("m", OTHER_VARIANTS, ids=lambda m: m.key)
def test_every_adapter_variant_keeps_the_target_test_rows_out(m, calibration, network, monkeypatch):
    """tests/test_protocol.py's check (no target test row or label reaches training, stopping,
    calibration, threshold or the epoch kept) for the variants its METHODS leave out: coral
    unsupervised, dann supervised, finetune 'all' and 'last'."""
    leak_check(m, calibration, network, monkeypatch)


@CALIBRATIONS
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


@pytest.mark.parametrize("law", ["gaussian", "laplace"])
@pytest.mark.parametrize("adapter, supervised, params", [("mmd", False, {}), ("finetune", True, {"variant": "last"})])
def test_shapes_scores_in_the_noise_law_read_off_the_target_history(law, adapter, supervised, params):
    """`shapes` scores its templates in the noise law of the target history (calibration.history_law),
    as `likelihood_ratio` does: a target with Gaussian noise gets Gaussian templates, one with Laplace
    noise Laplace ones. A law fixed in the code (the true law of Experiments A and B) fails one."""
    rng = np.random.default_rng(4)
    fault = (np.arange(40) < 12).astype(np.int8)
    noise = rng.normal(size=(40, 256)) if law == "gaussian" else rng.laplace(size=(40, 256)) / np.sqrt(2.0)
    X = noise + np.sin(np.arange(256) / 5.0) + 0.5
    X[fault == 1, ::32] += 4.0
    target = replace(synthetic(12, 28), X=X.astype(np.float32), fault=fault, label=fault.copy())
    m = method(adapter, supervised, **params)
    p = tiny(methods=(m,), calibration=RECIPE, network="shapes")
    s = split(p, SOURCE, target, 0, 0)
    assert history_law(target.X[s.history_core]) == law  # the data say which law it is
    model = run_method(p, m, target, s)
    laws = {module.law for module in model.modules() if isinstance(module, ShapeLikelihood)}
    assert laws == {law}


def run_method(p, m, target, s):
    """The model *m* makes of the split *s* (as the protocol's unit makes it, before scoring)."""
    source = (SOURCE.X[s.source_train], SOURCE.fault[s.source_train].astype(np.int64))
    val = (SOURCE.X[s.source_val], SOURCE.fault[s.source_val].astype(np.int64))
    train = (target.X[s.target_train], target.fault[s.target_train].astype(np.int64))
    core = target.X[s.history_core]
    model, _, _ = P.train_method(p, m, source, val, train, 0, 0, StateStore(None), torch.device("cpu"), core=core)
    return model
