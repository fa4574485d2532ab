"""Which gear in the envelope (gearlab.signals.envelope_sync, read by data.which_gear): on a 39/61 box at 30 Hz
(tests/jittered_strikes.py), a tooth strike ringing a resonance at 120.9 input orders, its instant jittering by up
to half a ring period, cancels in every shaft's synchronous average and the non-synchronous check leaves its lines
out; its shaft's synchronous average of the residual's squared envelope names its gear. A healthy take is not
called, and a synchronous fault is named as before."""

from __future__ import annotations

import dataclasses
import re

import numpy as np
import pytest
from jittered_strikes import BOX, RING_ORDERS, Strike, take

from gearlab.data import which_gear as W
from gearlab.gearbox import order_table, resolve_gearbox
from gearlab.kinds import detection_which_gear as D
from gearlab.signals import envelope_sync as E
from gearlab.signals import localise as L
from gearlab.signals import which_template as T

PINION, WHEEL = "input pinion 39T (stage 1)", "output gear 61T (stage 1)"
SEED_WEAK = 12  # a take whose weak output-gear strike the whole residual's envelope left unnamed


@pytest.fixture(scope="module")
def box(tmp_path_factory):
    """(the order table, the history of two healthy takes as data.which_gear reads it)."""
    path = tmp_path_factory.mktemp("mill") / "box.toml"
    path.write_text(BOX)
    table = order_table(resolve_gearbox(str(path)))
    return table, W.history_of([W.Take(*take(seed)) for seed in (1, 2)], table)


@pytest.mark.parametrize(("strike", "gear"), [(Strike("input", 0.3, 0.5), PINION), (Strike("output", 0.7, 1.0), WHEEL)])
def test_a_strike_whose_ring_wanders_is_named_on_its_gear_in_the_envelope(box, strike, gear):
    table, hist = box
    t = W.Take(*take(11, strike))
    # the synchronous averages alone: nothing localised, as before the envelope was read
    alone = L.localise(t.revolutions, hist, table, t.first)
    assert alone.named is None, alone.summary()
    found = W.which_gear(t, hist, table, None)
    assert found["named"] == gear and found["seen"] == "envelope", found["summary"]
    assert E.SEEN in found["summary"] and "nothing localised" in found["summary"], found["summary"]
    call = D.call_of(found, [PINION])
    assert call.endswith(gear + T.IN_ENVELOPE), call
    assert call.startswith(D.WATCHED if gear == PINION else D.OTHER), call
    assert D.evidence(found).startswith(D.ENVELOPE + f"{strike.shaft} z "), D.evidence(found)
    # the tooth from the envelope's peak: the strike's tooth, or the next (the ring's decay moves the peak later)
    ev = next(s for s in found["shafts"] if s["shaft"] == strike.shaft)
    teeth = ev["tooth"][gear]
    placed = int(strike.angle * teeth["of"]) + 1
    assert (teeth["tooth"] - placed) % teeth["of"] in (0, 1), (teeth, placed)


def test_healthy_takes_are_not_called_in_the_envelope(box):
    table, hist = box
    for seed in range(20, 26):
        found = W.which_gear(W.Take(*take(seed)), hist, table, None)
        assert found["named"] is None, found["summary"]


def test_the_envelope_s_history_is_saved_and_restored_with_the_averages(box):
    table, hist = box
    saved = E.state(hist.envelope)  # every band's history, those no take was read in too
    assert all(f"envelope{i}_thresholds" in saved for i in range(1, len(E.bands(1.0)))), sorted(saved)
    back = E.restored({**hist.state(), **saved}, table)
    assert len(back.histories) == len(E.bands(1.0)) > 1
    t = W.Take(*take(11, Strike("input", 0.3, 0.5)))
    again = W.which_gear(t, dataclasses.replace(hist, envelope=back), table, None)
    assert again == W.which_gear(t, hist, table, None)
    np.testing.assert_array_equal(back.thresholds(), hist.envelope.thresholds())  # the selection's, restored as read
    assert E.restored(hist.state(), table) is None  # a run stored before the envelope was read: the averages alone


