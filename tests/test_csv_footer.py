"""A logger's footer under the rows ('End of data', 'Samples: 204800', a blank line then a note) is left out
with one warning naming the file and its first line; a text line with rows of numbers after it stays an error
naming the file and the line. The same for a CSV, a text and a gzipped or zipped text."""

from __future__ import annotations

import gzip
import zipfile

import numpy as np
import pytest

from gearlab.data.recordings import read_header, read_recording
from gearlab.errors import GearlabInputError

N = 400
T = np.arange(N) / 1000.0
ACC = np.sin(2 * np.pi * 37.0 * T) + 0.25 * np.cos(2 * np.pi * 5.0 * T)
FOOTERS = {
    "one line": ["End of data"],
    "a total": ["Samples: 400"],
    "blank, then two": ["", "Measurement finished", "Samples = 400"],
    "three": ["# end", "End of data", "Total samples: 400;; 2 channels"],
}


def _rows(sep: str) -> list[str]:
    decimal = "," if sep == ";" else "."  # a semicolon export writes decimal commas
    return [f"{t:.6f}{sep}{float(a)!r}".replace(".", decimal) for t, a in zip(T, ACC)]


def _write(path, lines: list[str]) -> None:
    text = "\n".join(lines) + "\n"
    if path.suffix == ".gz":
        path.write_bytes(gzip.compress(text.encode()))
    elif path.suffix == ".zip":
        with zipfile.ZipFile(path, "w") as z:
            z.writestr("take.txt", text)
    else:
        path.write_text(text)


@pytest.mark.parametrize("footer", FOOTERS.values(), ids=FOOTERS.keys())
@pytest.mark.parametrize(
    "name, sep", [("c.csv", ","), ("s.csv", ";"), ("t.tsv", "\t"), ("b.txt", " "), ("g.gz", ","), ("z.zip", "\t")]
)
def test_a_footer_is_left_out_with_one_warning(tmp_path, name, sep, footer):
    path = tmp_path / name
    _write(path, [sep.join(["time", "acc"]), *_rows(sep), *footer])
    header = read_header(path)  # the header alone: the footer is not its business
    assert header.channels == ["time", "acc"]
    rec = read_recording(path, "acc", unit="m/s^2")
    assert rec.signal.size == N and np.allclose(rec.signal, ACC, rtol=0, atol=1e-12)
    assert rec.fs == pytest.approx(1000.0)
    first = next(line for line in footer if line and not line.startswith("#"))
    assert len(rec.warnings) == 1, rec.warnings
    said = rec.warnings[0]
    assert f"line {footer.index(first) + N + 2}" in said and repr(first) in said and "left out" in said


@pytest.mark.parametrize("name, sep", [("c.csv", ","), ("s.csv", ";"), ("b.txt", " "), ("g.gz", ","), ("z.zip", "\t")])
def test_a_text_line_in_the_middle_stays_an_error(tmp_path, name, sep):
    rows = _rows(sep)
    path = tmp_path / name
    _write(path, [sep.join(["time", "acc"]), *rows[:100], "Pause", *rows[100:], "End of data"])
    with pytest.raises(GearlabInputError) as caught:
        read_recording(path, "acc", unit="m/s^2")
    said = str(caught.value)
    assert str(path) in said and "line 102" in said and "\n" not in said
    assert path.suffix != ".csv" or "a note amid the rows?" in said


@pytest.mark.parametrize("name, sep", [("c.csv", ","), ("b.txt", " ")])
def test_a_truncated_last_row_stays_an_error(tmp_path, name, sep):
    path = tmp_path / name
    _write(path, [sep.join(["time", "acc", "probe"]), *(f"{r}{sep}0.5" for r in _rows(sep)), "0.4", "End of data"])
    with pytest.raises(GearlabInputError, match=f"line {N + 2}"):
        read_recording(path, "acc", unit="m/s^2")


def test_no_footer_no_warning(tmp_path):
    path = tmp_path / "c.csv"
    _write(path, ["time,acc", *_rows(",")])
    assert read_recording(path, "acc", unit="m/s^2").warnings == ()


def test_the_cli_says_the_footer_once(tmp_path):
    from typer.testing import CliRunner

    from gearlab.cli import app

    path = tmp_path / "c.csv"
    _write(path, ["time,acc", *_rows(","), "End of data"])
    result = CliRunner().invoke(app, ["inspect", str(path), "--vibration", "acc", "--speed", "10"])
    out = result.output
    assert result.exit_code == 0, out
    assert out.count("'End of data'") == 1 and f"line {N + 2}" in out


