"""An outside user's look (issue 39): two gearboxes no other test uses, their takes made here by plain numpy (mesh
lines with both shafts' sidebands, shaft harmonics, noise; no gearlab simulator).
A: two stages 19/67 + 23/71 at ~20 Hz, a European logger's CSV (';', decimal commas, CRLF) headed
'Zeit [s];Beschl. [m/s²];Drehzahlgeber [V]', an encoder of 60 pulses a turn.
B: one stage 31/97 at 480 rpm (a slow mill), no tacho, the accelerometer in volts at 10.2 mV/(m/s²): the same take
exported twice, a zip of a blank-separated text (header 'time acc', a units row 's V') and an .npz. A blank-separated
text's units row was refused ('its first data row (line 2) holds no number'): readers.text now reads it."""

from __future__ import annotations

import io
import zipfile

import numpy as np
import pytest
from gearboxes import description, inspected, read_as_described, stage

FS_A, FS_B = 8000.0, 4096.0
SENS_B = 0.0102  # V per m/s²
VIB_A, TACHO_A = "Beschl. [m/s²]", "Drehzahlgeber [V]"
BOX_A = description(
    stage(19, 67, "3 mm", "25 mm", ("25 mm", "40 mm")),
    stage(23, 71, "4 mm", "35 mm", ("40 mm", "60 mm")),
    name="boxA", speed="20 Hz", load="40 N*m", near="input", tacho="input", marks=60,
)  # fmt: skip
BOX_B = description(stage(31, 97, "5 mm", "60 mm", ("60 mm", "120 mm")), name="millB", speed="480 rpm", load="900 N*m")


def _take(stages, f_in, fs, seconds, seed, ppr=None):
    """(t, m/s², tacho V or None): each stage's mesh (3 harmonics) modulated by its two shafts, each shaft's first
    3 harmonics, noise 25 dB under the signal, the speed wandering 0.2 %; *ppr*: an encoder's pulses a turn."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * fs)) / fs
    speed = f_in * (1 + 0.002 * np.sin(2 * np.pi * 0.13 * t + rng.uniform(0, 6)))
    theta = [2 * np.pi * np.cumsum(speed) / fs + rng.uniform(0, 6)]
    for zp, zw in stages:
        theta.append(theta[-1] * zp / zw)
    x = sum(a * np.cos(h * th + 0.7 * h + k) for k, th in enumerate(theta) for h, a in ((1, 0.4), (2, 0.15), (3, 0.05)))
    for s, (zp, _) in enumerate(stages):
        am = 1 + 0.25 * np.cos(theta[s] + 0.3 * s) + 0.2 * np.cos(theta[s + 1] + 1.1 + s)
        x = x + sum(
            a / (s + 1) * am * np.cos(h * zp * theta[s] + 0.9 * h + 2 * s) for h, a in ((1, 3), (2, 1.2), (3, 0.5))
        )
    x = x + rng.standard_normal(t.size) * np.sqrt(np.mean(x**2) / 10**2.5)
    tacho = None if ppr is None else np.where(np.mod(theta[0] * ppr / (2 * np.pi), 1.0) < 0.5, 5.0, 0.0)
    return t, x, tacho


def _text(columns, fmts, sep) -> str:
    buf = io.StringIO()
    np.savetxt(buf, np.column_stack(columns), fmt=fmts, delimiter=sep)
    return buf.getvalue()


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """box A's take as its logger's CSV; box B's as a zip of a text and as an .npz; both descriptions."""
    d = tmp_path_factory.mktemp("hn")
    t, x, tacho = _take([(19, 67), (23, 71)], 20.0, FS_A, 4.0, 1, ppr=60)
    body = _text([t, x, tacho], ["%.6f", "%.5f", "%.3f"], ";").replace(".", ",")
    (d / "A.csv").write_bytes(f"Zeit [s];{VIB_A};{TACHO_A}\n{body}".replace("\n", "\r\n").encode())
    t, x, _ = _take([(31, 97)], 8.0, FS_B, 8.0, 2)
    text = "time acc\ns V\n" + _text([t, x * SENS_B], ["%.6f", "%.6e"], " ")
    with zipfile.ZipFile(d / "B.zip", "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("B.txt", text)
    with zipfile.ZipFile(d / "B2.zip", "w") as z:  # two exports in one zip: which is the take?
        z.writestr("B.txt", text)
        z.writestr("B_copy.txt", text)
    np.savez(d / "B.npz", acc=x * SENS_B, fs=FS_B)
    (d / "A.toml").write_text(BOX_A)
    (d / "B.toml").write_text(BOX_B)
    (d / "B31.toml").write_text(BOX_B.replace("z = 31,", "z = 32,"))
    return d


B_KEYS = ("--vibration", "acc", "--sensitivity", "10.2 mV/(m/s^2)", "--speed", "480 rpm")


def test_box_a_s_european_csv_is_read_as_described(folder, cli):
    report = inspected(cli, folder / "A.csv", "--gearbox", folder / "A.toml", "--vibration", VIB_A, "--tacho", TACHO_A)
    read_as_described(report, 20.0, [19.0, 19 * 23 / 67])
    assert "60 pulse(s) per revolution" in report["speed"]["source"] and report["units"].startswith("m/s²")


@pytest.mark.parametrize("take", ["B.zip", "B.npz"])
def test_box_b_s_two_exports_read_alike_in_volts_at_the_plate_s_speed(folder, cli, take):
    report = inspected(cli, folder / take, "--gearbox", folder / "B.toml", *B_KEYS)
    read_as_described(report, 8.0, [31.0])
    assert report["units"].startswith("m/s² = value x 98.0392"), report["units"]


def test_box_b_s_pinion_described_one_tooth_off_is_called_out(folder, cli):
    report = inspected(cli, folder / "B.zip", "--gearbox", folder / "B31.toml", *B_KEYS)
    assert report["matches"] is False and "a 31-tooth pinion on the input shaft? described 32" in report["verdict"]


def _gap(folder, file: str, **keys) -> str:
    target = {"vibration": "acc", "sensitivity": "10.2 mV/(m/s^2)", "speed": "480 rpm", **keys}
    lines = "".join(f'{k} = "{v}"\n' for k, v in target.items())
    text = f'[scenario]\nname = "g"\nkind = "gap"\n[source]\ngearbox = "B.toml"\n[target]\n{lines}file = "{file}"\n'
    (folder / "g.toml").write_text(text)
    return str(folder / "g.toml")


@pytest.mark.parametrize(
    ("file", "keys", "said"),
    [
        ("B.zip", {"vibration": "acc_V"}, ["key 'vibration'", "acc_V"]),
        ("B_gone.zip", {}, ["key 'file'", "B_gone.zip"]),
        ("B.zip", {"sensitivity": "10.2 mV/(mm/s)"}, ["key 'sensitivity'", "'10.2 mV/(mm/s)' has the wrong dimension"]),
        ("B2.zip", {}, ["key 'file'", "B2.zip", "exactly one text file, found 2"]),
    ],
    ids=["a wrong column", "a missing file", "a wrong unit", "a zip of two files"],
)
def test_bad_input_is_one_line_naming_file_and_key_at_validate(folder, cli, file, keys, said):
    code, out, err = cli("validate", _gap(folder, file, **keys))
    line = err.strip()
    assert code == 2 and "\n" not in line and "g.toml" in line, (code, out, err)
    assert all(s in line for s in said), line
    assert line.count("e.g.") <= 1, line  # a sensitivity's example was given twice