def test_a_run_saved_before_the_bands_were_read_reads_the_whole_residual_as_then(box):
    """A run saved its envelope's history of the whole residual alone, 'envelope_' keys and no bands: restored, every
    take is read in the whole residual's envelope against it, as the run read its own."""
    table, hist = box
    whole = hist.envelope.histories[0]
    then = E.restored({**hist.state(), **{f"envelope_{k}": v for k, v in whole.state().items()}}, table)
    assert len(then.histories) == 1 and then.candidates.tolist() == [[0.0, float("inf")]]
    t = W.Take(*take(11, Strike("input", 0.3, 0.5)))
    found = W.which_gear(t, dataclasses.replace(hist, envelope=then), table, None)
    assert "demodulated in the whole residual" in found["method"], found["method"]
    # the whole residual's envelope localised as before the bands: signals.localise against its own history
    first = t.first % int(table.train_period) + E.sound(len(t.revolutions), table)[0]  # the envelope's first turn
    alone = L.localise(E.envelope(t.revolutions, table), whole, table, first)
    ev = {s["shaft"]: s["z"] for s in found["shafts"]}
    assert ev == {e.shaft: e.z for e in alone.ranking}
    assert found["named"] == PINION, found["summary"]


def test_a_weak_output_gear_strike_is_named_in_the_band_where_its_ring_is_most_impulsive(box):
    """An output-gear strike at 0.3 of the mesh amplitude rings in a few orders about 120.9 under a residual of about
    300 orders: the whole residual's envelope buries it (z under its threshold), the band chosen by the take's
    spectral kurtosis holds the ring and names the output gear."""
    table, hist = box
    t = W.Take(*take(SEED_WEAK, Strike("output", 0.55, 0.3)))
    whole = E.Bank(hist.envelope.candidates[:1], hist.envelope.histories[:1], hist.envelope.kurtosis[:1])
    before = W.which_gear(t, dataclasses.replace(hist, envelope=whole), table, None)
    assert before["named"] is None, before["summary"]
    found = W.which_gear(t, hist, table, None)
    assert found["named"] == WHEEL and found["seen"] == "envelope", found["summary"]
    lo, hi = (float(v) for v in re.search(r"input orders ([\d.]+)-([\d.]+)", found["method"]).groups())
    assert lo < RING_ORDERS < hi and hi - lo < 100, found["method"]


def test_a_take_s_kurtosis_is_its_envelope_s_in_every_band_and_its_band_s_history_alone_is_read(box, monkeypatch):
    """A take's spectral kurtosis, read in every band at the fewest points that hold each band's envelope, is the
    kurtosis of its envelope at POINTS a turn (or at the record's length) to round-off; reading the take reads the
    history of its chosen band alone (the history saved for `gearlab score` holds every band's:
    test_the_envelope_s_history_is_saved_and_restored_with_the_averages)."""
    table, _ = box
    t = W.Take(*take(SEED_WEAK, Strike("output", 0.55, 0.3)))
    spec = E._spectrum(t.revolutions, table)
    candidates = E.bands(W.band([t]))
    each = [E._band(*spec, b)[1] for b in candidates]
    assert max(abs(k) for k in each) > 1.0  # the strike's ring: far from nil in some band
    np.testing.assert_allclose(E.kurtosis(t.revolutions, table, candidates), each, rtol=1e-9, atol=1e-12)
    read, real = [], L.history
    monkeypatch.setattr(L, "history", lambda *a, **k: read.append(1) or real(*a, **k))
    hist = W.history_of([W.Take(*take(seed)) for seed in (1, 2)], table)
    assert len(read) == 2  # the synchronous averages' history and the whole residual's envelope's
    quiet = W.which_gear(W.Take(*take(20)), hist, table, None)
    assert quiet["named"] is None and len(read) == 3  # a healthy take: the band it is read in alone
    found = W.which_gear(t, hist, table, None)
    assert found["seen"] == "envelope" and "input orders" in found["method"], found["summary"]
    # over its band's threshold: read against every band's (envelope_sync.Bank.thresholds), each band's history once
    assert E.SELECTED in found["method"] and len(read) == 1 + len(candidates), found["method"]


