"""Whitening of the revolutions a template detector sees (issue 39).

The template detectors (gearlab.learn.detectors: matched_filter, likelihood_ratio) are the
likelihood-ratio tests of a known shape ``t`` in *white* noise: a revolution's residual
``r = x - h`` is correlated with ``t`` sample by sample, every order weighted alike. A measured
history's residual is not white. On a train whose later mesh is no whole input order, what the
fit of that mesh leaves in each revolution (its shaft's sidebands, the cycle's other
revolutions) is a coloured leftover far above the sensor noise in a few orders, and a
single healthy revolution scores by how much of that leftover it holds: on the outside gearbox
E (18/67 + 29/71) likelihood_ratio ranked single revolutions at AUC 0.73, matched_filter 0.61.

For Gaussian noise of covariance ``C`` the test is the same correlation after both the residual
and the shape are passed through ``C^(-1/2)`` (Kay, *Fundamentals of Statistical Signal
Processing*, vol. II, ch. 4, the generalised matched filter). Revolutions on one angular grid
whose residual is stationary in angle have a circulant ``C``, diagonal in the DFT: ``C^(-1/2)``
is the circular filter of gain ``1 / sqrt(P(k))`` per order ``k``, with ``P`` the residual's
power spectrum. ``P`` is read off the detector's own healthy history rows (the target's
training data, never a test unit), each less their sample median:

    P(k) = mean_i |DFT(x_i - median_j x_j)(k)|^2
    g(k) = sqrt(m / max(P(k), floor * m)),   m = median of P over the orders the rows carry

``floor`` bounds the gain at ``1 / sqrt(floor)`` times that of a median order, so an order the
history barely moves in (a short history's estimate of it is poor) is not raised without limit.
Orders no row carries (the rows' own power below 1e-12 of its peak: what detection_records'
inputs take out) get gain 0: there the residual holds only the elementwise median's content, the
same in every revolution. The filter is linear: applied to the residual and to the shapes (a
shape is a difference of rows) it whitens both (`whitened`); it is kept with the detector
(`Whitened`), so every unit scored, `gearlab score`'s too, passes the run's filter.

Single-revolution ROC AUC on development records, unwhitened -> whitened (matched_filter,
likelihood_ratio): E 0.69 -> 0.95, 0.73 -> 0.95; fan2s (17/59 + 26/83) 0.50 -> 0.80, 0.77 -> 0.83;
outside H (21/55 + 27/64) 0.71 -> 1.00, 0.43 -> 0.98; outside I (three stages) 0.67 -> 0.95,
0.17 -> 0.67. The cost: a detector this sensitive also flags damage on other gears (the which-gear
verdict names it), and on fan2s 17-25 % of a healthy test record's single revolutions pass the
history's threshold (its TSAs: 0-9 %).
"""

from __future__ import annotations

import numpy as np
import torch
from torch import nn

FLOOR = 0.1  # an order's power is taken as at least this share of the median order's
DEAD = 1e-12  # below this share of the peak an order is outside the rows' band: gain 0


def whitening_gain(rows: np.ndarray, floor: float = FLOOR) -> np.ndarray:
    """The gain per DFT bin (rfft order 0 … L/2) that whitens the residuals of *rows* ((n, L)
    healthy revolutions) about their median; 1 at a median order (module docstring)."""
    rows = np.asarray(rows, dtype=np.float64)
    power = np.mean(np.abs(np.fft.rfft(rows - np.median(rows, axis=0), axis=-1)) ** 2, axis=0)
    # the band from the rows themselves: their elementwise median is no band-limited row
    carried = np.mean(np.abs(np.fft.rfft(rows, axis=-1)) ** 2, axis=0)
    live = (carried > DEAD * carried.max()) & (power > 0)
    if not live.any():  # identical rows: nothing to whiten by
        return np.ones_like(power)
    level = np.median(power[live])
    return np.where(live, np.sqrt(level / np.maximum(power, floor * level)), 0.0)


def whitening_of(rows: np.ndarray, floor: float = FLOOR) -> Whitening:
    """The `Whitening` of *rows*' residuals ((n, L) healthy revolutions)."""
    rows = np.asarray(rows)
    return Whitening(whitening_gain(rows, floor), rows.shape[-1])


