"""The simulator's fault shapes in a likelihood ratio (beyond the thesis): the Bayes detector's
statistic (gearlab.learn.bounds) with the simulation's shapes in place of the target's own.

No network is trained. A target revolution's residual from the healthy history's median is
scored by the mixture likelihood ratio of the source's fault shapes, brought to the target's
size by the gain between the two domains' healthy references, in the noise law read off the
history (Gaussian, Laplace or Student-t) at the revolution's own noise scale; the threshold
lets `false_alarm` of the history through (a Gumbel law fitted by its quartiles, as
`matched_filter`). Against `matched_filter`'s largest cosine it knows the noise law and the
shapes' sizes; it is exact where the simulator is (a corrected simulator, docs/gap.md).
"""

from __future__ import annotations

from gearlab.api import FALSE_ALARM_PARAM, Adapter, hookimpl

# torch (via gearlab.learn.detectors) is imported inside the method: see gearlab.learn.adapters.


class LikelihoodRatio(Adapter):
    name = "likelihood_ratio"
    doc = (
        "Physics-template detector: mixture likelihood ratio of the simulated fault shapes in the history's noise "
        "law, thresholded on the healthy history (no network)."
    )
    params = (FALSE_ALARM_PARAM,)
    calibrated = False
    supervision = ("unsupervised", "supervised")
    train_on = "detector"

    def detector(self, source, target, params=None):
        from gearlab.api import likelihood_detector

        (Xs, ys), (Xt, yt) = source, target
        return likelihood_detector(Xs, ys, Xt, yt, false_alarm=float(self.values(params)["false_alarm"]))


@hookimpl
def gearlab_adapters():
    return [LikelihoodRatio()]
