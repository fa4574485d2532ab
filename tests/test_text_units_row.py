"""A text record's row of units under its header ('time acc tacho' then 's g V', then numbers) is read as each
column's unit, as a CSV's is (readers.csv.units_row, the one reading of such a row): a blank- or tab-separated
.txt, plain or zipped, was refused as 'its first data row (line 2) holds no number'. validate (the header) and the
run (the columns) read it alike."""

from __future__ import annotations

import zipfile

import numpy as np
import pytest

from gearlab.data.recordings import read_header, read_recording
from gearlab.errors import GearlabInputError

G = 9.80665
FS = 4000.0
T = np.arange(800) / FS
ACC = np.sin(2 * np.pi * 150 * T)  # in g as written


def _take(path, separator: str, units: str = "s g V", zipped: bool = False):
    rows = "\n".join(separator.join(f"{v:.9g}" for v in row) for row in zip(T, ACC, (T * 25) % 1 < 0.1))
    text = separator.join(["time", "acc", "tacho"]) + "\n" + separator.join(units.split()) + "\n" + rows + "\n"
    if not zipped:
        path.write_text(text)
        return path
    with zipfile.ZipFile(path.with_suffix(".zip"), "w") as z:
        z.writestr(path.name, text)
    return path.with_suffix(".zip")


@pytest.mark.parametrize(
    ("separator", "zipped"), [(" ", False), ("\t", False), ("  ", True)], ids=["blanks", "tabs", "zip"]
)
def test_a_units_row_under_the_header_gives_each_column_s_unit(tmp_path, separator, zipped):
    path = _take(tmp_path / "take.txt", separator, zipped=zipped)
    header = read_header(path)
    assert header.channels == ["time", "acc", "tacho"] and header.units == {"time": "s", "acc": "g", "tacho": "V"}
    got = read_recording(path, "acc", "tacho")
    assert got.fs == pytest.approx(FS) and got.signal.size == T.size and got.tacho.size == T.size
    assert np.allclose(got.signal, ACC * G, atol=1e-6) and "in g" in got.units, got.units


def test_a_second_row_of_words_that_are_no_units_is_still_refused(tmp_path):
    # only a row of one short unit a column is one (units_row); a note there is no data
    path = _take(tmp_path / "take.txt", " ", units="see notes: channel 2 broken")
    with pytest.raises(GearlabInputError, match="line 2"):
        read_recording(path, "acc", "tacho")