class Whitening(nn.Module):
    """The circular filter of *gain* (`whitening_gain`) applied to the last axis of any array of
    revolutions; the same object filters the training rows and, kept in `Whitened`, every row
    scored later."""

    def __init__(self, gain: np.ndarray, length: int):
        super().__init__()
        if len(gain) != length // 2 + 1:
            raise ValueError(f"whitening: {len(gain)} gains do not fit revolutions of {length} samples")
        self.register_buffer("gain", torch.as_tensor(np.asarray(gain), dtype=torch.float32))
        self.register_buffer("length", torch.tensor(int(length)))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        n = int(self.length)
        if x.shape[-1] != n:
            raise ValueError(f"whitening: revolutions of {x.shape[-1]} samples, the filter is for {n}")
        return torch.fft.irfft(torch.fft.rfft(x.to(torch.float32), dim=-1) * self.gain, n=n, dim=-1)

    def rows(self, X: np.ndarray) -> np.ndarray:
        """*X* (…, L) filtered, as float32 (numpy in, numpy out)."""
        with torch.no_grad():
            return self.forward(torch.as_tensor(np.asarray(X, dtype=np.float32))).numpy()


class Whitened(nn.Module):
    """A fitted template detector that scores its input through *whitening*: its reference and
    shapes are filtered once (`whitened`), every scored row on the way in."""

    def __init__(self, whitening: Whitening, detector: nn.Module):
        super().__init__()
        self.whitening = whitening
        self.detector = detector
        self.latent_dim = getattr(detector, "latent_dim", None)

    @property
    def threshold(self) -> torch.Tensor:
        return self.detector.threshold  # Detector.thresholded sets it in place

    def score(self, x: torch.Tensor) -> torch.Tensor:
        return self.detector.score(self.whitening(x))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.detector(self.whitening(x))


def whitened(detector: nn.Module, whitening: Whitening, history: np.ndarray, false_alarm: float) -> nn.Module:
    """*detector* (gearlab.learn.detectors, fitted on the unfiltered rows) seen through *whitening*:
    its healthy reference and shapes filtered, its noise level the filtered *history*'s (``norm``
    of matched_filter, ``scale`` of likelihood_ratio: the median over the history rows), and its
    threshold set again on them at *false_alarm*. A detector with neither ``templates`` nor
    ``shapes`` (a plugin's own) is returned as it is.

    The shapes are filtered after the fit, not the rows before it, because a detector's reference
    is the elementwise median of its history rows, which the filter does not commute with: on E's
    development training, fitted on filtered rows, matched_filter ranked single revolutions at AUC
    0.16, with the filtered median and the shapes as fitted (through the path between the two
    unfiltered references) then filtered at 0.95. The history's level, not each revolution's own,
    because once the strong leftover is filtered down a revolution's own level is mostly what the
    shapes miss of its fault's response, so a fault reads as noise: on E, each unit's own level
    gave revolution AUCs 0.19 (matched_filter) and 0.50 (likelihood_ratio), the history's 0.95."""
    from .detector_contract import Detector

    buffers = dict(detector.named_buffers())
    if "reference" not in buffers or not ({"templates", "shapes"} & set(buffers)):
        return detector
    with torch.no_grad():
        detector.reference.copy_(whitening(detector.reference))
        if "templates" in buffers:  # a cosine's templates: unit rows again
            t = whitening(detector.templates)
            detector.templates.copy_(t / t.norm(dim=1, keepdim=True).clamp_min(1e-12))
        if "shapes" in buffers:  # a likelihood ratio's shapes keep their size (residual and shape alike)
            detector.shapes.copy_(whitening(detector.shapes))
        rows = whitening(torch.as_tensor(np.asarray(history, dtype=np.float32)))
        if "norm" in buffers:  # matched_filter: the history's median residual norm
            detector.norm.copy_(detector.residual(rows).norm(dim=1).median())
        if "scale" in buffers:  # likelihood_ratio: the history's median noise scale
            from .bounds import noise_scale

            detector.scale.copy_(noise_scale(rows - detector.reference, detector.kind).median())
    return Detector.thresholded(Whitened(whitening, detector), (history, None), false_alarm)
