"""Zipped whitespace-separated text records (the PHM 2009 format) through the one import path
(gearlab.data.readers.text, gearlab.data.recordings.cut_recording) and their calibration and tacho
marks (gearlab.data.textzip): columns, sensitivity, N-pulse tacho, streaming; synthetic files made
here, the real PHM 2009 records when present."""

import tracemalloc
import zipfile
from pathlib import Path

import numpy as np
import pytest
from textrecords import FS, PULSES, SENSITIVITY, SPEED, record, signals, text, write_zip

from gearlab.data.readers import text as text_reader
from gearlab.data.readers.text import read_columns
from gearlab.data.recordings import cut_recording
from gearlab.data.textzip import align_to, parse_sensitivity
from gearlab.errors import GearlabInputError

PHM09 = Path(__file__).resolve().parents[2] / "shared" / "data" / "phm09"


@pytest.mark.parametrize(
    "given, expected",
    [
        ("10 mV/g", 0.01 / 9.80665),
        ("0.01 V/g", 0.01 / 9.80665),
        ("1.02 mV/(m/s^2)", 1.02e-3),
        (0.5, 0.5),
        ("100 mV / g", 0.1 / 9.80665),
    ],
)
def test_sensitivity_reads_g_as_standard_gravity(given, expected):
    assert parse_sensitivity(given, "here") == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize(
    "bad, message",
    [
        ("10 mV", "wrong dimension.*10 mV/g"),
        ("10 mV/kg", "wrong dimension"),
        (-1.0, "positive"),
        ("ten", "cannot read"),
    ],
)
def test_bad_sensitivity_is_refused_with_where(bad, message):
    with pytest.raises(GearlabInputError, match=f"here.*{message}"):
        parse_sensitivity(bad, "here")


def test_columns_by_index_and_by_header_name(tmp_path):
    vib, tacho = signals(revolutions=3)
    plain = write_zip(tmp_path / "a.zip", text(vib, tacho))
    named = write_zip(tmp_path / "b.zip", text(vib, tacho, header="acc_in acc_out tacho"))
    by_index, header, width = read_columns(plain, [0, "2"])
    assert header is None and width == 3
    by_name, header, _ = read_columns(named, ["acc_in", "tacho"])
    assert header == ["acc_in", "acc_out", "tacho"]
    assert np.array_equal(by_index[0], by_name["acc_in"])
    assert np.array_equal(by_index["2"], tacho)
    assert np.allclose(by_index[0] / SENSITIVITY, vib, rtol=1e-6, atol=1e-9)
    # the text itself, not zipped, reads the same
    (tmp_path / "c.txt").write_bytes(text(vib, tacho))
    assert np.array_equal(read_columns(tmp_path / "c.txt", [0])[0][0], by_index[0])


@pytest.mark.parametrize(
    "header, sep",
    [('"t [s]",Accel (V),"tacho, V"', ","), ("t [s];Accel (V);tacho V", ";"), ("t\tAccel (V)\ttacho", "\t")],
)
def test_zipped_delimited_text_reads_as_the_csv_reader_does(tmp_path, monkeypatch, header, sep):
    """A zipped CSV export (commas, semicolons with decimal commas, tabs; names with blanks):
    the streamed columns equal the plain CSV reader's, at any block size."""
    from gearlab.data.readers.csv import _read_csv

    vib, tacho = signals(revolutions=2)
    t = np.arange(vib.size) / FS
    rows = [sep.join(f"{v:.6f}" for v in row) for row in zip(t, vib, tacho)]
    if sep == ";":
        rows = [r.replace(".", ",") for r in rows]  # a European export's decimal commas
    data = (header + "\n" + "\n".join(rows) + "\n").encode()
    (tmp_path / "plain.csv").write_bytes(data)
    names = [n.strip('"') for n in __import__("csv").reader([header], delimiter=sep).__next__()]
    expected = _read_csv(tmp_path / "plain.csv", names).found
    for size in (9, 4093, text_reader.CHUNK_BYTES):
        monkeypatch.setattr(text_reader, "CHUNK_BYTES", size)
        got, head, width = read_columns(write_zip(tmp_path / f"r{size}.zip", data), names)
        assert head == names and width == 3
        assert all(np.array_equal(got[n], expected[n]) for n in names)
    assert np.allclose(got[names[2]], np.round(tacho, 6))


def test_blocks_split_anywhere_give_the_same_columns(tmp_path, monkeypatch):
    """Lines cut by the block boundary, comments, blank and CRLF lines: the same numbers."""
    vib, tacho = signals(revolutions=2)
    data = text(vib, tacho)
    whole = read_columns(write_zip(tmp_path / "a.zip", data), [0, 1, 2])[0]
    messy = b"# a comment\r\n\r\n" + data.replace(b"\n", b"\r\n", 50) + b"\n\n"
    for size in (7, 100, 4093):
        monkeypatch.setattr(text_reader, "CHUNK_BYTES", size)
        got = read_columns(write_zip(tmp_path / f"m{size}.zip", messy), [0, 1, 2])[0]
        assert all(np.array_equal(got[c], whole[c]) for c in whole)