def test_a_take_s_kurtosis_in_the_whole_residual_is_read_without_its_envelope_s_low_pass(box, monkeypatch):
    """The whole residual's kurtosis needs its squared envelope's two means alone: _kurtosis makes no low-pass of it
    (an rfft and an irfft of the record's length, half of that band's cost), and reads the same value as _band."""
    table, _ = box
    spec = E._spectrum(W.Take(*take(SEED_WEAK, Strike("output", 0.55, 0.3))).revolutions, table)
    candidates = E.bands(0.45 * spec[2])
    whole = E._band(*spec, candidates[0])[1]
    made, real = [], E.rfft
    monkeypatch.setattr(E, "rfft", lambda x: made.append(np.size(x)) or real(x))
    assert E._kurtosis(*spec, candidates)[0] == whole
    assert made == []  # before: one, of the record's kept revolutions' length
    assert np.shape(E._band(*spec, candidates[0])[0]) == (spec[3][1] - spec[3][0], E.POINTS) and len(made) == 1


def test_a_history_record_s_whole_residual_envelope_is_made_once_for_its_kurtosis_and_its_band(box, monkeypatch):
    """A history reads every record's whole-residual envelope (its first band, read at once) and that band's
    kurtosis: one squared envelope a record serves both, and the bank is the one each band's own _band reads."""
    table, _ = box
    records = [W.Take(*take(seed)).revolutions for seed in (1, 2)]
    made, real = [], E._squared
    monkeypatch.setattr(E, "_squared", lambda *a: made.append(a[-1]) or real(*a))
    bank = E.history(records, table)
    assert sum(1 for band in made if np.isinf(band[1])) == len(records)  # before: two a record
    specs = [E._spectrum(r, table) for r in records]
    kurt = np.mean([[E._band(*s, b)[1] for b in bank.candidates] for s in specs], axis=0)
    np.testing.assert_allclose(bank.kurtosis, kurt, rtol=1e-9, atol=1e-12)
    assert bank.kurtosis[0] == np.mean([E._band(*s, bank.candidates[0])[1] for s in specs])


def test_a_synchronous_fault_is_named_as_before(box):
    """A chipped 24T pinion of the simulated 21/63 + 24/56 reducer: the synchronous averages name it, and the
    envelope changes nothing of what they say."""
    from which_gear_takes import REDUCER, reducer_take

    table = order_table(resolve_gearbox(str(REDUCER)))
    made = (reducer_take([], seed, 25.0, 20_000.0) for seed in (3, 4))
    takes = [W.Take(revs, first, 25.0, 20_000.0) for _, revs, first in made]
    hist = W.history_of(takes, table)
    assert hist.envelope is not None
    chip = {"name": "chip", "gear": "intermediate pinion", "tooth": 5, "step": 16}
    _, revs, first = reducer_take([chip], 5, 25.0, 20_000.0)
    t = W.Take(revs, first, 25.0, 20_000.0)
    found = W.which_gear(t, hist, table, None)
    assert found == W.which_gear(t, dataclasses.replace(hist, envelope=None), table, None)
    assert found["named"] is not None and "24T" in found["named"] and "seen" not in found, found["summary"]


def test_the_envelope_names_nothing_where_another_shaft_s_average_is_near_its_threshold():
    """A synchronous change under its threshold on one shaft leaks into another shaft's envelope: not named there."""

    def ranked(other_z: float) -> L.Localisation:
        shafts = (("input", 0.2), ("output", other_z))
        ranking = tuple(L.ShaftEvidence(s, (), z, 1.0, z, 2.7, 5, False, s) for s, z in shafts)
        return L.Localisation("", ranking, None, None)

    assert E.elsewhere(ranked(0.9 * 2.7), "input")
    assert not E.elsewhere(ranked(0.5 * 2.7), "input")
    assert not E.elsewhere(ranked(0.9 * 2.7), "output")  # the envelope's own shaft: its average may read it too


