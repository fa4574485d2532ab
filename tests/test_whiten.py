"""The whitening of a template detector's rows (gearlab.learn.whiten, issue 39): in a history whose
residual is coloured (what a later mesh of no whole input order leaves in each revolution), the
unwhitened detectors rank single revolutions near chance and the whitened ones well; the filter
is kept in the model, so `gearlab score` applies the run's filter to a new record's units."""

import numpy as np
import torch

from gearlab.confined import Confined
from gearlab.kinds import detection_scoring
from gearlab.learn.detectors import likelihood_statistic, template_statistic
from gearlab.learn.whiten import Whitened, whitened, whitening_gain, whitening_of
from gearlab.parts import scoring
from gearlab.parts.roc import auc
from gearlab.runs import RunDir

L = 256
THETA = 2 * np.pi * np.arange(L) / L
HEALTHY = np.cos(20 * THETA) + 0.5 * np.cos(40 * THETA)


def _chip(at: int = 100) -> np.ndarray:
    """A short ringing pulse at sample *at*: broadband, as a tooth's impact."""
    d = np.angle(np.exp(1j * (THETA - 2 * np.pi * at / L))) * L / (2 * np.pi)
    return np.exp(-0.5 * (d / 1.5) ** 2) * np.cos(np.pi * d / 3)


def _revolutions(rng, n: int, chip: float = 0.0) -> np.ndarray:
    """Measured revolutions: the healthy one, a leftover of unit amplitude at orders 3-24 in a phase
    of its own per revolution (ten times the white noise's level), white noise, and a chip."""
    k = np.arange(3, 25)
    phase = rng.uniform(0, 2 * np.pi, (n, len(k)))
    leftover = np.cos(k[None, :, None] * THETA[None, None, :] + phase[..., None]).sum(axis=1)
    return HEALTHY + leftover + 0.1 * rng.standard_normal((n, L)) + chip * _chip()


def _source():
    """Noise-free simulated rows: healthy, and the chip at four sizes."""
    X = np.concatenate([np.tile(HEALTHY, (8, 1)), np.stack([HEALTHY + s * _chip() for s in (0.5, 1.0, 1.5, 2.0)])])
    return X, np.array([0] * 8 + [1] * 4)


def _scores(model, X) -> np.ndarray:
    with torch.no_grad():
        return model.score(torch.as_tensor(X, dtype=torch.float32)).numpy()


def test_whitening_ranks_single_revolutions_in_a_coloured_leftover():
    rng = np.random.default_rng(5)
    Xs, ys = _source()
    history = _revolutions(rng, 120)
    healthy, chipped = _revolutions(rng, 200), _revolutions(rng, 200, chip=0.4)
    for fit in (template_statistic, likelihood_statistic):
        plain = fit(Xs, ys, history, None)
        white = whitened(fit(Xs, ys, history, None), whitening_of(history), history, 0.01)
        before = auc(_scores(plain, healthy), _scores(plain, chipped))
        after = auc(_scores(white, healthy), _scores(white, chipped))
        assert before < 0.7, (fit.__name__, before)  # the leftover's projection on the shapes ranks them
        assert after > 0.95, (fit.__name__, after)
        # thresholded on the whitened history: about the asked share of fresh healthy revolutions called
        assert np.mean(_scores(white, healthy) > float(white.threshold)) < 0.05


def test_the_gain_is_one_at_a_median_order_bounded_and_zero_outside_the_band():
    rng = np.random.default_rng(1)
    spectrum = np.fft.rfft(rng.standard_normal((200, L)), axis=-1)
    spectrum[:, 10] *= 30.0  # a strong coloured order
    spectrum[:, 100:] = 0.0  # outside the rows' band
    gain = whitening_gain(np.fft.irfft(spectrum, n=L, axis=-1), floor=0.1)
    assert gain[10] < 0.1
    assert np.all(gain[100:] == 0)
    assert 0.8 < np.median(gain[1:100]) < 1.2
    assert gain.max() <= np.sqrt(10) + 1e-9


def test_gearlab_score_applies_the_runs_filter(tmp_path):
    rng = np.random.default_rng(7)
    Xs, ys = _source()
    history = _revolutions(rng, 120)
    model = whitened(template_statistic(Xs, ys, history, None), whitening_of(history), history, 0.01)
    assert isinstance(model, Whitened)
    run = RunDir(tmp_path)
    unit = "35 Hz/matched_filter"
    scoring.save_model(Confined(tmp_path, scoring.MODELS), unit, model)
    new = {"new.wav": {"revolution": _revolutions(rng, 50, chip=0.4)}}
    scored = detection_scoring._learned_scores(run, {"unit": unit}, new, None, {})["new.wav"]["revolution"]
    X = new["new.wav"]["revolution"]
    expected = _scores(model, X) - float(model.threshold)  # the logit a fault call reads
    assert np.allclose(scored, expected, atol=1e-5)
    # not the same detector on the unfiltered rows
    assert not np.allclose(scored, _scores(model.detector, X) - float(model.threshold), atol=1e-3)