def test_streaming_needs_about_the_kept_columns_not_the_text(tmp_path):
    vib, tacho = signals(revolutions=400)  # 204 800 rows, 8.8 MB of text
    data = text(vib, tacho)
    path = write_zip(tmp_path / "big.zip", data)
    tracemalloc.start()
    try:
        cols = read_columns(path, [0])[0]
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    kept = cols[0].nbytes
    assert peak < 0.8 * len(data)  # the whole text is never held, let alone parsed at once
    assert peak < 3 * kept + 12 * text_reader.CHUNK_BYTES


@pytest.mark.parametrize(
    "content, message",
    [
        (b"1 2 3\n4 5\n", "line 2 has 2 fields, expected 3"),
        (b"1 2 3\n4 x 6\n", "line 2 column 1: 'x' is not a number"),
        (b"# only a comment\n", "no rows of numbers"),
    ],
)
def test_bad_text_names_the_line(tmp_path, content, message):
    path = write_zip(tmp_path / "bad.zip", content)
    with pytest.raises(GearlabInputError, match=f"bad.zip: member 'record.txt': {message}"):
        read_columns(path, [0])


def test_bad_archives_and_columns_are_refused(tmp_path):
    (tmp_path / "not.zip").write_bytes(b"plain text")
    with pytest.raises(GearlabInputError, match="not a readable zip"):
        read_columns(tmp_path / "not.zip", [0])
    two = tmp_path / "two.zip"
    with zipfile.ZipFile(two, "w") as z:
        z.writestr("a.txt", "1 2\n")
        z.writestr("b.txt", "1 2\n")
    with pytest.raises(GearlabInputError, match="exactly one text file, found 2"):
        read_columns(two, [0])
    with pytest.raises(GearlabInputError, match="no such file"):
        read_columns(tmp_path / "missing.zip", [0])
    one = write_zip(tmp_path / "one.zip", b"1 2 3\n")
    with pytest.raises(GearlabInputError, match="column 3 does not exist; the file has 3 columns"):
        read_columns(one, [3])
    with pytest.raises(GearlabInputError, match="no column named 'acc'"):
        read_columns(one, ["acc"])


def test_record_cut_with_a_ten_pulse_tacho(tmp_path):
    path = record(tmp_path / "r.zip", revolutions=20, noise=0.0)
    rec = cut_recording(path, vibration=0, tacho=2, pulses_per_rev=PULSES, sensitivity=SENSITIVITY, fs=FS)
    assert rec.speed_hz == pytest.approx(SPEED, rel=1e-3)
    assert rec.revolutions.shape == (19, 4096)  # the record starts before the first mark
    # m/s²: the mesh tone's amplitude is back to 1 after the volts are divided by the sensitivity
    spectrum = np.abs(np.fft.rfft(rec.revolutions.mean(axis=0))) * 2 / 4096
    assert spectrum[32] == pytest.approx(1.0, rel=0.02)
    # a wrong pulses_per_rev shows as a speed ten times too high: one-pulse revolutions
    wrong = cut_recording(path, vibration=0, tacho=2, pulses_per_rev=1, sensitivity=SENSITIVITY, fs=FS)
    assert wrong.speed_hz == pytest.approx(PULSES * SPEED, rel=1e-3)


def test_records_starting_at_different_marks_are_aligned(tmp_path):
    a = cut_recording(
        record(tmp_path / "a.zip", noise=0.05, chip=3.0, seed=1),
        vibration=0,
        tacho=2,
        pulses_per_rev=PULSES,
        sensitivity=SENSITIVITY,
        fs=FS,
    )
    # the same machine, the record starting 3 marks (3/10 of a turn) later
    b = cut_recording(
        record(tmp_path / "b.zip", noise=0.05, chip=3.0, seed=2, phase=2 * np.pi * 0.3),
        vibration=0,
        tacho=2,
        pulses_per_rev=PULSES,
        sensitivity=SENSITIVITY,
        fs=FS,
    )
    ref = a.revolutions.mean(axis=0)
    before = np.corrcoef(ref, b.revolutions.mean(axis=0))[0, 1]
    shift, aligned = align_to(ref, b.revolutions, PULSES)
    after = np.corrcoef(ref, aligned.mean(axis=0))[0, 1]
    # b's revolutions start 3 marks later: advancing them by 7 marks (going back 3) matches a's
    assert shift == PULSES - 3 and before < 0.9 and after > 0.95


@pytest.mark.skipif(not PHM09.is_dir(), reason="the PHM 2009 records (../shared/data/phm09) are not here")
def test_real_phm09_record():
    rec = cut_recording(
        PHM09 / "spur2_30hz_High_1.zip",
        vibration=0,
        tacho=2,
        pulses_per_rev=10,
        sensitivity=parse_sensitivity("10 mV/g", "test"),
        fs=66666.67,
    )
    assert rec.speed_hz == pytest.approx(29.9, abs=0.1)
    assert 115 <= rec.revolutions.shape[0] <= 120
    rms = float(np.sqrt(np.mean(rec.revolutions**2)))
    assert 1.0 < rms < 100.0  # m/s², a gearbox housing's vibration (not volts, not g)
