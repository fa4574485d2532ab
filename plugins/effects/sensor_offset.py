"""sensor_offset: a constant (DC) offset on the measured acceleration.

Physical mismatch. A piezoelectric accelerometer cannot measure a constant acceleration, yet a
record may carry a constant: the sensor's bias voltage or an amplifier offset left in by a
DC-coupled acquisition, which the sensitivity then turns into m/s² (on the PHM 2009 rig's
input-side channel, about 0.4 V, i.e. some 40 m/s²). It is not vibration, and a simulation has
none. The gap diagnosis compares each record without its mean (gearlab.gap.views.offset_removed),
source and target alike, and the offset is added last (after every signal effect, before order
tracking, which keeps a constant a constant), so there it changes nothing: it is a simulator
effect only (mean_only), which no diagnosis takes as a candidate. A simulated dataset may carry
it, as a DC-coupled record does (phm09_chip's source).

Realisation. The offset is added to every sample of the record (after every other effect).

Bounds. -1000 to 1000 m/s² (±10 V at 10 mV/g: the whole input range of a usual acquisition).
Default 0.
"""

import numpy as np

from gearlab.api import Effect, hookimpl, parameters, setting


class SensorOffset(Effect):
    name = "sensor_offset"
    doc = "constant (DC) offset on the measured acceleration: a sensor or amplifier bias"
    mean_only = True
    params = parameters(
        offset=setting(float, 0.0, low=-1000.0, high=1000.0, unit="m/s^2", doc="constant added to the acceleration")
    )

    def apply_signal(self, x, params, ctx):
        return np.asarray(x, dtype=float) + params["offset"]


@hookimpl
def gearlab_effects():
    return [SensorOffset()]
