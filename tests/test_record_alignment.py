"""Detection's and score's alignment of a record with its condition's history (issue 39): on a train
whose later mesh is no whole input order, each record is shifted into register as one signal
(signals.angle.continued), not each revolution turned on itself, which cut that mesh at every row's
turn: its fit (without_asynchronous) could not take it out of the units. A whole-order train keeps
the row-by-row turn (the same rows, the same figures)."""

from types import SimpleNamespace

import numpy as np
import pytest

from gearlab.data.textzip import align_to, align_turn
from gearlab.kinds.detection_records import aligned, register_to_source, tsa_units, without_asynchronous
from gearlab.parts.measured import TargetFile
from gearlab.signals.angle import continued

P, N = 1024, 40


def _train(stages, start: int, seed: int) -> np.ndarray:
    """N revolutions of *stages* ((z1, z2), ...) from sample *start* on: each mesh's harmonics 1-2, a
    later stage at 0.3 of the one before, amplitude-modulated by its pinion's shaft; white noise."""
    theta = 2 * np.pi * (np.arange(N * P) + start) / P
    x, o = np.zeros(theta.size), 1.0
    for k, (z1, z2) in enumerate(stages):
        mod = 1 + 0.2 * np.cos(o * theta)
        for h in (1, 2):
            x += 0.3**k / h * mod * np.cos(h * o * z1 * theta + 0.7 * h + k)
        o *= z1 / z2
    return (x + np.random.default_rng(seed).normal(0, 0.05, x.size)).reshape(N, P)


FAN = [(19, 58), (25, 67)]
M2 = 19 * 25 / 58  # 8.19 input orders


def _kept(continuous: bool) -> float:
    """The share of the later stage's energy the revolution units keep once it is fitted out."""
    reference = _train(FAN, 0, 1).mean(axis=0)
    turn, full = aligned(reference, _train(FAN, 357, 2), None, 1, continuous)
    _, first = aligned(reference, _train(FAN[:1], 357, 2), None, 1, continuous)  # the same, stage 1 only
    assert turn != 0
    left = without_asynchronous(full, (M2,)) - without_asynchronous(first, (M2,))
    return float(np.sum(left**2) / np.sum((full - first) ** 2))


def test_a_record_is_shifted_as_one_signal_so_the_later_mesh_is_fitted_out():
    # measured: 19/58 + 25/67 at 1024 points, 14 % of the later stage kept turned row by row, 0.2 % shifted
    # as one signal; lines at 8.19 + k of the rows end to end 39 dB over the floor -> 5 dB
    assert _kept(False) > 0.05  # what detection and score kept before
    assert _kept(True) < 0.01
    reference = _train(FAN, 0, 1).mean(axis=0)
    _, rows = aligned(reference, _train(FAN, 357, 2), None, 1, True)
    assert rows.shape == (N - 1, P)  # the record's last revolution given up
    x = rows.reshape(-1)
    spectrum = np.abs(np.fft.rfft(x * np.hanning(x.size)))
    orders = np.fft.rfftfreq(x.size, 1 / P)
    floor = np.median(spectrum[(orders > 1) & (orders < 60)])
    beside = [spectrum[np.argmin(abs(orders - M2 - k))] / floor for k in (-2, -1, 1, 2, 3)]
    assert 20 * np.log10(max(beside)) < 15


def test_a_tacho_s_mark_shifts_the_record_by_its_fraction_of_a_turn():
    # three marks a turn: the record starts a third of a turn on, in between the samples
    reference = np.cos(2 * np.pi * np.arange(P) / P)
    one = np.cos(2 * np.pi * (np.arange(20 * P) + P / 3) / P) + np.cos(2 * np.pi * M2 * np.arange(20 * P) / P)
    turn, rows = aligned(reference, one.reshape(20, P), "tacho", 3, True)
    assert turn == 2  # two thirds on: back in register
    want = np.cos(2 * np.pi * M2 * (np.arange(19 * P) + 2 * P / 3) / P) + np.cos(2 * np.pi * np.arange(19 * P) / P)
    assert np.abs(rows - want.reshape(19, P))[2:-2].max() < 1e-4


