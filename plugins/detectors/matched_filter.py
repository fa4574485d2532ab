"""Physics-template detection (beyond the thesis): the simulator's fault shapes as matched
filters, referenced and thresholded on the target's healthy history.

No network is trained. A target revolution is called faulty when its residual from the
target's healthy reference lines up with a simulated fault response better than the
healthy history's revolutions do (``gearlab.learn.detectors``). Unsupervised, the 120
target training revolutions are taken as the healthy history (the thesis's assumption at
k = 0); supervised, the labelled healthy ones are, and the labelled faults add their shapes.
The residual leaves out the reference's healthy lines (its strong mesh orders, which a take's
speed or load moves more than its TSAs' noise; gearlab.learn.detectors.healthy_lines).

``limiter`` (0 off by default, 1 on, 2 auto; scenarios may give the names): a soft limiter on the
residual before the correlation, the locally optimal statistic in impulsive noise; ``auto``
turns it on when the history's noise law is not Gaussian (gearlab.learn.history.noise_law).
``path`` (``fir`` by default, or ``gain``): the shapes reach the target through the filter fitted
between the two domains' healthy references (gearlab.learn.path).
``scale`` (``history`` by default, or ``unit``): a correlation over the healthy history's median
residual norm, or over the scored revolution's own (the cosine, which a fault response the
shapes miss pushes below the healthy revolutions'; gearlab.learn.detectors).
"""

from __future__ import annotations

from gearlab.api import PATHS, Detector, DetectorParams, hookimpl, parameters, path_setting, setting

LIMITERS = ("off", "on", "auto")
SCALES = ("unit", "history")  # gearlab.learn.detectors.SCALES (torch is not imported here)
SCALE_DOC = (
    "noise level of a correlation: 0 = unit (the revolution's own residual norm: cosine), 1 = history "
    "(the healthy history's median)"
)

# torch (via gearlab.learn.detectors) is imported inside the method: see gearlab.learn.detector_contract.


LIMITER_DOC = "soft limiter before the correlation: 0 = off, 1 = on, 2 = auto (on in impulsive noise)"


class MatchedFilter(Detector):
    name = "matched_filter"
    doc = (
        "Physics-template detector: largest correlation between a revolution's residual from the target's healthy "
        "reference and the simulated fault responses over the history's noise level, thresholded on the healthy "
        "history (no network)."
    )
    params = parameters(
        DetectorParams,
        limiter=setting(int, 0, low=0, high=2, doc=LIMITER_DOC),
        path=path_setting(),
        scale=setting(int, 1, low=0, high=len(SCALES) - 1, doc=SCALE_DOC),
    )
    choices = {"limiter": LIMITERS, "path": PATHS, "scale": SCALES}

    def statistic(self, source, target, params=None):
        from gearlab.api import template_statistic

        values = self.named(params)
        return template_statistic(
            *source, *target, limiter=values["limiter"], path=values["path"], scale=values["scale"]
        )


@hookimpl
def gearlab_detectors():
    return [MatchedFilter()]
