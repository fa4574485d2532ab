"""Outside user EJ (issue 39, round 20): a two-stage 33/97 + 26/119 mixer drive at 40 Hz, its takes made here with
numpy (each shaft's lines, each mesh's harmonics modulated by both its shafts, a tooth's dip once a turn of its
shaft, noise, a once-per-turn tacho), exported as real tools write them: Excel's CSV (a UTF-8 BOM, CRLF, a quoted
German header with units in brackets, trailing empty columns), a DAQ's HDF5 (tacho and vibration in one 2-D
dataset, the channels' names and units in its attributes), a stereo WAV with the tacho in channel 2."""

from __future__ import annotations

import json

import numpy as np
import pytest

from gearlab.inspect import InspectOptions, inspect_record

FS = 25600.0
STAGES = ((33, 97), (26, 119))
BOX = (
    '[gearbox]\nname = "mixer"\n[operation]\nspeed = "40 Hz"\nload = "60 N*m"\n'
    '[[stages]]\nmodule = "2 mm"\nface_width = "20 mm"\npinion = { z = 33, bore = "25 mm" }\n'
    'wheel = { z = 97, bore = "35 mm" }\n'
    '[[stages]]\nmodule = "3 mm"\nface_width = "30 mm"\npinion = { z = 26, bore = "35 mm" }\n'
    'wheel = { z = 119, bore = "60 mm" }\n[sensor]\nnear = "input"\ntacho = "input"\n'
)


def _shaft(seconds: float, seed: int) -> np.ndarray:
    """The input shaft's angle per sample (rad): 40 Hz swinging 0.2 %, from any turn and angle."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * FS)) / FS
    f = 40.0 * (1 + 0.002 * np.sin(2 * np.pi * 0.23 * t + rng.uniform(0, 6)))
    return 2 * np.pi * (np.cumsum(f) / FS + rng.integers(0, 1000)) + rng.uniform(0, 6)


def _take(th: np.ndarray, seed: int) -> np.ndarray:
    """m/s²: every shaft's orders 1-2, each mesh's harmonics 1-3 modulated by both its shafts, noise 24 dB down."""
    rng = np.random.default_rng(seed + 101)
    turns = np.cumprod([1.0] + [p / w for p, w in STAGES])
    x = sum(0.25 * np.cos(k * th * r + 0.5 * k + i) for i, r in enumerate(turns) for k in (1, 2))
    for s, (zp, _) in enumerate(STAGES):
        a, b = th * turns[s], th * turns[s + 1]
        for h, amp in ((1, 3.0), (2, 1.3), (3, 0.5)):
            am = 1 + 0.07 * np.cos(a + 0.2 * h) + 0.05 * np.cos(b + 0.9 * h)
            x = x + amp / (s + 1) * am * np.cos(h * (zp * a + 0.03 * np.cos(a + 0.4) + 0.02 * np.cos(b)) + 0.5 * h * s)
    return x + rng.normal(0, 0.06 * np.std(x), th.size)


def _tacho(th: np.ndarray) -> np.ndarray:
    return np.where(np.mod(th, 2 * np.pi) < 0.25, 5.0, 0.0)


@pytest.fixture(scope="module")
def box(tmp_path_factory):
    from gearlab.gearbox import load_gearbox

    path = tmp_path_factory.mktemp("mixer") / "box.toml"
    path.write_text(BOX)
    return load_gearbox(path)


def test_a_daq_s_hdf5_names_the_columns_of_its_2d_dataset_in_an_attribute(tmp_path, box):
    # a DAQ's export: one (N, 2) dataset 'data' of [tacho, accel], its attributes channel_names = [Tacho, Accel] and
    # units = [V, m/s^2]: `--vibration Accel` was refused ('no vibration channel 'Accel'; the file has: data') and
    # 'data[1]' read with 'the file's unit '[b'V' b'm/s^2']' is not read'
    h5py = pytest.importorskip("h5py")
    th = _shaft(2.0, 1)
    acc = _take(th, 1)
    path = tmp_path / "take.h5"
    with h5py.File(path, "w") as f:
        data = f.create_dataset("data", data=np.c_[_tacho(th), acc].astype("float32"))
        data.attrs["channel_names"] = np.array([b"Tacho", b"Accel"])
        data.attrs["units"] = np.array([b"V", b"m/s^2"])
        data.attrs["sample_rate"] = FS
    got = inspect_record(str(path), box, InspectOptions("Accel", tacho="Tacho"))
    assert got["units"].startswith("m/s²"), got["units"]
    assert got["rms"] == pytest.approx(np.std(acc), rel=0.02)
    assert "matches" in got["verdict"], got["verdict"]
    assert got["speed"]["mean_hz"] == pytest.approx(40.0, rel=0.005)
    by_column = inspect_record(str(path), box, InspectOptions("data[1]", tacho="data[0]"))
    assert by_column["units"].startswith("m/s²"), by_column["units"]  # the column's own unit


def _excel(path, th, acc) -> None:
    """Excel's 'CSV UTF-8' of a sheet whose two columns right of the data were once used: a BOM, CRLF line ends, the
    header quoted, every row ending in two empty cells."""
    lines = ['"Zeit [s]","Beschleunigung [m/s²]","Tacho [V]",,']
    lines += [f"{i / FS:.6f},{v:.6g},{p:g},," for i, (v, p) in enumerate(zip(acc, _tacho(th)))]
    path.write_bytes("\ufeff".encode() + "\r\n".join(lines).encode() + b"\r\n")


def test_an_excel_csv_s_trailing_empty_columns_are_no_channels(tmp_path, box):
    # the take read right, but listed 'channels: Beschleunigung [m/s²], Tacho [V], ' (an empty one: the second empty
    # column; one trailing separator was dropped) in inspect and in validate's 'the file has: ...'
    from gearlab.data.readers.headers import HEADERS

    th = _shaft(1.5, 3)
    acc = _take(th, 3)
    path = tmp_path / "take.csv"
    _excel(path, th, acc)
    got = inspect_record(str(path), box, InspectOptions("Beschleunigung [m/s²]", tacho="Tacho [V]"))
    assert got["channels"] == ["Beschleunigung [m/s²]", "Tacho [V]"], got["channels"]
    assert got["rms"] == pytest.approx(np.std(acc), rel=0.02) and "matches" in got["verdict"], got["verdict"]
    assert HEADERS["CSV"](path).channels == ["Zeit [s]", "Beschleunigung [m/s²]", "Tacho [V]"]


# --- `gearlab score` from a cron-like loop: alarm, no alarm, error -------------------------------------------------


def _row(file: str, decision: str, **more) -> dict:
    """One of `gearlab score`'s rows (kinds.detection_scoring.score) as its JSON gives it."""
    return {"file": file, "method": "fm4", "unit": "record30", "decision": decision, **more}


