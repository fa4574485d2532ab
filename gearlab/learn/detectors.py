"""A fault detector built from the simulator's fault shapes (beyond the thesis).

The chapter-5 target is a single noisy revolution ``x``; a fault adds a short response
``a·t`` of known shape ``t`` (the simulator's) and unknown size ``a`` to the domain's
healthy revolution ``h``. For white noise of unknown level, the generalised likelihood-ratio
test of "fault of shape ``t``" against "healthy" compares the cosine between the residual
``r = x - h`` and ``t`` with a threshold (Kay, *Fundamentals of Statistical Signal
Processing*, vol. II, chapters 7 and 9); with many possible shapes (fault type, intensity,
tooth) the statistic is the largest cosine over them:

    score(x) = max_j |<r, t_j>| / ||r||,      ||t_j|| = 1

(``scale = "unit"``). By default (``scale = "history"``) the noise level is not the scored
revolution's own ||r|| but the healthy history's median ||r||, the known-level matched filter
(Kay, vol. II, ch. 7): a revolution's own norm also holds whatever part of its fault response
the simulated shapes miss, so a fault that grows the residual away from the templates lowers
its cosine below the healthy revolutions' (a one-stage 31/97 outside recording, development
data: the chip rings the target's 2100 Hz resonance, 77 % of its record residual at orders
150-200, where the templates hold 7 %; cosine to the best template 0.056; its residual norm
3.4 times the history's, its correlation 1.9 times: record30 AUC 0.29 with the unit's own
norm, 1.00 with the history's).

The residual leaves out the reference's healthy lines (`healthy_lines`: orders where the healthy
reference stands 20 dB over the history residuals' floor), in the scored revolutions and the
templates alike. A strong mesh line's phase and size move a little with a take's speed, load or
temperature, where its frequency lies against the resonances; a TSA averages the noise down but
not that change, and with no per-revolution norm to absorb it, a known-level correlation calls it
a fault. A history of two takes cannot show it to the records rule either: each take is half
their difference from their own median reference, so both score alike (development data: a
two-stage 24/60 + 35/83 reducer, MAT takes without a tacho, history at 30.00 and 30.09 Hz;
healthy takes at 29.85-30.15 Hz had 15 of 36 record10 units called with the lines, 3 without;
record30 7 of 12 and 0). A chip's response spreads over many orders and is found as before.

* ``h`` is the target's healthy reference: the sample median of its healthy history
  (thesis 5.4.2: the target's training data is that history);
* the templates ``t_j`` are the source's fault revolutions minus the source's healthy
  reference, normalised; the sign is left free, since a change of path (pinion to casing,
  six to eight DOF) may turn a response over;
* the threshold lets a share ``false_alarm`` of healthy revolutions through: the
  ``1 - false_alarm`` quantile of a Gumbel law (the law of a maximum of many noisy
  correlations) fitted to the healthy history's own scores by their quartiles, then refitted
  without the scores above it until it stops moving (`history_threshold`). Quartiles, not the
  upper tail, and the refit, because an unlabelled history may hold a few fault revolutions
  (k of the 120), whose scores an empirical upper quantile would follow and which would widen
  the quartiles.

In impulsive noise (Laplace, Student-t) the correlation is no longer the likelihood-ratio
statistic: the locally optimal detector passes the residual through the noise's score
function first, for Laplace noise a hard limiter (Kay, vol. II, ch. 10). With ``clip`` set,
each residual sample is limited softly, ``c·σ·tanh(r / (c·σ))`` with σ the revolution's robust
noise scale (1.4826·MAD), before the cosine; gearlab.learn.bounds gives the exact likelihood
ratio this approximates when the shapes are known.

The detector is an :class:`torch.nn.Module` whose logits are ``[0, score - threshold]``,
so the protocol scores it like any trained network. It needs revolutions on the same
angular grid in both domains (what the datasets are: one revolution, starting at the
same pinion angle); see docs/learning.md.
"""

from __future__ import annotations

import math

import numpy as np
import torch
from torch import nn

