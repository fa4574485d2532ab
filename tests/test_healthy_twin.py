"""The detectors' templates on a train whose later mesh is no whole input order (issue 39): each
source row holds that mesh at its own revolution of the train's cycle, and what the input's fit of
the mesh leaves of it (its shaft's sidebands) outweighs a chip; a template made as the fault row
minus the healthy median is then mostly that leftover, and single revolutions are ranked by it
(likelihood_ratio's revolution AUC 0.38 on the 18/67 + 29/71 development records). A template is
now the fault row less its healthy twin: the same sample with the fault taken out (the same cycle
revolution, tooth turn, effects and noise draws; DatasetSpec.healthy_twin)."""

from __future__ import annotations

import numpy as np
from test_gearbox_source import RIG2S, small, source

from gearlab.data.builder import build_dataset
from gearlab.kinds.detection_records import without_asynchronous
from gearlab.kinds.detection_units import healthy_twin, signature_rows
from gearlab.learn.detector_contract import Detector
from gearlab.learn.detectors import likelihood_statistic, template_statistic
from gearlab.parts.roc import auc

FAN = 17 * 26 / 59  # 17/59 then 26/83: the later mesh at 442/59 input orders
SHAFT = 17 / 59  # its shaft's turn, whose sidebands the fit of the mesh's harmonics leaves
P, Z = 1024, 17
THETA = np.arange(P) / P


def test_the_healthy_twin_is_each_sample_without_its_fault(tmp_path):
    (tmp_path / "rig2s.toml").write_text(RIG2S)  # 21/53 then 29/61: a cycle of 53 turns
    spec = small(source(tmp_path, gearbox="rig2s.toml"), (("chip", (20,)),), (5,)).with_(duplicates=3)
    assert "healthy_twin" not in spec.canonical()  # every other dataset keeps its cache key
    twin_spec = healthy_twin(spec)
    assert twin_spec.key() != spec.key()
    data, twin = build_dataset(spec), build_dataset(twin_spec)
    X, T = data.X.astype(float), twin.X.astype(float)
    healthy, fault = data.fault == 0, data.fault == 1
    assert np.array_equal(twin.label, data.label) and np.array_equal(X[healthy], T[healthy])
    # each fault row's twin is healthy at that row's own point of the cycle: the rows differ (their
    # own revolutions of the later mesh), and a fault row is far nearer its twin than any other
    leftover = X[fault] - np.median(X[healthy], axis=0)
    signature = X[fault] - T[fault]
    assert np.all(np.linalg.norm(signature, axis=1) < 0.5 * np.linalg.norm(leftover, axis=1))
    assert np.linalg.norm(T[fault][0] - T[fault][1]) > 5 * np.linalg.norm(signature[0])  # 12 x
    # the chip's signature is the same whichever revolution of the cycle the row starts at
    cos = signature @ signature.T / np.outer(*2 * [np.linalg.norm(signature, axis=1)])
    assert cos.min() > 0.99  # 1.000 (the simulator is linear in the fault)


def _later(s: int) -> np.ndarray:
    """The later mesh at the train's cycle revolution *s*, modulated by its shaft's turn."""
    t = s + THETA
    return sum(
        a * np.cos(2 * np.pi * k * FAN * t + p) * (1 + 0.8 * np.cos(2 * np.pi * SHAFT * t + q))
        for k, a, p, q in ((1, 1.0, 0.3, 1.0), (2, 0.6, 1.1, 2.0), (5, 0.5, 2.0, 0.5))
    )


def _chip(tooth: int) -> np.ndarray:
    x = np.zeros(P)
    c = int((tooth - 1) * P / Z) + 20
    x[c - 6 : c + 7] = np.hanning(13) * np.cos(np.pi * np.arange(13) / 2.2)
    return x


def test_single_revolutions_are_ranked_by_the_fault_not_by_the_later_mesh():
    """Hand-made revolutions of the mechanism: source rows at random revolutions of the cycle
    (chips on random teeth), a history and test records running on through the cycle with noise,
    the chip on tooth 3. Templates from the fault rows minus the healthy median rank single
    revolutions at chance (AUC 0.5); from the fault rows less their twins, 0.98."""
    rng = np.random.default_rng(0)
    starts, teeth = rng.integers(0, 59, 96), rng.integers(1, Z + 1, 96)
    ys = np.repeat([0, 1], 48)
    twins = np.stack([_later(s) for s in starts])
    Xs = twins + np.stack([_chip(n) * y for n, y in zip(teeth, ys)])

    def seen(X):
        return without_asynchronous(X, (FAN,))

    def record(first: int, n: int, chip: bool = False) -> np.ndarray:
        return np.stack([_later(first + i) + chip * _chip(3) for i in range(n)]) + 0.3 * rng.standard_normal((n, P))

    history, ok, chipped = seen(record(7, 240)), seen(record(300, 200)), seen(record(600, 200, chip=True))
    for rows, low, high in ((seen(Xs), 0.0, 0.7), (signature_rows(seen(Xs), ys, seen(twins)), 0.9, 1.0)):
        for statistic in (likelihood_statistic, template_statistic):
            det = statistic(rows, ys, history[:120], None)
            healthy, fault = Detector.score(det, ok), Detector.score(det, chipped)
            assert low <= auc(healthy, fault) <= high, (statistic.__name__, low)
            if low:  # the history's 99th percentile lets through about 1 % of the healthy test record
                threshold = np.quantile(Detector.score(det, history[120:]), 0.99)
                assert np.mean(healthy > threshold) <= 0.05 and np.mean(fault > threshold) >= 0.6
