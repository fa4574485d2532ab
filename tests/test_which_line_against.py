"""Which gear where the records' structure turns a line both gears' meshes share against the simulator's: the rig's
idler carries a 96T wheel and a 48T pinion, so its orders 96, 192, 288 and 384 are lines of both meshes, each through
its own dynamics and path. Stiffer bearings (development records, seeds 41, 42, 45) turned order 96's line 115-160° off
the simulated healthy line and the event's phase to it by a median 128° (the other lines 7-35°): the 96T's faults were
named the 48T's. signals.which_template.lines_against finds such a shared line (the shaft's angle offset fitted first)
and reference_phase_match reads the others. Hand-written spectra as tests/test_which_gear_reference.py's, on a 48T
wheel and a 24T pinion (every wheel harmonic a pinion one)."""

from types import SimpleNamespace

import numpy as np
import pytest
import test_which_gear_reference as reference

from gearlab.signals import which_template as T
from gearlab.signals.localise import Gear

TOP = 420  # shaft orders
ORDERS = np.arange(1, TOP + 1)
WHEEL, PINION = Gear("idler", 1, "wheel", 48), Gear("idler", 2, "pinion", 24)
CARRIER = ORDERS % 24 == 0
LAY = SimpleNamespace(orders=ORDERS.astype(float), carrier=CARRIER, shaft_orders=(1.0,), shafts=("idler",))
HARMONICS = (~CARRIER, ORDERS[~CARRIER])
_rng = np.random.default_rng(3)
PHI = {z: _rng.uniform(0, 2 * np.pi, 20) for z in (48, 24)}  # each mesh's harmonics' phases in the shaft's angle
# the simulator's own paths, each line's level off by up to ±6 dB (a real gain: no phase), so the structures differ
# (structure gap over SHAPE_DB) and the phases at each gear's own mesh decide
GAINS = np.where(CARRIER, 10 ** (_rng.uniform(-6, 6, TOP) / 20), 1.0)


def event(gear: Gear, tooth: int, sign: float, response: np.ndarray) -> np.ndarray:
    return reference.event(gear, tooth, sign, response, PHI)


def lines(wheel_path: np.ndarray, pinion_path: np.ndarray) -> np.ndarray:
    return reference.lines(wheel_path, pinion_path, (WHEEL, PINION), PHI)


SIMULATED = (reference.path(80.0), reference.path(260.0))
TEMPLATES = {
    "healthy": lines(*SIMULATED),
    "gears": {g.name: [event(g, 0, s, p) for s in (1.0, -1.0)] for g, p in zip((WHEEL, PINION), SIMULATED)},
}


def record(gear, tooth: int, turned: tuple[int, ...] = (), offset: float = 0.0):
    """(rec, ref) of a fault on *tooth* of *gear*: the healthy lines at the shaft harmonics *turned* turned by 135°, the
    event's content about them not; every order m turned by m times the shaft angle *offset* (the tacho mark
    elsewhere)."""
    x = event(gear, tooth, -1.0, SIMULATED[0 if gear is WHEEL else 1])
    healthy = TEMPLATES["healthy"] * GAINS
    healthy[np.isin(ORDERS, turned)] *= np.exp(1j * 0.75 * np.pi)
    mean = np.where(CARRIER, healthy, x) * np.exp(-1j * ORDERS * offset)
    rec = SimpleNamespace(mean=mean, power=np.abs(mean) ** 2, noise=np.full(TOP, 1e-12 * np.abs(x).max() ** 2))
    ref = SimpleNamespace(power=np.where(CARRIER, np.abs(healthy) ** 2, 1e-9 * np.abs(x).max() ** 2), line=CARRIER)
    return rec, ref


def match(gear, tooth: int, turned=()) -> dict:
    rec, ref = record(gear, tooth, turned)
    by, ev = T.which_by_template(rec, ref, LAY, HARMONICS, [WHEEL, PINION], TEMPLATES)
    assert ev["structure gap dB"] > T.SHAPE_DB and ev["rule"] == T.RULE_REFERENCE, ev
    return ev["own-mesh phase match"]


@pytest.mark.parametrize("gear", [WHEEL, PINION], ids=["48T wheel", "24T pinion"])
@pytest.mark.parametrize("tooth", [3, 11])
def test_a_shared_line_turned_against_the_simulated_is_not_read(gear, tooth):
    # red before lines_against: order 48 turned took 0.21 off the damaged gear's match (1.00 -> 0.79), wheel or pinion
    plain, turned = match(gear, tooth), match(gear, tooth, (48,))
    assert plain[gear.name] > 0.95 and abs(turned[gear.name] - plain[gear.name]) < 0.05, (plain, turned)


@pytest.mark.parametrize("offset", [0.0, 0.37, 2.0])
def test_the_turned_shared_line_is_found_wherever_the_tacho_mark_sits(offset):
    # orders 24 and 72 are the pinion's mesh alone: its event passes with the line there, read as before
    for turned, found in (((), []), ((48,), [48]), ((96, 144), [96, 144]), ((24, 72), []), ((24, 192), [192])):
        rec, _ = record(PINION, 11, turned, offset)
        got = T.lines_against(rec.mean, TEMPLATES["healthy"], LAY, 0, [WHEEL, PINION])
        assert got == found, (offset, turned, got)
