"""The structure check (gearlab/gap/structure.py) takes each history's spectrum, and inspect's reading of it
(gearbox.match.check_description) against each description, once (structure_later.Spectra): it reads the revolutions
several ways (mesh_check, inspect's stages, a tacho's misread, what passed unchecked, the later stages), and a long
history's spectrum and running median cost seconds a reading. Read once or read afresh each time, the check says the
same line and records the same readings."""

import math

import numpy as np
import pytest
from gearboxes import described_pair

import gearlab.signals
from gearlab.data.chain import Chain
from gearlab.gap import structure
from gearlab.gap.structure_later import Spectra
from gearlab.gearbox import match

TRAIN = ((22, 71), (27, 86))


def _rows(n: int = 240, points: int = 1024, seed: int = 0) -> np.ndarray:
    """*n* input revolutions of a two-stage train, each mesh's first three harmonics modulated by its shafts."""
    t = 2 * math.pi * np.arange(n * points) / points
    x = 0.05 * np.random.default_rng(seed).standard_normal(t.size)
    speed = 1.0
    for z1, z2 in TRAIN:
        shafts = 1 + 0.3 * np.cos(speed * t) + 0.2 * np.cos(speed * z1 / z2 * t)
        x += shafts * sum(np.cos(h * z1 * speed * t) / h for h in (1, 2, 3))
        speed *= z1 / z2
    return x.reshape(n, points)


class _Afresh(Spectra):
    """Every reading taken anew, as each reader took it before the check shared them: inspect's with the tacho's
    shaft as the reader gave it (0 for the input too)."""

    def _entry(self, rows) -> dict:
        self._read.clear()
        return super()._entry(rows)

    def check(self, rows, max_order, box, on_input, tacho_shaft=None, beyond=()) -> dict:
        lines = self.lines(rows, max_order)
        return match.check_description(lines, box, rows.shape[0], on_input, tacho_shaft, beyond)


@pytest.fixture
def counted(monkeypatch):
    calls = []
    spectrum = gearlab.signals.spectrum
    monkeypatch.setattr(gearlab.signals, "spectrum", lambda *a: calls.append(a[0].size) or spectrum(*a))
    return calls


@pytest.fixture
def inspected(monkeypatch):
    """The readings check_description is asked for: (the lines read, the description, revolutions, the tacho read
    on the input, its shaft, the stages beyond)."""
    calls = []
    check = match.check_description

    def counted(lines, box, n, on_input, tacho_shaft=None, beyond=()):
        calls.append((id(lines), box, n, on_input, tacho_shaft, tuple(beyond)))
        return check(lines, box, n, on_input, tacho_shaft, beyond)

    monkeypatch.setattr(match, "check_description", counted)
    return calls


TACHO = dict(tacho_shaft="input")
NO_TACHO = dict(speed_from_mesh=True, described_speed=25.0)  # the speed from the mesh lines: the input's count read


@pytest.mark.parametrize(
    "described, takes, read, histories",
    [
        (TRAIN, (80, 80, 80), TACHO, 2),  # takes laid end to end: the whole history and its longest take
        (TRAIN, (), TACHO, 1),  # one take: one history
        (((22, 71), (28, 86)), (80, 80, 80), TACHO, 2),  # a later pinion one tooth off: a line
        (TRAIN, (80, 80, 80), NO_TACHO, 2),
        (((22, 71), (28, 86)), (80, 80, 80), NO_TACHO, 2),
    ],
)
def test_the_structure_check_reads_each_history_s_spectrum_once_and_says_the_same(
    counted, inspected, described, takes, read, histories
):
    rows, pair = _rows(), described_pair(*described)

    def check(spectra):
        chain = Chain(fs=1024 * 25.0, speed=25.0, takes=takes, **read)
        record: dict = {}
        return structure.structure_line(
            rows, pair, 400, chain, None, record, 1 if read is TACHO else None, spectra
        ), record

    once = check(None)
    assert len(counted) == histories
    # inspect's reading of a history against a description: once each (the first stage's pair, the train)
    assert len(inspected) == len(set(inspected)) <= 2 * histories
    taken = len(inspected)
    counted.clear()
    inspected.clear()
    afresh = check(_Afresh())
    assert len(counted) > histories  # the readers do read the revolutions more than once
    assert len(inspected) >= taken  # ... and ask inspect's reading of them again (a train read right: 6 for 4)
    assert repr(once) == repr(afresh)
    assert (once[0] is None) == (described == TRAIN)