@pytest.mark.parametrize(
    ("decisions", "code"),
    [
        (["healthy", "healthy"], 0),
        (["healthy", "fault"], 1),
        (["healthy", "other damage: output gear 119T (stage 2)"], 1),
        (["healthy", "fault, gear not determined: 5 turns of the output shaft, 8 needed"], 1),
    ],
)
def test_gearlab_score_exit_code_tells_a_script_whether_a_take_was_called(cli, monkeypatch, decisions, code):
    # a weekly cron job `gearlab score RUN week.wav --json || mail ...` got exit 0 for a chipped take and a healthy
    # one alike (2 only for bad input): a script had to parse the rows. With --exit-code: 1 where any take is called
    import gearlab.notebook

    rows = [_row(f"week{i}.wav", d) for i, d in enumerate(decisions)]
    monkeypatch.setattr(gearlab.notebook, "score_recordings", lambda *a, **k: rows)
    got, out, err = cli("score", "run", "week0.wav", "week1.wav", "--json", "--exit-code")
    assert got == code, err
    assert [r["decision"] for r in json.loads(out)] == decisions  # the rows printed whatever the code
    plain, _, err = cli("score", "run", "week0.wav", "week1.wav", "--json")
    assert plain == 0, err  # without it, as before: 0 where every take was scored


def test_gearlab_score_exit_code_is_2_where_a_take_was_not_scored_even_beside_an_alarm(cli, monkeypatch):
    import gearlab.notebook

    rows = [_row("week1.wav", "fault"), _row("week2.wav", "not scored", method=None, unit=None, skipped="too slow")]
    monkeypatch.setattr(gearlab.notebook, "score_recordings", lambda *a, **k: rows)
    got, _, err = cli("score", "run", "week1.wav", "week2.wav", "--json", "--exit-code")
    assert got == 2 and "1 of 2 takes not scored" in err, err


# --- a long take: read once --------------------------------------------------------------------------------------


def test_inspect_reads_a_named_vibration_s_file_once(tmp_path, box, monkeypatch):
    # a 60 s take at 51.2 kHz (3.1 M rows, a 69 MB CSV): `gearlab inspect --vibration acc` parsed the whole file twice,
    # once only to list its channels (2 x 4 s of 55 s); a named vibration needs no listing
    import gearlab.inspect

    th = _shaft(1.0, 2)
    path = tmp_path / "take.csv"
    rows = "\n".join(f"{v:.6g},{p:g}" for v, p in zip(_take(th, 2), _tacho(th)))
    path.write_text(f"# fs = {FS:g}\nacc,tacho\n{rows}\n")
    reads = []
    real = gearlab.inspect.read_contents
    monkeypatch.setattr(gearlab.inspect, "read_contents", lambda *a, **k: reads.append(a[1]) or real(*a, **k))
    got = inspect_record(str(path), box, InspectOptions("acc", tacho="tacho"))
    assert reads == [["acc", "tacho"]], reads
    assert got["channels"] == ["acc", "tacho"], got["channels"]
    reads.clear()
    with pytest.raises(Exception, match="which channel is the vibration"):  # unnamed: listed first, as before
        inspect_record(str(path), box, InspectOptions(None))
    assert reads == [[]], reads