from gearlab.errors import GearlabInputError

from .bounds import noise_scale, shape_llr
from .detector_contract import Detector
from .history import noise_law
from .path import fit_path

SCALES = ("unit", "history")  # the noise scale of a scored revolution: its own, or the healthy history's
LIMIT = 0.7  # soft limit of the residual, in robust noise scales (issue measurement: best near 0.7)
LINES = 100.0  # a healthy line: the reference's power over the history residuals' floor there (20 dB)
FLOOR_ORDERS = 8  # the residuals' floor at an order: their median power over this many orders either side
MIXTURES = ("shapes", "sizes")  # likelihood_ratio's mixture: the path's shapes, or each at `SIZES` and both signs
SIZES = (0.25, 0.5, 1.0, 2.0, 4.0)  # times the size the path gives: a target's fault may be 4 times off either way


class TemplateDetector(nn.Module):
    def __init__(
        self,
        reference: np.ndarray,
        templates: np.ndarray,
        threshold: float,
        clip: float = 0.0,
        norm: float = 0.0,
        kept: np.ndarray | None = None,
    ):
        super().__init__()
        self.register_buffer("reference", torch.as_tensor(reference, dtype=torch.float32))
        self.register_buffer("templates", torch.as_tensor(templates, dtype=torch.float32))
        self.register_buffer("threshold", torch.tensor(float(threshold)))
        self.register_buffer("clip", torch.tensor(float(clip)))
        self.register_buffer("norm", torch.tensor(float(norm)))  # 0: each revolution's own ||r||
        # 1 at the orders the residual keeps, 0 at the reference's healthy lines (`healthy_lines`);
        # empty: every order
        kept = np.zeros(0) if kept is None else np.asarray(kept)
        self.register_buffer("kept", torch.as_tensor(kept, dtype=torch.float32))
        self.latent_dim = len(templates)

    def residual(self, x: torch.Tensor) -> torch.Tensor:
        """Each revolution's residual from the reference, without the reference's healthy lines
        (`healthy_lines`), limited when ``clip`` is set."""
        r = x.reshape(len(x), -1) - self.reference
        kept = self._buffers.get("kept")  # None in a model a run saved before the lines were left out
        if kept is not None and kept.numel():
            r = torch.fft.irfft(torch.fft.rfft(r, dim=1) * kept, n=r.shape[1], dim=1)
        if self.clip > 0:
            scale = 1.4826 * (r - r.median(dim=1, keepdim=True).values).abs().median(dim=1, keepdim=True).values
            c = self.clip * scale.clamp_min(1e-12)
            r = c * torch.tanh(r / c)
        return r

    def embed(self, x: torch.Tensor) -> torch.Tensor:
        """The correlations of each revolution's (limited) residual with every template over its noise
        level (its own norm: cosines; or ``norm``, the history's), ``(B, n_templates)``."""
        r = self.residual(x)
        norm = self._buffers.get("norm")  # None in a model a run saved before the history's norm: cosines
        level = r.norm(dim=1, keepdim=True) if norm is None or norm <= 0 else norm
        return (r @ self.templates.T) / level.clamp_min(1e-12)

    def score(self, x: torch.Tensor) -> torch.Tensor:
        return self.embed(x).abs().amax(dim=1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        s = self.score(x) - self.threshold
        return torch.stack([torch.zeros_like(s), s], dim=1)


def healthy_lines(reference: np.ndarray, residuals: np.ndarray) -> np.ndarray:
    """The orders (rfft bins of a revolution) where the healthy *reference* holds a line at least
    `LINES` times the power of the history's *residuals* about it: the orders a healthy take's
    small change of speed, load or temperature moves most (a line's phase and size follow where
    its frequency lies against the resonances), and which its TSAs do not average out. The
    residuals' power is their floor, the median over the orders beside (`FLOOR_ORDERS` either
    side), not theirs at the line: that holds the history takes' own changes of the line, so the
    lines that move most between takes would be the ones kept."""
    from scipy.ndimage import median_filter  # here, not at the top: start-up time

    line = np.abs(np.fft.rfft(reference)) ** 2
    power = np.mean(np.abs(np.fft.rfft(residuals, axis=1)) ** 2, axis=0)
    if power.max() <= 1e-10 * line.max():  # a noise-free history (a simulation's): no floor, no line
        return np.zeros(line.shape, dtype=bool)
    floor = median_filter(power, size=2 * FLOOR_ORDERS + 1, mode="nearest")
    return line > LINES * np.maximum(floor, 1e-300)


def _unit_rows(R: np.ndarray) -> np.ndarray:
    return R / np.maximum(np.linalg.norm(R, axis=1, keepdims=True), 1e-12)


def _checked(name: str, Xs, ys, Xt, yt) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(Xs, ys, Xt, healthy mask of Xt) as float64 arrays, or a one-line error naming the detector."""
    Xs, Xt = np.asarray(Xs, dtype=np.float64), np.asarray(Xt, dtype=np.float64)
    ys = np.asarray(ys)
    if not (ys == 0).any() or not (ys == 1).any():
        raise GearlabInputError(f"{name}: the source training set needs healthy and fault revolutions")
    healthy_t = np.ones(len(Xt), bool) if yt is None else np.asarray(yt) == 0
    if healthy_t.sum() < 2:
        raise GearlabInputError(f"{name}: the target training set needs at least 2 healthy revolutions")
    if Xs.shape[1] != Xt.shape[1]:
        raise GearlabInputError(
            f"{name}: source revolutions have {Xs.shape[1]} samples, target revolutions {Xt.shape[1]}"
        )
    return Xs, ys, Xt, healthy_t


def _shapes(name: str, Xs, ys, Xt, yt, path: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The checked target revolutions, which of them are healthy, the target's healthy reference
    and the fault shapes: the source's fault revolutions minus its healthy reference, through the
    path fitted between the two references (each domain is standardised by its own healthy
    statistics, eq. 4.6; the path brings the shapes to the target's size and form), and with
    target labels the labelled target faults minus the target's reference."""
    Xs, ys, Xt, healthy_t = _checked(name, Xs, ys, Xt, yt)
    source_healthy, reference, through = fit_path(Xs, ys, Xt[healthy_t], path)
    shapes = [through(Xs[ys == 1] - source_healthy)]
    if yt is not None:
        shapes.append(Xt[~healthy_t] - reference)
    return Xt, healthy_t, reference, np.concatenate(shapes)


def template_statistic(
    Xs: np.ndarray,
    ys: np.ndarray,
    Xt: np.ndarray,
    yt: np.ndarray | None,
    limiter: str = "off",
    path: str = "fir",
    scale: str = "history",
) -> TemplateDetector:
    """The detector of the source's fault shapes referenced on the target's healthy history,
    its threshold not set yet (gearlab.learn.detector_contract.Detector.fit sets it). *yt* None:
    every target training revolution is taken as healthy (the unsupervised case); with labels,
    the healthy ones are the history and the target's own fault revolutions are templates too.
    *limiter* ``on``/``off``, or ``auto``: on when the history's residuals follow an impulsive
    law (gearlab.learn.calibration.noise_law). *path*: the shapes reach the target through the
    path fitted between the two healthy references (gearlab.learn.path: ``fir`` the filter,
    ``gain`` one number, to which a cosine is blind). *scale* (`SCALES`): the noise level a
    correlation is divided by, the scored revolution's own residual norm (``unit``: the cosine)
    or the healthy history's median one (``history``, the module docstring's reason)."""
    if scale not in SCALES:
        raise ValueError(f"scale must be one of {SCALES}, got {scale!r}")
    Xt, healthy_t, reference, shapes = _shapes("matched_filter", Xs, ys, Xt, yt, path)
    if limiter == "auto":
        limiter = "off" if noise_law(Xt[healthy_t] - reference) == "gaussian" else "on"
    clip = LIMIT if limiter == "on" else 0.0
    kept = ~healthy_lines(reference, Xt[healthy_t] - reference)
    shapes = np.fft.irfft(np.fft.rfft(shapes, axis=1) * kept, n=shapes.shape[1], axis=1)
    detector = TemplateDetector(reference, _unit_rows(shapes), threshold=0.0, clip=clip, kept=kept)
    if scale == "history":
        with torch.no_grad():
            residuals = detector.residual(torch.as_tensor(Xt[healthy_t], dtype=torch.float32))
            detector.norm.fill_(float(residuals.norm(dim=1).median()))
    return detector


def template_detector(
    Xs, ys, Xt, yt, false_alarm: float, limiter: str = "off", path: str = "fir", scale: str = "history"
) -> TemplateDetector:
    """`template_statistic` thresholded on the healthy history at *false_alarm*."""
    return Detector.thresholded(template_statistic(Xs, ys, Xt, yt, limiter, path, scale), (Xt, yt), false_alarm)


class LikelihoodDetector(nn.Module):
    """The mixture likelihood ratio of the simulated fault shapes (gearlab.learn.bounds):

        log Λ(x) = log (1/J) Σ_j Π_n p(r_n - t_j,n) / p(r_n),     r = x - h

    in the noise law read off the healthy history, at each revolution's own noise scale, or
    (*scale* > 0) at that one scale for every revolution. With the target's true shapes this is
    the Bayes detector; with the simulator's, it is as good as the simulator (docs/learning.md,
    decision 18)."""

    def __init__(self, reference: np.ndarray, shapes: np.ndarray, kind: str, threshold: float, scale: float = 0.0):
        super().__init__()
        self.register_buffer("reference", torch.as_tensor(reference, dtype=torch.float32))
        self.register_buffer("shapes", torch.as_tensor(shapes, dtype=torch.float32))
        self.register_buffer("threshold", torch.tensor(float(threshold)))
        self.register_buffer("scale", torch.tensor(float(scale)))
        self.kind = kind
        self.latent_dim = len(shapes)

    def embed(self, x: torch.Tensor) -> torch.Tensor:
        """``(B, J)``: each revolution's log-likelihood ratio for every shape."""
        r = x.reshape(len(x), -1).to(self.reference.dtype) - self.reference
        scale = noise_scale(r, self.kind) if self.scale <= 0 else self.scale.expand(len(r))
        return shape_llr(r, self.shapes, scale, self.kind)

    def score(self, x: torch.Tensor) -> torch.Tensor:
        return torch.logsumexp(self.embed(x), dim=1) - math.log(self.latent_dim)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        s = self.score(x) - self.threshold
        return torch.stack([torch.zeros_like(s), s], dim=1)


def likelihood_statistic(
    Xs, ys, Xt, yt: np.ndarray | None, path: str = "fir", scale: str = "unit", mixture: str = "shapes"
) -> LikelihoodDetector:
    """The likelihood-ratio detector of the source's fault shapes on the target's healthy
    history, its threshold not set yet (as `template_statistic`'s): reference h = the history's
    median; shapes = the source's fault revolutions minus
    its healthy median, passed through the path fitted between the two domains' healthy
    references (gearlab.learn.path; *path* ``fir`` the filter, ``gain`` the ratio of their
    RMS: a likelihood ratio needs the shapes' size and form, a cosine only their form); noise
    law from the history's residuals (gearlab.learn.history.noise_law). With target labels
    (*yt*) the labelled faults add their own shapes. *scale* ``unit``: each scored revolution's noise scale from its own
    residual; ``history``: the median of the healthy history revolutions' scales, the same
    under both hypotheses. Where a fault raises the whole residual rather than adding a sparse
    shape (the PHM 2009 chip: its units' own scale alone ranks them first), the unit's own
    scale reads the fault's energy as noise and ranks the faults low (docs/real_data.md).
    *mixture* ``sizes``: the fault's size and sign are unknown too, each shape enters the mixture
    at every size of `SIZES` and both signs, equally weighted (a model mismatch the path does not
    see, such as the bearings' stiffness, scales a fault's response apart from the healthy
    mesh's or turns it over: docs/results.md §5)."""
    if scale not in SCALES:
        raise ValueError(f"scale must be one of {SCALES}, got {scale!r}")
    if mixture not in MIXTURES:
        raise ValueError(f"mixture must be one of {MIXTURES}, got {mixture!r}")
    Xt, healthy_t, reference, shapes = _shapes("likelihood_ratio", Xs, ys, Xt, yt, path)
    if mixture == "sizes":
        shapes = np.concatenate([sign * size * shapes for sign in (1.0, -1.0) for size in SIZES])
    kind = noise_law(Xt[healthy_t] - reference)
    fixed = 0.0
    if scale == "history":
        residuals = torch.as_tensor(Xt[healthy_t] - reference, dtype=torch.float32)
        fixed = float(noise_scale(residuals, kind).median())
    return LikelihoodDetector(reference, shapes, kind, threshold=0.0, scale=fixed)


def likelihood_detector(
    Xs, ys, Xt, yt, false_alarm: float, path: str = "fir", scale: str = "unit", mixture: str = "shapes"
) -> LikelihoodDetector:
    """`likelihood_statistic` thresholded on the healthy history at *false_alarm*."""
    statistic = likelihood_statistic(Xs, ys, Xt, yt, path, scale, mixture)
    return Detector.thresholded(statistic, (Xt, yt), false_alarm)


def referenced_on(model: nn.Module, rows: np.ndarray) -> nn.Module | None:
    """A copy of the fitted detector *model* referenced on *rows* alone: its healthy reference their
    elementwise median and its noise level theirs (``norm`` of matched_filter, ``scale`` of
    likelihood_ratio, where the model reads the history's: the median over *rows*), through the model's
    whitening where it has one (gearlab.learn.whiten.Whitened); all else kept: its shapes, path,
    left-out lines and threshold. What scores a history record without itself
    (gearlab.kinds.detection_units.train_unit): the history enters a detector through these two, and a
    record's own revolutions pull both towards it. Development boxes (3 takes, record30, 1 % asked),
    matched_filter detected / false alarm %: the whole history's 45/6.9; the reference alone made
    without the take 35/2.8; reference and noise level 22/1.1; the whole detector refitted (path,
    shapes, lines too, at 4 fits' cost) 25/0.8. None for a model without a reference (a plugin's own)."""
    import copy

    if "reference" not in dict(getattr(model, "detector", model).named_buffers()):
        return None
    made = copy.deepcopy(model)
    inner, whitening = getattr(made, "detector", made), getattr(made, "whitening", None)
    rows = torch.as_tensor(np.asarray(rows), dtype=torch.float32)
    median = torch.as_tensor(np.median(np.asarray(rows, dtype=np.float64), axis=0), dtype=torch.float32)
    with torch.no_grad():
        if whitening is not None:
            rows, median = whitening(rows), whitening(median)
        inner.reference.copy_(median)
        buffers = dict(inner.named_buffers())
        if "norm" in buffers and inner.norm > 0:  # matched_filter's history level (as template_statistic's)
            inner.norm.copy_(inner.residual(rows).norm(dim=1).median())
        if "scale" in buffers and inner.scale > 0:  # likelihood_ratio's (as likelihood_statistic's)
            inner.scale.copy_(noise_scale(rows - inner.reference, inner.kind).median())
    return made


class MeanOf(nn.Module):
    """The mean of the logits of *parts*, detectors alike but for what each was referenced on
    (`referenced_on`): how a new take is scored where each history record was scored by the part
    referenced without it (gearlab.kinds.detection_units.train_unit), so that its scores are what the
    history's were. A part referenced on fewer records holds a noisier reference; the score of a detector
    that divides by the scored unit's own residual scale (likelihood_ratio's ``unit``) depends on it."""

    def __init__(self, parts: list[nn.Module]):
        super().__init__()
        self.parts = nn.ModuleList(parts)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return torch.stack([m(x) for m in self.parts]).mean(dim=0)