def test_a_bearing_s_strikes_at_no_shaft_order_are_not_named_a_gear_in_the_envelope():
    # the rig at 50 Hz, two healthy history takes, a take of strikes at input order 4.208 (development seed 17 of the
    # non-synchronous sensitivity check): over the non-synchronous threshold (13.9 / 5.5), and the envelope, lifted at
    # every order by the strikes, named the output gear 80T first ('other damage: output gear 80T (in the envelope:
    # ...)'); a strike at no shaft's order is a bearing's: called non-synchronous, the envelope set aside
    from test_nonsync import NON_SYNC, strikes
    from which_gear_takes import cut, rig_condition

    from gearlab.data.simulated import simulated_record
    from gearlab.data.spec import dataset_preset

    files = {"h1": ("history", "healthy", [], 1700), "h2": ("history", "healthy", [], 1701)}
    files["ok"] = ("test", "healthy", [], 1704)
    cond, _ = rig_condition(files, 50.0, 80)
    rec = simulated_record([], speed_hz=50.0, revolutions=80, snr_db=30.0, seed=1711)
    cond["raw"]["race"] = (cut(strikes(rec, 4.208, 0.015, 0.3, seed=1721)), 0)
    cond["test"].append(
        (dataclasses.replace(cond["test"][0][0], path="race", resolved="race", label="outer race"), None)
    )
    found = D.localise_target(dataset_preset("phm09-30"), {"50 Hz": cond})["records"]["race"]
    assert found["nonsync"]["changed"] and found["call"].startswith(NON_SYNC), found["call"]
    assert found.get("seen") != "envelope" and "in the envelope" not in found["call"], found["call"]


def _lines_one_product_a_line(revs: np.ndarray, table) -> np.ndarray:
    """less_lines_between_bins as the record's full-length product of each line's cosine and sine, least squares over
    them (one line after another, in the same order)."""
    count, points = revs.shape
    y = revs.reshape(-1) - revs.mean()
    power = np.abs(np.fft.rfft(y)) ** 2
    angle = (np.arange(count)[:, None] + np.arange(points)[None, :] / points).reshape(-1)  # in turns
    for stage in table.stages:
        for o in E._line_orders(stage.mesh, stage.pinion_shaft_order, stage.wheel_shaft_order, points):
            if o <= 0 or o * count >= power.size - 1 or power[round(o * count)] < E.STRONG * power.sum():
                continue
            c, s = np.cos(2 * np.pi * o * angle), np.sin(2 * np.pi * o * angle)
            a, b = np.linalg.lstsq(np.column_stack([c, s]), y, rcond=None)[0]
            y = y - a * c - b * s
    return y.reshape(count, points)


def test_the_mesh_lines_between_bins_go_whole_from_products_of_a_turn_s_length(tmp_path):
    # each strong line was fitted on its full-length product with the record (cos and sin of R x P points, its normal
    # matrix and its removal over them: a 89 x 4096 take's 10 lines 0.6 s of CPU, an inspect --history call's largest
    # cost, at 7.5 times the record's memory); the same fit from products of R and P points is the same to round-off
    import tracemalloc

    path = tmp_path / "box.toml"
    path.write_text(BOX)
    table = order_table(resolve_gearbox(str(path)))
    rng = np.random.default_rng(3)
    count, points = 41, 2048
    turns = (np.arange(count)[:, None] + np.arange(points)[None, :] / points).reshape(-1)
    lines = [(39.0, 1.0), (39 + 39 / 61, 0.3), (78.0 - 2 * 39 / 61, 0.2), (1.0, 0.4), (39 / 61, 0.5)]  # between bins
    x = sum(a * np.cos(2 * np.pi * o * turns + rng.uniform(0, 6.3)) for o, a in lines) + rng.normal(0, 0.05, turns.size)
    revs = x.reshape(count, points)
    want = _lines_one_product_a_line(revs, table)
    tracemalloc.start()
    got = E.less_lines_between_bins(revs, table)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert np.std(want) < 0.06 < np.std(revs), "the lines went, the noise is left"
    assert np.max(np.abs(got - want)) < 1e-12 * np.max(np.abs(revs)), np.max(np.abs(got - want))
    assert peak < 4 * revs.nbytes, peak / revs.nbytes  # no full-length product a line (7.5 record sizes)
    # the lines' orders (exact fractions, a set each harmonic) are made once for every take of one gearbox and length
    made = E._line_orders.cache_info().misses
    E.less_lines_between_bins(revs * 1.5, table)
    assert E._line_orders.cache_info().misses == made