def test_a_quoted_header_leaves_the_rows_to_numpy_s_reader(tmp_path, monkeypatch):
    # a DAQ's export quoting its column names ('"Zeit [s]","Beschleunigung [m/s²]"') sent every row of the file
    # through Python's csv module: a 1 M-row take in 5.3 s of CPU and 624 MB, against 0.35 s for the same rows unquoted
    from gearlab.data.readers import csv as reader
    from gearlab.data.recordings import read_contents

    th = _shaft(0.5, 4)
    acc = _take(th, 4)
    path = tmp_path / "take.csv"
    rows = "\r\n".join(f"{i / FS:.6f},{v:.6g},{p:g}" for i, (v, p) in enumerate(zip(acc, _tacho(th))))
    path.write_text('"Zeit [s]","Beschleunigung [m/s²]","Tacho [V]"\r\n"s","m/s²","V"\r\n' + rows + "\r\n")
    parsed = []
    block = reader.numeric_block
    monkeypatch.setattr(reader, "numeric_block", lambda lines, *a: parsed.append(len(lines)) or block(lines, *a))
    contents, _ = read_contents(path, ["Beschleunigung [m/s²]", "Tacho [V]"])
    assert parsed == [acc.size], parsed
    assert np.allclose(contents.found["Beschleunigung [m/s²]"], acc, rtol=1e-5, atol=1e-5)
    parsed.clear()
    _excel(path, th, acc)  # and every row ending in two empty cells: 5.6 s and 625 MB for 1 M rows, now 0.5 s
    contents, _ = read_contents(path, ["Beschleunigung [m/s²]", "Tacho [V]"])
    assert parsed == [acc.size], parsed
    assert contents.available == ["Zeit [s]", "Beschleunigung [m/s²]", "Tacho [V]"], contents.available
    assert np.allclose(contents.found["Beschleunigung [m/s²]"], acc, rtol=1e-5, atol=1e-5)


@pytest.mark.slow
def test_a_long_csv_take_is_read_in_under_eight_times_its_size(tmp_path):
    # a 60 s take at 51.2 kHz in a 69 MB CSV: its rows were joined into one text and copied into a StringIO for
    # numpy's reader, a peak of 10.2 times the file's size (840 MB resident); the lines are now read as they are (5.9)
    import tracemalloc

    from gearlab.data.recordings import read_contents

    n = 1_000_000
    rng = np.random.default_rng(0)
    path = tmp_path / "long.csv"
    table = np.c_[np.arange(n) / 51200.0, rng.normal(size=n), rng.normal(size=n)]
    np.savetxt(path, table, fmt=["%.7f", "%.6g", "%.6g"], delimiter=",", header="time_s,acc,tacho", comments="")
    tracemalloc.start()
    try:
        contents, _ = read_contents(path, ["acc", "tacho"])
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert contents.found["acc"].size == n
    assert peak < 8 * path.stat().st_size, peak / path.stat().st_size


# --- the TUI: the score trend's chart --------------------------------------------------------------------------


@pytest.mark.parametrize("width", [160, 80])
def test_the_tui_s_trend_chart_keeps_a_heading_wider_than_the_chart(width):
    # the mixer's run after four takes scored, in `gearlab tui` at 160 columns, Results, `n`: the trend chart had no
    # heading at all (plotext draws none wider than its plot): not the chart's place ('chart 2/2, n next'), nor the
    # line that says which take was first called, by which methods, on which gear and tooth
    from gearlab.charts import Chart, Curve
    from gearlab.tui.widgets import ChartView

    first = (
        "40 Hz, record30: first called on take 1 (next.wav) by fm4, na4, likelihood_ratio, matched_filter; its change "
        "on input pinion 33T (stage 1), tooth 6 of 33; not called again on take 2 (test_ok.wav) by fm4"
    )
    title = f"40 Hz: scored records, record30\n{first}\nrecords: 1 next.wav, 2 test_ok.wav"
    chart = Chart(title, "record scored (in order)", "score less threshold", (Curve("fm4", [1, 2], [0.3, -0.1]),))
    drawn = ChartView()._draw(chart, list(chart.curves), f"chart 2/2, n next: {title}", width).plain
    words = " ".join(drawn.split())
    assert "chart 2/2, n next: 40 Hz: scored records" in words, drawn[:400]
    assert first in words, drawn[:800]
    assert max(len(line) for line in drawn.splitlines()) <= width
