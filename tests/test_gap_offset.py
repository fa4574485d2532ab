"""A record's DC offset is its electronics', not vibration: the gap diagnosis compares each record
without its mean (gearlab.gap.views.offset_removed), the source's rows and the target's alike."""

import numpy as np
import pytest

from gearlab.data.chain import Chain
from gearlab.data.spec import dataset_preset
from gearlab.gap import scoring
from gearlab.gap.views import offset_removed

SOURCE = dataset_preset("B-6-ch5").with_(healthy=12)
SETTINGS = scoring.Settings(healthy=12, bootstrap=0, permutations=20)


def test_each_record_loses_its_own_mean():
    rng = np.random.default_rng(0)
    X = rng.standard_normal((7, 64))
    X[:3] += 5.0  # first record: a 5 m/s² offset
    X[3:] -= 2.0  # second record: -2 m/s²
    out = offset_removed(X, (3, 4))
    assert out[:3].mean() == pytest.approx(0.0, abs=1e-12) and out[3:].mean() == pytest.approx(0.0, abs=1e-12)
    # within a record nothing but the constant moves (a drift between its revolutions stays)
    np.testing.assert_allclose(out[:3] - X[:3], -X[:3].mean())
    # counts that do not add up to the rows: one record
    assert offset_removed(X, (3, 3)).mean() == pytest.approx(0.0, abs=1e-12)


@pytest.fixture(scope="module")
def plain_target():
    """Rows of the source itself on another noise seed: a target with no gap but sampling."""
    return scoring.Rows()(SOURCE.with_(seed=SOURCE.seed + 17))


def test_a_dc_offset_makes_no_gap(plain_target):
    """A record with a 30 m/s² offset (0.3 V at 10 mV/(m/s^2)) against the simulator: the same gap
    as its offset-free copy, not the waveform view's mean read as vibration (before: 1.0e12 against 0,
    times larger, all of it in the waveform view)."""
    clean = scoring.plain_report(SOURCE, plain_target, SETTINGS)
    offset = scoring.plain_report(SOURCE, plain_target + 30.0, SETTINGS)
    assert offset["total"]["gap"] == pytest.approx(clean["total"]["gap"], rel=1e-6, abs=1e-9)


def test_two_records_with_their_own_offsets_make_no_gap(plain_target):
    """Two takes with different offsets (measured records laid end to end, Chain.takes): each loses
    its own, so the offsets' difference is no spread either."""
    half = len(plain_target) // 2
    takes = (half, len(plain_target) - half)
    shifted = plain_target.copy()
    shifted[:half] += 30.0
    shifted[half:] -= 12.0
    chain = Chain(fs=SOURCE.fs, speed=SOURCE.speed_hz or 30.0, takes=takes)
    target = scoring._prepared(SOURCE, shifted, SETTINGS, chain)[0]
    expected = scoring._prepared(SOURCE, plain_target, SETTINGS, chain)[0]
    np.testing.assert_allclose(target, expected, atol=1e-9)
