"""How well can a chapter-5 target be told apart at all? Detectors side by side, one split.

Not a timing: the accuracy (%) on the target test set of repetition 0, k = 0 of a transfer
scenario, for detectors that know more and more of the answer:

* ``network, told the labels``   the scenario's network trained on labelled noisy *target*
                                 test revolutions (60 % to fit, 10 % to stop on, scored on
                                 the remaining 30 %)
* ``energy, told threshold``     largest 128-sample energy of the residual from the target's
                                 healthy reference, the best threshold read off the test labels
* ``target shapes, told``        the matched filter with the target's own noise-free fault
                                 shapes and the best threshold (an upper bound of the method)
* ``matched_filter``             the shipped adapter: the source's shapes, threshold from the
                                 unlabelled healthy history (what a user gets)
* ``Bayes``                      the likelihood ratio of the target's own shapes in its own
                                 noise law (gearlab.learn.bounds), the best threshold: no
                                 detector of these data can do better

    python benchmarks/detection_bounds.py [--scenario expB expA]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import torch
from scipy.ndimage import uniform_filter1d

from gearlab.data.cache import load_or_build
from gearlab.engine import load_scenario
from gearlab.learn.bounds import bayes_scores, best_accuracy, detection_at
from gearlab.learn.detectors import template_detector
from gearlab.learn.networks import build_network
from gearlab.learn.protocol import split
from gearlab.learn.training import fit_supervised, predict

SCENARIOS = Path(__file__).parents[1] / "scenarios"


def bounds(name: str) -> dict[str, float]:
    scenario = load_scenario(SCENARIOS / f"{name}.toml")
    protocol = scenario.spec.protocol
    source, _ = load_or_build(scenario.spec.source)
    target, _ = load_or_build(scenario.spec.target)
    clean, _ = load_or_build(scenario.spec.target.with_(noise=None))
    s = split(protocol, source, target, rep=0, k=0)
    test, y = s.target_test, target.fault[s.target_test].astype(np.int64)
    history = target.X[s.target_train].astype(np.float64)
    residual = target.X[test] - np.median(history, axis=0)
    out = {}

    rng = np.random.default_rng(0)
    order = rng.permutation(test)
    n_fit, n_stop = int(0.6 * len(order)), int(0.1 * len(order))
    fit, stop, scored = order[:n_fit], order[n_fit : n_fit + n_stop], order[n_fit + n_stop :]
    torch.manual_seed(0)
    net = build_network(protocol.network, n_classes=2, dropout=protocol.dropout)
    fit_supervised(
        net,
        target.X[fit],
        target.fault[fit].astype(np.int64),
        rng=rng,
        device=torch.device("cpu"),
        epochs=100,
        batch=protocol.batch,
        val=(target.X[stop], target.fault[stop].astype(np.int64)),
        patience=20,
    )
    out["network, told the labels"] = (
        100 * (predict(net, target.X[scored], torch.device("cpu")) == target.fault[scored]).mean()
    )

    energy = uniform_filter1d(residual**2, 128, axis=1, mode="wrap").max(axis=1)
    out["energy, told threshold"] = best_accuracy(energy, y)

    X_test = torch.as_tensor(target.X[test])
    told = template_detector(clean.X, clean.fault, history, None, false_alarm=0.01)
    with torch.no_grad():
        out["target shapes, told threshold"] = best_accuracy(told.score(X_test).numpy(), y)

    detector = template_detector(
        source.X[s.source_train], source.fault[s.source_train], history, None, false_alarm=0.01
    )
    with torch.no_grad():
        called = detector(X_test).argmax(1).numpy()
    out["matched_filter (source shapes, history threshold)"] = 100 * (called == y).mean()
    kind = scenario.spec.target.noise.kind
    bayes = bayes_scores(target.X[test], history, clean, kind)
    out[f"Bayes ({kind} likelihood ratio, target shapes), told threshold"] = best_accuracy(bayes, y)
    out["Bayes: faults found at 1 % false alarms"] = detection_at(bayes, y, 0.01)
    out["healthy share of the test set"] = 100 * (y == 0).mean()
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", nargs="*", default=["expB", "expA"])
    args = parser.parse_args()
    torch.set_num_threads(2)
    results = {name: bounds(name) for name in args.scenario}
    rows = list(next(iter(results.values())))
    print("| detector | " + " | ".join(results) + " |")
    print("|---|" + "---|" * len(results))
    for row in rows:
        print(f"| {row} | " + " | ".join(f"{results[n][row]:.1f}" for n in results) + " |")


if __name__ == "__main__":
    main()
