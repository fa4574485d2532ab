"""The detector contract: a method that trains no network (beyond the thesis).

A detector plugin is a :class:`Detector` registered through the ``gearlab`` entry-point group
(hook ``gearlab_detectors``). Where an adapter trains a network, a detector is fitted in one
step on the training arrays of a unit (a chapter-5 unit, a detection condition, a gap
accuracy unit):

- ``source`` = (X, y): the simulated source's revolutions, healthy (y = 0) and faulty (y = 1);
  the protocol hands each sample's mean over its noise draws, the least noisy estimate of its shape;
- ``target`` = (X, y or None): the target's training revolutions; None (unsupervised, the
  thesis's assumption at k = 0) takes every one as the healthy history, labels mark the
  healthy ones and let the target's own faults add their shapes.

The plugin writes :meth:`Detector.statistic`, the unthresholded model: a ``torch.nn.Module``
with ``score(x)`` (one number a revolution, higher = more like a fault), a ``threshold`` buffer
and logits ``[0, score - threshold]``, so that every protocol scores it as it scores a network.
The base class's :meth:`Detector.fit` then sets the threshold from the target's healthy history
alone: the ``1 - false_alarm`` quantile of a Gumbel law fitted to the history's scores
(gearlab.learn.history.history_threshold). ``plugins/detectors/`` holds the two built-ins.

A scenario names a detector where it names its methods (``[[methods]] adapter = ...``, a gap
scenario's ``methods`` list): adapters and detectors share one namespace (gearlab.registry.METHODS).

This module does not import torch (the registry imports every plugin on every command);
``fit`` and ``score`` import it when they run.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from gearlab.settings import plugin_description, setting

from .adapters import MethodPlugin
from .path import PATHS

if TYPE_CHECKING:  # for the annotations only; see the module docstring
    from torch import nn


@dataclass(frozen=True)
class DetectorParams:
    """Every detector's threshold: the share of the target's healthy history let through. A
    detector's parameters extend it."""

    false_alarm: float = setting(
        float, 0.01, low=1e-6, high=0.5, doc="share of the target's healthy history allowed above the threshold"
    )


PATH_DOC = "simulated shapes to the target: 0 = gain, 1 = fir (filter fitted between the healthy references)"


def path_setting():
    """A detector's parameter ``path``: how the simulated shapes reach the target (gearlab.learn.path);
    scenarios may give the names."""
    return setting(int, PATHS.index("fir"), low=0, high=len(PATHS) - 1, doc=PATH_DOC)


class Detector(MethodPlugin):
    """Base of every detector plugin: fitted on the source's healthy and fault rows and the
    target's healthy history, scores rows, thresholded on that history at ``false_alarm``."""

    kind = "detector"
    params: type = DetectorParams

    def statistic(self, source, target, params: Mapping | None = None) -> nn.Module:
        """The unthresholded model of the training arrays *source* = (X, y) and *target* =
        (X, y or None); see the module docstring."""
        raise NotImplementedError(f"detector '{self.name}' has no statistic")

    def fit(self, source, target, params: Mapping | None = None) -> nn.Module:
        """:meth:`statistic`, thresholded on the target's healthy history (:meth:`thresholded`)."""
        false_alarm = float(self.values(params)["false_alarm"])
        return self.thresholded(self.statistic(source, target, params), target, false_alarm)

    @classmethod
    def thresholded(cls, model: nn.Module, target, false_alarm: float) -> nn.Module:
        """*model* with its threshold set from the scores of the target's healthy history (the
        rows of *target* = (X, y) labelled 0, or every row when y is None) at *false_alarm*."""
        X, y = target
        history = np.asarray(X, dtype=np.float64)[slice(None) if y is None else np.asarray(y) == 0]
        model.threshold.fill_(cls.threshold(cls.score(model, history), false_alarm))
        return model

    @staticmethod
    def score(model: nn.Module, X: np.ndarray) -> np.ndarray:
        """The model's score of each row of *X* (its threshold not taken off)."""
        import torch  # start-up time

        with torch.no_grad():
            return model.score(torch.as_tensor(X, dtype=torch.float32)).numpy()

    @staticmethod
    def threshold(history_scores: np.ndarray, false_alarm: float) -> float:
        """The threshold that lets *false_alarm* of the healthy history's scores through."""
        from .history import history_threshold

        return history_threshold(history_scores, 1.0 - false_alarm)

    def describe(self) -> dict:
        return plugin_description(self, supervision=list(self.supervision))


__all__ = ["Detector", "DetectorParams", "path_setting"]
