"""Which gear of a shaft's two gears where the event is strong enough to stand at its own mesh lines: the record's
line there is the healthy mesh's plus the event's own content at that order, and reference_phase_match reads the
event's phase against it (signals.which_template). Where the event rivals the line, the reference turns with the
event itself and every gear's phases match alike: on development records (benchmarks/localisation.py, seeds 41 and
42, bearings 0.5x / 2x, casing path, sensor resonance) the 24T pinion of 21/63 + 24/56 with a pit (z in the thousands,
the event 0.5-1.1 of its own mesh lines at their neighbouring orders) was left with both gears or named the 63T wheel.
event_free_lines takes the event's content at each mesh line, interpolated from its orders on either side, off the
line first. The spectra are the hand-written ones of tests/test_which_gear_reference.py, the event k times stronger and
added at every order, the lines included."""

from types import SimpleNamespace

import numpy as np
import pytest
from test_which_gear_reference import (
    CARRIER,
    HARMONICS,
    LAY,
    ORDERS,
    PINION,
    SIMULATED,
    WHEEL,
    event,
    lines,
)
from test_which_gear_reference import decide as reference_decide

from gearlab.signals import which_template as T
from gearlab.signals.localise import Gear


def decide(gear, tooth: int, k: float):
    """which_by_template on a fault on *gear* through another structure (the simulator's paths swapped), its event *k*
    times the hand-written one, added at the mesh lines too."""
    return reference_decide(gear, tooth, -1.0, SIMULATED[::-1], k)


@pytest.mark.parametrize("gear", [WHEEL, PINION], ids=["63T wheel", "24T pinion"])
@pytest.mark.parametrize("tooth", [3, 11, 17])
def test_a_strong_event_is_named_by_its_phases_as_a_weak_one_is(gear, tooth):
    # red before: at k = 100 (the event 0.5-13 times the lines it stands at) the 24T pinion's faults named the 63T wheel
    # (tooth 3) or both (11, 17), the 63T's tooth 11 both; the damaged gear's match fell from 0.88-1.0 to 0.35-0.79
    weak, strong = decide(gear, tooth, 1.0), decide(gear, tooth, 100.0)
    assert weak[0] == gear and strong[0] == gear, strong[1]
    own = strong[1]["own-mesh phase match"][gear.name]
    assert own > 0.85 and abs(own - weak[1]["own-mesh phase match"][gear.name]) < 0.02, strong[1]


def test_the_event_is_taken_off_the_line_it_stands_at():
    x = 100.0 * event(PINION, 11, -1.0, SIMULATED[0])
    healthy = lines(*SIMULATED)
    sel, m = HARMONICS
    clean = T.event_free_lines(x[sel], m, healthy + x, LAY, 0, [WHEEL, PINION])
    at = np.flatnonzero(CARRIER)[:6]  # the first mesh lines of both gears
    before = np.abs(x[at]) / np.abs(healthy[at])
    after = np.abs(clean[at] - healthy[at]) / np.abs(healthy[at])
    assert before.max() > 0.3 and after.max() < 0.2 * before.max(), (before, after)


def test_a_line_both_gears_share_loses_the_event_once():
    # a 48T wheel and a 24T pinion on one shaft (the rig's idler: 96T and 48T): every wheel harmonic is a pinion one
    wheel, pinion = Gear("intermediate", 1, "wheel", 48), Gear("intermediate", 2, "pinion", 24)
    carrier = ORDERS % 24 == 0
    lay = SimpleNamespace(orders=ORDERS.astype(float), carrier=carrier, shaft_orders=(1.0,), shafts=("intermediate",))
    x = 1.0 / (1 + 1j * (ORDERS - 100) / 60.0)  # a smooth event, peaking at the shaft's zero
    healthy = np.where(carrier, 5.0, 0.0).astype(complex)
    clean = T.event_free_lines(x[~carrier], ORDERS[~carrier], healthy + x, lay, 0, [wheel, pinion])
    at = np.flatnonzero(carrier)[:8]
    assert np.abs(clean[at] - healthy[at]).max() < 0.01 * np.abs(x[at]).min(), clean[at] - healthy[at]
