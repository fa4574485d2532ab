"""The transfer report's latent maps (Figure 5.9) of a calibrated method: the source features are
taken as training saw the source (with the target's noise), so both domains share one scale and
the map is a map (issue 41: the `shapes` network's source features were ~1e14, the target's ~1e2,
and every mmd/dann map read 'features collapse to a line: no map')."""

from dataclasses import replace

import numpy as np
import pytest
from tiny import bare_dataset, protocol

from gearlab.kinds.transfer_figures import latent_projection
from gearlab.learn.calibration import RECIPE
from gearlab.learn.protocol import StateStore, run_unit
from gearlab.parts import training

pytestmark = pytest.mark.usefixtures("one_torch_thread")

LENGTH = 256


def revolutions(faults: int, healthy: int, rng, noise: float, gain: float = 1.0):
    """A tone per revolution (identical rows without noise, as a simulator's source), a fault an
    impulse burst at a random place; Laplace noise of scale *noise* (0: none)."""
    n = faults + healthy
    fault = (np.arange(n) < faults).astype(np.int8)
    X = np.tile(gain * np.sin(2 * np.pi * 7 * np.arange(LENGTH) / LENGTH), (n, 1))
    for i in np.flatnonzero(fault):
        at = rng.integers(0, LENGTH - 8)
        X[i, at : at + 8] += gain * np.hanning(8) * 3.0
    if noise:
        X += rng.laplace(scale=noise, size=X.shape)
    return bare_dataset(X.astype(np.float32), fault)


def test_calibrated_latent_features_share_the_targets_scale():
    rng = np.random.default_rng(0)
    source = revolutions(20, 30, rng, noise=0.0)  # noise-free, as the simulator's source
    target = revolutions(12, 28, rng, noise=0.3, gain=1.3)
    mmd = training.method({"adapter": "mmd", "supervised": False, "params": {}}, "test")
    tiny = protocol(
        [mmd], ks=(0,), repetitions=1, baseline_epochs=2, max_epochs=2, network="shapes", calibration=replace(RECIPE)
    )
    latent = run_unit(tiny, source, target, 0, 0, mmd, StateStore(None))["_latent"]
    zs, zt = np.abs(latent["source"]).max(), np.abs(latent["target"]).max()
    assert np.isfinite(zs) and zs < 100 * zt, (zs, zt)  # 1.4e13 against 60 before the fix
    points, collapsed = latent_projection(np.concatenate([latent["source"], latent["target"]]))
    assert points is not None, collapsed


def test_only_the_kept_repetition_embeds_its_training_rows(monkeypatch):
    """The latent features (two passes through the network) are made for the repetition whose maps
    a run keeps, not for every unit (issue 42); the source validation accuracy is the kept epoch's,
    the figure a fresh pass gives."""
    from gearlab.learn import protocol as P
    from gearlab.learn import training as T

    rng = np.random.default_rng(1)
    source, target = revolutions(20, 30, rng, noise=0.0), revolutions(12, 28, rng, noise=0.3, gain=1.3)
    mmd = training.method({"adapter": "mmd", "supervised": False, "params": {}}, "test")
    tiny = protocol(
        [mmd], ks=(0,), repetitions=2, baseline_epochs=2, max_epochs=2, network="shapes", calibration=replace(RECIPE)
    )
    embedded, embed = [], T.embed
    monkeypatch.setattr(T, "embed", lambda *a, **kw: embedded.append(1) or embed(*a, **kw))
    records = {rep: run_unit(tiny, source, target, rep, 0, mmd, StateStore(None)) for rep in (0, 1)}
    assert P.LATENT_REPETITION == 0 and "_latent" in records[0] and "_latent" not in records[1]
    assert len(embedded) == 2  # source and target rows of repetition 0 only
    for record in records.values():
        kept = record["history"]["val_acc"][record["history"]["best_epoch"]]
        assert record["source_val_accuracy"] == 100.0 * kept