def test_the_cut_record_says_it_once_and_validate_takes_the_file(tmp_path, cli):
    from gearboxes import description, stage

    from gearlab.data.recordings import cut_recording

    path = tmp_path / "c.csv"
    _write(path, ["time,acc", *_rows(","), "", "End of data", "Samples: 400"])
    cut = cut_recording(path, vibration="acc", unit="m/s^2", speed_hz=10.0)
    assert [w for w in cut.warnings if "End of data" in w] == [
        f"line {N + 3} 'End of data' and the 1 line under it: no row of numbers (a logger's footer?); left out"
    ]
    (tmp_path / "k.toml").write_text(description(stage(105, 143, "1 mm", "12 mm"), speed="10 Hz", load="30 N*m"))
    text = '[scenario]\nname = "s"\nkind = "gap"\n[source]\ngearbox = "k.toml"\n[target]\nvibration = "acc"\n'
    text += 'unit = "m/s^2"\nfiles = [{ file = "c.csv", role = "history", label = "healthy" }]\n'
    (tmp_path / "s.toml").write_text(text)
    code, out, err = cli("validate", tmp_path / "s.toml")
    assert code == 0 and "OK" in out, (out, err)


def test_a_dataset_keeps_the_note_in_its_meta(tmp_path):
    from gearlab.data.importers import MeasuredSpec, import_measured

    path = tmp_path / "c.csv"
    _write(path, ["time,acc_ms2", *_rows(","), "End of data"])
    ds = import_measured(MeasuredSpec(name="rig", path=str(path), vibration="acc_ms2", speed_hz=10.0, transient="none"))
    assert ds.meta["warnings"] == [
        f"{path}: line {N + 2} 'End of data': no row of numbers (a logger's footer?); left out"
    ]


@pytest.mark.parametrize("chunk", [64, 4096])
def test_a_footer_across_the_text_readers_blocks(tmp_path, monkeypatch, chunk):
    from gearlab.data.readers import text

    monkeypatch.setattr(text, "CHUNK_BYTES", chunk)  # the footer's lines read in several blocks
    path = tmp_path / "g.gz"
    _write(path, ["time acc", *_rows(" "), "", "Samples 400, then:", "End of data " * 20, "# end", "Total: 400"])
    rec = read_recording(path, "acc", unit="m/s^2")
    assert rec.signal.size == N and rec.warnings == (
        f"line {N + 3} 'Samples 400, then:' and the 2 lines under it: no row of numbers (a logger's footer?); left out",
    )
    rows = _rows(" ")
    _write(path, ["time acc", *rows[:300], "Pause", *rows[300:], "End of data"])
    with pytest.raises(GearlabInputError, match="line 302 has 1 fields"):
        read_recording(path, "acc", unit="m/s^2")


@pytest.mark.parametrize("rows", [N, 30])  # the tail (8 kB) past the rows' start, and holding the whole file
@pytest.mark.parametrize("name, sep", [("c.csv", ","), ("s.csv", ";"), ("b.txt", " ")])
def test_validate_warns_of_a_footer_as_the_run_s_reader_does(tmp_path, cli, name, sep, rows):
    # DP: `gearlab validate` said OK without a word of a footer the run's reader leaves out with a warning: it reads
    # headers only; the file's last 8 kB now say it, in the reader's words
    from gearboxes import description, stage

    from gearlab.data.readers.headers import tail_footer

    path = tmp_path / name
    _write(path, [sep.join(["time", "acc"]), *_rows(sep)[:rows], "", "End of data", "Samples: 400"])
    said = read_recording(path, "acc", unit="m/s^2").warnings
    assert len(said) == 1 and tail_footer(path, 2) == said[0], (said, tail_footer(path, 2))
    (tmp_path / "k.toml").write_text(description(stage(105, 143, "1 mm", "12 mm"), speed="10 Hz", load="30 N*m"))
    text = '[scenario]\nname = "s"\nkind = "gap"\n[source]\ngearbox = "k.toml"\n[target]\nvibration = "acc"\n'
    text += f'unit = "m/s^2"\nfiles = [{{ file = "{name}", role = "history", label = "healthy" }}]\n'
    (tmp_path / "s.toml").write_text(text)
    code, out, err = cli("validate", tmp_path / "s.toml")
    assert code == 0 and "OK" in out, (out, err)
    assert err.splitlines() == [f"warning: {path}: {said[0]}"], err
    _write(path, [sep.join(["time", "acc"]), *_rows(sep)[:rows]])  # no footer: no word
    code, out, err = cli("validate", tmp_path / "s.toml")
    assert code == 0 and "OK" in out and err == "", (out, err)
