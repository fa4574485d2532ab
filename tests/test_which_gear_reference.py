"""Which gear where the records' structure is not the simulator's: the simulated events' phases at their
own mesh (signals.which_template.reference_phase_match), not their whole shape. A tooth fault changes its
own mesh while in mesh, so about that mesh's harmonics h Z its event stands at a phase to the line that the
fault and the mesh set, the same for every tooth, and that a structure turning a line and its neighbouring
orders alike leaves; about the other gear's mesh the phase moves with the tooth. Hand-written spectra of a
63T wheel and a 24T pinion on one shaft: each fault a pulse 1.5 of its pitches long times its mesh's
deflection, reaching the sensor through a broad mode per mesh (orders 80 and 260 in the simulator, swapped
in the records: the history's mesh lines 11 dB off the simulated)."""

from types import SimpleNamespace

import numpy as np
import pytest

from gearlab.signals import which_template as T
from gearlab.signals.localise import Gear

TOP = 420  # shaft orders
ORDERS = np.arange(1, TOP + 1)
WHEEL, PINION = Gear("intermediate", 1, "wheel", 63), Gear("intermediate", 2, "pinion", 24)
CARRIER = (ORDERS % 63 == 0) | (ORDERS % 24 == 0)
LAY = SimpleNamespace(orders=ORDERS.astype(float), carrier=CARRIER, shaft_orders=(1.0,), shafts=("intermediate",))
HARMONICS = (~CARRIER, ORDERS[~CARRIER])
_rng = np.random.default_rng(3)
PHI = {z: _rng.uniform(0, 2 * np.pi, 20) for z in (63, 24)}  # each mesh's harmonics' phases in the shaft's angle
DEFLECTION = 0.7 ** np.arange(20)  # the mesh deflection's harmonics (its mean 1)


def path(centre: float) -> np.ndarray:
    """A broad mode at shaft order *centre*: the response from a mesh to the sensor."""
    return 1.0 / (1 + 1j * (ORDERS - centre) / 25.0) + 0.05


def event(gear: Gear, tooth: int, sign: float, response: np.ndarray, phi: dict = PHI) -> np.ndarray:
    """A fault on *tooth* of *gear*: a stiffness pulse 1.5 pitches long times the mesh's deflection (its
    harmonics' phases *phi*[teeth])."""
    z, at = gear.teeth, 2 * np.pi * tooth / gear.teeth
    pulse = lambda k: np.sinc(k * 1.5 / z) * np.exp(-1j * k * at)  # noqa: E731
    e = pulse(ORDERS).astype(complex)
    for h in range(1, 8):
        e += 0.5 * DEFLECTION[h] * np.exp(1j * phi[z][h]) * pulse(ORDERS - h * z)
    return sign * response * e


def lines(wheel_path: np.ndarray, pinion_path: np.ndarray, gears: tuple = (WHEEL, PINION), phi: dict = PHI):
    out = np.zeros(TOP, complex)
    for g, response in zip(gears, (wheel_path, pinion_path)):
        for h in range(1, TOP // g.teeth + 1):
            out[h * g.teeth - 1] += 30 * DEFLECTION[h] * np.exp(1j * phi[g.teeth][h]) * response[h * g.teeth - 1]
    return out


SIMULATED = (path(80.0), path(260.0))  # the simulator's paths from mesh 1 (wheel) and mesh 2 (pinion)
TEMPLATES = {
    "healthy": lines(*SIMULATED),
    "gears": {g.name: [event(g, 0, s, p) for s in (1.0, -1.0)] for g, p in zip((WHEEL, PINION), SIMULATED)},
}


def decide(gear: Gear, tooth: int, sign: float, structure: tuple[np.ndarray, np.ndarray], k: float = 0.0):
    """which_by_template on a record of a fault on *gear* through *structure* (wheel's path, pinion's); with *k*,
    the event k times the hand-written one and added at the mesh lines too (tests/test_which_strong.py)."""
    x = (k or 1.0) * event(gear, tooth, sign, structure[0 if gear is WHEEL else 1])
    healthy = lines(*structure)
    mean = healthy + x if k else np.where(CARRIER, healthy, x)
    # noise-free but for a floor: every harmonic's event stands clear of it (own_mesh_weights near 1)
    rec = SimpleNamespace(mean=mean, power=np.abs(mean) ** 2, noise=np.full(TOP, 1e-12 * np.abs(x).max() ** 2))
    ref = SimpleNamespace(power=np.where(CARRIER, np.abs(healthy) ** 2, 1e-9 * np.abs(x).max() ** 2), line=CARRIER)
    return T.which_by_template(rec, ref, LAY, HARMONICS, [WHEEL, PINION], TEMPLATES)


@pytest.mark.parametrize("gear", [WHEEL, PINION], ids=["63T wheel", "24T pinion"])
@pytest.mark.parametrize("tooth", [3, 11, 17])
def test_another_structure_names_the_gear_by_its_own_mesh_phases(gear, tooth):
    """Red before reference_phase_match: the events were not used over 5 dB (the width decided)."""
    by, ev = decide(gear, tooth, -1.0, SIMULATED[::-1])
    assert ev["structure gap dB"] > T.SHAPE_DB
    assert by == gear and ev["rule"] == T.RULE_REFERENCE, ev
    match = ev["own-mesh phase match"]
    own, other = match[gear.name], match[(PINION if gear is WHEEL else WHEEL).name]
    # 0.88 for the 24T at tooth 3: its 8th mesh harmonic lies past the hand-written deflection's 7 (the pulse's tail)
    assert own > 0.85 and own - other > T.REFERENCE_MARGIN, ev
    assert "own-mesh phases matched" in T.fit_words(ev) and T.phase_words(ev) == ""


def test_the_simulators_own_structure_still_compares_the_whole_shape():
    by, ev = decide(PINION, 5, 1.0, SIMULATED)
    assert ev["structure gap dB"] < T.SHAPE_DB
    assert by == PINION and "simulated fit" in ev and "own-mesh phase match" not in ev, ev
