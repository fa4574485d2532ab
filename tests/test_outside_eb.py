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


# --- which gear on the intermediate shaft of a 42/63 + 23/71 box heard at its output bearing --------------------

MIXER = ((42, 63), (23, 71))  # DY's mixer drive at 1440 rpm: the 63T wheel and the 23T pinion on one shaft
MIXER_FS = 25600.0


def _mixer_take(seed: int, stage: int | None = None, seconds: float = 4.0) -> tuple[np.ndarray, np.ndarray]:
    """(m/s² at the output bearing, a once-per-turn input tacho): each mesh's harmonics 1-3 modulated by both its
    shafts, stage 1's heard at 0.3x stage 2's; *stage*: a tooth of the intermediate shaft's gear in that stage (0:
    the 63T wheel, 1: the 23T pinion) dips its own mesh while in mesh, a pitch of its gear wide, once a turn."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * MIXER_FS)) / MIXER_FS
    f = 24.0 * (1 + 0.002 * np.sin(2 * np.pi * 0.29 * t + rng.uniform(0, 6)))
    th = 2 * np.pi * (np.cumsum(f) / MIXER_FS + rng.integers(0, 1000)) + rng.uniform(0, 6)
    turns = np.cumprod([1.0] + [p / w for p, w in MIXER])
    weight = (0.3, 1.0)
    x = sum(0.3 * np.cos(k * th * r + 0.7 * k + i) for i, r in enumerate(turns) for k in (1, 2))
    for s, (zp, _) in enumerate(MIXER):
        a, b = th * turns[s], th * turns[s + 1]
        for h, amp in ((1, 3.0), (2, 1.4), (3, 0.6)):
            am = 1 + 0.08 * np.cos(a + 0.3 * h) + 0.06 * np.cos(b + 1.1 * h)
            x = x + weight[s] * amp * am * np.cos(h * (zp * a + 0.03 * np.cos(a + 0.7)) + 0.4 * h * s)
    if stage is not None:
        teeth = MIXER[0][1] if stage == 0 else MIXER[1][0]
        d = np.angle(np.exp(1j * (th * turns[1] - 2.0)))  # from the damaged tooth, in the intermediate shaft's turn
        win = np.exp(-0.5 * (d / (0.6 * 2 * np.pi / teeth)) ** 2)
        zp, a = MIXER[stage][0], th * turns[stage]
        x = x - 0.3 * win * 3.0 * weight[stage] * np.cos(zp * a + 0.4 * stage)  # its own mesh's line, lowered
    return x + rng.normal(0, 0.1 * np.std(x), th.size), np.where(np.mod(th, 2 * np.pi) < 0.3, 5.0, 0.0)


@pytest.fixture(scope="module")
def mixer(tmp_path_factory):
    from gearlab.gearbox import load_gearbox

    folder = tmp_path_factory.mktemp("mixer")
    (folder / "box.toml").write_text(
        '[gearbox]\nname = "mixer"\n[operation]\nspeed = "1440 rpm"\nload = "60 N*m"\n'
        '[[stages]]\nmodule = "2 mm"\nface_width = "20 mm"\npinion = { z = 42, bore = "30 mm" }\n'
        'wheel = { z = 63, bore = "40 mm" }\n[[stages]]\nmodule = "3 mm"\nface_width = "25 mm"\n'
        'pinion = { z = 23, bore = "35 mm" }\nwheel = { z = 71, bore = "50 mm" }\n'
        '[sensor]\nnear = "output"\ndirection = "radial"\ntacho = "input"\n'
    )
    history = []
    for seed in (100, 101, 102):
        acc, tacho = _mixer_take(seed)
        np.savez(folder / f"hist{seed}.npz", acc=acc, tach=tacho, fs=MIXER_FS)
        history.append(str(folder / f"hist{seed}.npz"))
    return folder, load_gearbox(folder / "box.toml"), history


def test_a_fault_on_a_shaft_s_gear_is_named_by_its_own_mesh_s_sidebands(mixer):
    # DY's 42/63 + 23/71 box heard at its output bearing: a 23T pinion's fault, on the mesh the sensor hears best, was
    # named the 63T wheel's on 2 of 3 takes and both on 1. The record's own sidebands stood about the 23T's mesh (comb
    # 2.8 sds) and not the 63T's (-0.6), under COMB_Z, so the simulated events' phases, of another fault form and
    # structure (10.9 dB apart), decided: here the 63T named
    from gearlab.inspect_history import localisation

    folder, box, history = mixer
    acc, tacho = _mixer_take(203, 1)
    np.savez(folder / "take.npz", acc=acc, tach=tacho, fs=MIXER_FS)
    loc = localisation(str(folder / "take.npz"), history, box, InspectOptions("acc", tacho="tach"))
    assert loc["call"].startswith("localised change: intermediate pinion 23T (stage 2)"), loc["call"]
    assert "63T" not in loc["call"].split(" (by")[0], loc["call"]
