"""What can k labelled target faults add? The likelihood-ratio detector, fed more and more.

Not a timing. Issue 14 asks that supervised calibration rise with k; on Experiment B it stays
flat (docs/learning.md, decision 25). This asks how much the k labelled faults of a
repetition's target training set could add at all, with ``likelihood_ratio``'s statistic
(gearlab.learn.detectors.LikelihoodDetector: the source's shapes through the fitted path, the
history's noise law, the 1 % threshold refitted on the healthy history) as the yardstick,
every row on the same split:

* ``source shapes``              the shipped unsupervised detector (k labels unused)
* ``+ k noisy faults``           the labelled faults' residuals as shapes of their own (what
                                 ``likelihood_ratio`` does when supervised)
* ``path refitted on k``         the path (gearlab.learn.path) refitted on the healthy lines
                                 and on the k faults, each paired with the source shape of
                                 largest likelihood for it (3 rounds)
* ``size fitted on k``           every shape scaled by the factor (0.40 ... 1.60) under which
                                 the k faults are most likely
* ``+ k clean faults (oracle)``  the k labelled faults' own noise-free shapes (the target's
                                 noise-free twin), as if a label came with a perfect record of
                                 the fault: the most k examples can teach
* ``all target shapes (oracle)`` every noise-free target fault shape: the Bayes bound's
                                 statistic at the history threshold

Accuracy (%) and faults found at 1 % false alarms (the threshold read off the test's healthy
revolutions, so the mix of the test set does not enter), means over the repetitions.

    python benchmarks/labelled_faults.py [--scenario expB] [--reps 0 1 2 3 4] [--ks 0 1 4 16]
"""

from __future__ import annotations

import argparse
from pathlib import Path as FilePath

import numpy as np
import torch

from gearlab.data.cache import load_or_build
from gearlab.engine import load_scenario
from gearlab.learn.bounds import gain, noise_scale, shape_llr
from gearlab.learn.detectors import LikelihoodDetector
from gearlab.learn.history import history_threshold, noise_law
from gearlab.learn.path import Path, fit_path
from gearlab.learn.protocol import split

SCENARIOS = FilePath(__file__).parents[1] / "scenarios"
SIZES = np.round(np.arange(0.4, 1.61, 0.05), 2)
ROWS = (
    "source shapes",
    "+ k noisy faults",
    "path refitted on k",
    "size fitted on k",
    "+ k clean faults (oracle)",
    "all target shapes (oracle)",
)


def scored(reference, shapes, kind, history, X, y) -> tuple[float, float]:
    """(accuracy at the history threshold, faults found at 1 % false alarms on the test), in %."""
    detector = LikelihoodDetector(reference, shapes, kind, threshold=0.0)
    with torch.no_grad():
        threshold = history_threshold(detector.score(torch.as_tensor(history, dtype=torch.float32)).numpy(), 0.99)
        s = detector.score(torch.as_tensor(X, dtype=torch.float32)).numpy()
    healthy = np.sort(s[y == 0])
    return 100 * float(np.mean((s > threshold) == (y == 1))), 100 * float(
        np.mean(s[y == 1] > healthy[int(0.99 * len(healthy))])
    )


def likelihoods(R: np.ndarray, shapes: np.ndarray, kind: str) -> torch.Tensor:
    """``(k, J)`` log-likelihood ratios of the residuals *R* for every shape."""
    r = torch.as_tensor(R)
    return shape_llr(r, torch.as_tensor(shapes), noise_scale(r, kind), kind)


def refitted(path: Path, s: np.ndarray, h: np.ndarray, F: np.ndarray, R: np.ndarray, kind: str) -> Path:
    """The path's taps refitted by least squares on every order of the healthy references and of
    the k (fault, best source shape) pairs, the lags kept, a ridge of 1e-3 (gearlab.learn.path)."""
    if len(path.lags) == 1:
        return path
    n = len(s)
    E = np.exp(-2j * np.pi * np.outer(np.arange(n // 2 + 1), path.lags) / n)
    for _ in range(3):
        best = F[likelihoods(R, path(F), kind).argmax(dim=1).numpy()]
        A = np.vstack([E * np.fft.rfft(x)[:, None] for x in (s, *best)])
        b = np.concatenate([np.fft.rfft(x) for x in (h, *R)])
        A, b = np.vstack([A.real, A.imag]), np.concatenate([b.real, b.imag])
        G = A.T @ A
        path = Path(path.lags, np.linalg.solve(G + 1e-3 * np.trace(G) / len(path.lags) * np.eye(len(G)), A.T @ b))
    return path


def compare(name: str, reps: list[int], ks: list[int]) -> None:
    scenario = load_scenario(SCENARIOS / f"{name}.toml")
    protocol = scenario.spec["protocol"]
    source, _ = load_or_build(scenario.spec["source"])
    target, _ = load_or_build(scenario.spec["target"])
    clean, _ = load_or_build(scenario.spec["target"].with_(noise=None))
    C = clean.X.astype(np.float64)
    clean_healthy = np.median(C[clean.fault == 0], axis=0)
    print(f"{name}: {scenario.spec['source'].name} -> {scenario.spec['target'].name}, repetitions {reps}")
    print("| k | " + " | ".join(ROWS) + " |\n|---|" + "---|" * len(ROWS))
    for k in ks:
        table = []
        for rep in reps:
            sp = split(protocol, source, target, rep, k)
            Xs, ys = source.X[sp.source_train].astype(np.float64), source.fault[sp.source_train]
            Xt, yt = target.X[sp.target_train].astype(np.float64), target.fault[sp.target_train]
            X, y = target.X[sp.target_test], target.fault[sp.target_test]
            H = Xt[yt == 0]
            s, h, path = fit_path(Xs, ys, H, "fir")
            kind = noise_law(H - h)
            F = Xs[ys == 1] - s
            R = Xt[yt == 1] - h
            g = gain(h, clean_healthy)
            own = g * (C[sp.target_train][yt == 1] - clean_healthy)
            shapes = path(F)
            size = 1.0
            if k:
                size = SIZES[
                    int(np.argmax([float(likelihoods(R, c * shapes, kind).logsumexp(1).sum()) for c in SIZES]))
                ]
            rows = [
                shapes,
                np.concatenate([shapes, R]),
                refitted(path, s, h, F, R, kind)(F) if k else shapes,
                size * shapes,
                np.concatenate([shapes, own]),
                g * (C[clean.fault == 1] - clean_healthy),
            ]
            table.append([scored(h, r, kind, H, X, y) for r in rows])
        mean = np.mean(np.array(table), axis=0)
        print(f"| {k} | " + " | ".join(f"{a:.2f} / {d:.1f}" for a, d in mean) + " |", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", nargs="+", default=["expB"])
    parser.add_argument("--reps", nargs="+", type=int, default=[0, 1, 2, 3, 4])
    parser.add_argument("--ks", nargs="+", type=int, default=[0, 1, 4, 16])
    args = parser.parse_args()
    torch.set_num_threads(1)
    for name in args.scenario:
        compare(name, args.reps, args.ks)


if __name__ == "__main__":
    main()
