"""Physics-template detection (beyond the thesis): the simulator's fault shapes as matched
filters, referenced and thresholded on the target's healthy history.

No network is trained. A target revolution is called faulty when its residual from the
target's healthy reference lines up with a simulated fault response better than the
healthy history's revolutions do (``gearlab.learn.detectors``). Unsupervised, the 120
target training revolutions are taken as the healthy history (the thesis's assumption at
k = 0); supervised, the labelled healthy ones are, and the labelled faults add their shapes.
"""

from __future__ import annotations

from gearlab.learn.adapters import Adapter
from gearlab.params import Param
from gearlab.registry import hookimpl

# torch (via gearlab.learn.detectors) is imported inside the method: see gearlab.learn.adapters.


class MatchedFilter(Adapter):
    name = "matched_filter"
    doc = ("Physics-template detector: largest cosine between a revolution's residual from the target's healthy "
           "reference and the simulated fault responses, thresholded on the healthy history (no network).")
    params = (
        Param("false_alarm", "", 0.01, 1e-6, 0.5, "share of the target's healthy history allowed above the threshold"),
    )
    calibrated = False
    supervision = ("unsupervised", "supervised")
    train_on = "detector"

    def detector(self, source, target, params=None):
        from gearlab.learn.detectors import template_detector

        (Xs, ys), (Xt, yt) = source, target
        return template_detector(Xs, ys, Xt, yt, false_alarm=float(self.values(params)["false_alarm"]))


@hookimpl
def gearlab_adapters():
    return [MatchedFilter()]