def test_a_tacho_s_continuous_alignment_is_align_to_s_mark_then_continued_exactly():
    # the record advanced as one signal needs only align_to's mark (align_turn), not its rows turned on themselves:
    # the same mark and the same arrays, bit for bit, for marks tried in turn and folded at once (over 4096)
    reference = _train(FAN, 0, 0).mean(axis=0)
    record = _train(FAN, 357, 1)
    for marks in (6, 5000):
        mark, turned = align_to(reference, record, marks)
        assert align_turn(reference, record, marks) == mark
        turn, rows = aligned(reference, record, "tacho", marks, True)
        assert turn == mark and np.array_equal(rows, continued(record, mark * P / marks))
        turn, rows = aligned(reference, record, "tacho", marks)
        assert turn == mark and np.array_equal(rows, turned)
    assert 0 < mark  # (a record 357 samples on is no mark 0 of 5000)


def test_a_whole_order_train_keeps_its_rows():
    # the PHM 2009 rig's 32/96 + 48/80 (later mesh at a whole 16): nothing of it is fitted out, and
    # detection keeps the turn on itself for such trains (continuous only where asynchronous_orders
    # finds a mesh): the same rows, the same figures as before. (Its slower shafts, at 1/3 and 1/5 of
    # a turn, are cut at every row's turn alike: here their modulation differs by up to 0.15 at the
    # rows' ends, the signal's peak 1.8; left as it was.) One mark a turn: no turn, either way.
    reference = _train([(32, 96), (48, 80)], 0, 0).mean(axis=0)
    record = _train([(32, 96), (48, 80)], 357, 1)
    turn, rolled = aligned(reference, record, None, 1)
    assert turn == P - 357
    assert np.array_equal(rolled, np.roll(record, -turn, axis=-1))
    assert np.array_equal(aligned(reference, record, "tacho", 1, True)[1], record)


def test_the_source_s_turn_shifts_a_continuous_condition_s_records_once():
    # without a tacho the condition is turned again into the source's frame (register_to_source): a
    # continuous condition's records are shifted from where they were read by the sum of both turns
    # (one revolution given up, not two), and their units made again
    reference = _train(FAN, 0, 1).mean(axis=0)
    read = {"h": _train(FAN, 0, 1), "t": _train(FAN, 357, 2)}
    files = {p: TargetFile(p, p, "history" if p == "h" else "test", "", "c") for p in read}
    cond = {"reference": reference, "shifts": {}, "continuous": True, "blocks": (10,), "standardised": read}
    for role, p in (("history", "h"), ("test", "t")):
        cond["shifts"][p], rows = aligned(reference, read[p], None, 1, True)
        cond[role] = [(files[p], rows)]
    source = SimpleNamespace(X=np.roll(reference, 100)[None, :], fault=np.array([0]))
    turn = register_to_source(cond, source)
    assert turn == P - 100
    test = cond["test"][0][1]
    assert test.shape == (N - 1, P)
    assert np.array_equal(test, continued(read["t"], (P - 357 + turn) % P))
    assert np.array_equal(cond["test_units"]["t"]["record10"], tsa_units(test, 10))
    assert cond["history_units"]["revolution"].shape == (N - 1, P)


def test_a_run_of_the_row_by_row_turn_is_refused_where_its_train_has_a_later_mesh(tmp_path, monkeypatch):
    # its models and thresholds were fitted to units that kept the later mesh; a whole-order train's
    # run is scored (its units never changed)
    from gearlab.errors import GearlabInputError
    from gearlab.kinds import detection_scoring as S
    from gearlab.parts import scoring
    from gearlab.runs import RunDir

    class Passed(Exception):
        pass

    def passed(*args, **kwargs):
        raise Passed

    monkeypatch.setattr(S, "reading_keys", passed)
    run = RunDir(tmp_path)
    run.write_json(scoring.SCORING_FILE, {"conditions": {}, "later_orders": [M2], "input_version": 2})
    with pytest.raises(GearlabInputError, match=r"input_version 2 \(a later mesh .* turned on itself\)"):
        S.score(run, [])
    run.write_json(scoring.SCORING_FILE, {"conditions": {}, "later_orders": [], "input_version": 2})
    with pytest.raises(Passed):
        S.score(run, [])
