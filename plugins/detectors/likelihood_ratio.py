"""The simulator's fault shapes in a likelihood ratio (beyond the thesis): the Bayes detector's
statistic (gearlab.learn.bounds) with the simulation's shapes in place of the target's own.

No network is trained. A target revolution's residual from the healthy history's median is
scored by the mixture likelihood ratio of the source's fault shapes, brought to the target's
size and form by the path fitted between the two domains' healthy references (`path`:
``fir`` a filter, by default, or ``gain`` one number; gearlab.learn.path), in the noise law read off the
history (Gaussian, Laplace or Student-t) at the revolution's own noise scale; the threshold
lets `false_alarm` of the history through (a Gumbel law fitted by its quartiles, as
`matched_filter`). Against `matched_filter`'s largest cosine it knows the noise law and the
shapes' sizes; it is exact where the simulator is (a corrected simulator, docs/gap.md).
"""

from __future__ import annotations

from gearlab.api import PATHS, Detector, DetectorParams, hookimpl, parameters, path_setting, setting

SCALES = ("unit", "history")  # gearlab.learn.detectors.SCALES (torch is not imported here)
MIXTURES = ("shapes", "sizes")  # gearlab.learn.detectors.MIXTURES
MIXTURE_DOC = "the mixture: 0 = shapes (each as the path brings it), 1 = sizes (also 1/4-4 times that, either sign)"

# torch (via gearlab.learn.detectors) is imported inside the method: see gearlab.learn.detector_contract.


SCALE_DOC = "noise scale of a scored revolution: 0 = unit (its own), 1 = history (the healthy history's median)"


class LikelihoodRatio(Detector):
    name = "likelihood_ratio"
    doc = (
        "Physics-template detector: mixture likelihood ratio of the simulated fault shapes in the history's noise "
        "law, thresholded on the healthy history (no network)."
    )
    params = parameters(
        DetectorParams,
        path=path_setting(),
        scale=setting(int, 0, low=0, high=len(SCALES) - 1, doc=SCALE_DOC),
        mixture=setting(int, 0, low=0, high=len(MIXTURES) - 1, doc=MIXTURE_DOC),
    )
    choices = {"path": PATHS, "scale": SCALES, "mixture": MIXTURES}

    def statistic(self, source, target, params=None):
        from gearlab.api import likelihood_statistic

        values = self.named(params)
        return likelihood_statistic(
            *source, *target, path=values["path"], scale=values["scale"], mixture=values["mixture"]
        )


@hookimpl
def gearlab_detectors():
    return [LikelihoodRatio()]
