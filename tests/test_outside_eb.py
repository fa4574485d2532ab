"""What outside user DY left (issue 39): a mains-hum take's words in the verdict; a unit stated beside the numbers
(a MAT v7.3 struct's 'units', a whitespace table's '# units: g'), read one way by every reader."""

from __future__ import annotations

import numpy as np
import pytest

from gearlab.data.readers.base import stated_units
from gearlab.data.readers.matlab import _read_mat
from gearlab.inspect import InspectOptions, inspect_record
from gearlab.kinds.detection_verdict import left_out

HUM_CALL = "not a gear fault: mains hum at 50.0 Hz (order 2.08; the 50 Hz mains: electrical pickup)"


def _summary(calls: dict) -> dict:
    return {"which_gear": {"calls": [{"condition": "24 Hz", "unit": "record30", "left_out": calls}]}}


def test_verdict_says_a_mains_hum_take_is_no_gear_fault_not_other_damage():
    summary = _summary({"hum.csv": HUM_CALL, "out71.csv": "other damage: output gear 71T (stage 2)"})
    words = left_out(summary, "24 Hz", "record30")
    assert "as other damage: out71.csv (other damage: output gear 71T (stage 2))" in words
    assert "hum.csv" not in words.split("as other damage:")[1].split(";")[0]
    assert f"as no gear fault: hum.csv ({HUM_CALL})" in words
    # the hum alone: no "other damage" said at all
    alone = left_out(_summary({"hum.csv": HUM_CALL}), "24 Hz", "record30")
    assert "other damage" not in alone and alone.startswith("; left out of its AUC and false alarms as no gear fault")


# --- a unit stated beside the numbers: one reading for every reader ----------------------------------------------

G = 9.80665
FS = 20000.0


def _acc(seconds: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """(a 41T mesh at 29 Hz with noise in m/s², a once-per-turn tacho)."""
    th = 2 * np.pi * 29.0 * np.arange(int(seconds * FS)) / FS
    acc = 3.0 * np.cos(41 * th) + np.random.default_rng(5).normal(0, 0.2, th.size)
    return acc, np.where(np.mod(th, 2 * np.pi) < 0.3, 5.0, 0.0)


@pytest.mark.parametrize("field", ["units", "data_units"])
def test_a_mat73_struct_s_text_units_field_is_the_unit_of_its_data(tmp_path, field):
    # MATLAB -v7.3's rec = struct('fs', 20000, 'data', acc, 'units', 'g'): v5's units were read (matlab.said_units),
    # v7.3's data taken as m/s², 9.8 times too small
    from tests.test_importers import write_mat73

    acc, _ = _acc()
    path = write_mat73(tmp_path / "take.mat", {"rec/fs": FS, "rec/data": acc / G, f"rec/{field}": "g"})
    contents = _read_mat(path, ["rec/data"])
    assert contents.units == {"rec/data": "g"}, contents.units
    listed = _read_mat(path, []).available  # what inspect lists: its units no channel, as v5's
    assert listed == ["rec/data", "rec/fs"], listed


def test_a_units_comment_above_a_whitespace_table_is_the_unit_of_its_values(tmp_path):
    # '# units: g' above a blank-separated table was not read (a CSV's is: csv.file_units), its values taken as m/s²
    acc, tacho = _acc()
    path = tmp_path / "take.txt"
    rows = "\n".join(f"{v:.6g} {p:g}" for v, p in zip(acc / G, tacho))
    path.write_text(f"# fs = {FS:g}\n# units: g\nacc tach\n{rows}\n")
    got = inspect_record(str(path), None, InspectOptions("acc", tacho="tach"))
    assert "9.80665" in got["units"], got["units"]
    assert got["rms"] == pytest.approx(np.std(acc), rel=0.02)


def test_every_reader_reads_a_stated_unit_one_way():
    # a '<channel>_unit' entry stands over its group's 'units'; an empty text states nothing
    texts = {"rec/units": "g", "rec/acc_unit": "m/s^2", "units": " "}
    assert stated_units(texts, ["rec/acc", "rec/tach", "top"]) == {"rec/acc": "m/s^2", "rec/tach": "g"}


# --- a reversed take without a tacho -------------------------------------------------------------------------------


def _revolutions(sign: float, seed: int, points: int = 1024, rows: int = 20) -> tuple[np.ndarray, np.ndarray]:
    """(the history's mean revolution: a 23T mesh's harmonics 1-3 and the shaft's orders 1-2; a take's *rows*
    revolutions of it times *sign*, started at a random angle as a take without a tacho is, with noise)."""
    th = 2 * np.pi * np.arange(points) / points
    ref = 0.3 * np.cos(th + 0.7) + 0.3 * np.cos(2 * th + 1.4)
    ref += sum(a * np.cos(h * 23 * th + 0.4 * h) for h, a in ((1, 3.0), (2, 1.4), (3, 0.6)))
    rng = np.random.default_rng(seed)
    revs = sign * np.roll(ref, int(rng.integers(points))) + rng.normal(0, 0.5, (rows, points))
    return ref, revs


def test_a_reversed_take_without_a_tacho_is_warned_of():
    # aligned by correlation (its largest) a reversed take's mesh lines fit half a pitch off: read at that turn it
    # correlates positively and nothing was said (polarity_line was read with a tacho's marks only)
    from gearlab.parts.measured import aligned
    from gearlab.signals.checks import polarity_line

    ref, revs = _revolutions(-1.0, 3)
    _, turned = aligned(ref, revs, None, 1)
    assert polarity_line(turned, ref) == ""  # at the turn alignment chose: hidden
    words = polarity_line(turned, ref, any_turn=True)
    assert words.startswith("polarity reversed against its history's (their synchronous averages correlate -"), words
    assert float(words.split("correlate ")[1].split(",")[0]) < -0.95, words
    ref, revs = _revolutions(1.0, 4)  # the same take wired right: nothing said
    assert polarity_line(aligned(ref, revs, None, 1)[1], ref, any_turn=True) == ""
