"""Outside user AF (issue 39, docs/your_gearbox.md steps 3-5): recordings of a 23/59 + 19/67 box at 31 Hz
made with gearlab's own simulator and a hidden 4.5 kHz sensor resonance. The gap diagnosis named it
(sensor_bandwidth f_n 4.59 kHz, zeta 0.103 on 1.5 s takes); two things stood in the way of the guide:

* step 4 says to copy summary.json's corrected_effects into [corrected]: that form
  (["name", [["param", value], ...]]) was refused ('expected a table {name = "...", ...}');
* on 4 s takes (124 turns) the simulated mesh lines carried sidebands 0.322 orders apart (10 Hz),
  read as the intermediate shaft's: inspect said 'the wheel shows 71.3 teeth' and the gap diagnosis
  ended 'structure differs: stage 1 wheel: 71 teeth fit the recording, 59 described' without
  searching an effect, though both mesh orders matched the description (71 teeth make the second
  pinion 22.86).
"""

from __future__ import annotations

import numpy as np
import pytest
from gearboxes import description, stage

from gearlab.effects import effects_from_tables

BOX = description(
    stage(23, 59), stage(19, 67), name="af2359", speed="31 Hz", load="40 N*m", near="input", tacho="input"
)


def test_corrected_effects_copied_from_summary_json_read_as_the_tables():
    copied = [
        ["sensor_bandwidth", [["f_n", 4586.38], ["zeta", 0.1026]]],
        ["sensor_noise", [["kind", "laplace"], ["snr_db", 28.21]]],
    ]
    tables = [
        {"name": "sensor_bandwidth", "f_n": 4586.38, "zeta": 0.1026},
        {"name": "sensor_noise", "kind": "laplace", "snr_db": 28.21},
    ]
    assert effects_from_tables(copied, "[corrected] key 'effects'") == effects_from_tables(tables, "t")


def _record(path, seconds: float = 4.0, fs: float = 25_600.0, speed: float = 31.0):
    """Both meshes (23 and 23 x 19/59 orders, three harmonics each) amplitude-modulated at 10 Hz, a fixed
    frequency (a structural mode), no shaft's order: no line says anything of the intermediate shaft."""
    t = np.arange(int(seconds * fs)) / fs
    theta = speed * t  # input turns
    m1, m2 = 23.0, 23.0 * 19 / 59
    am = 1 + 0.1 * np.cos(2 * np.pi * 10.0 * t)
    acc = sum(am * np.cos(2 * np.pi * h * m * theta) / h for m in (m1, m2) for h in (1, 2, 3))
    acc = acc + 0.001 * np.random.default_rng(0).standard_normal(t.size)
    np.savez(path, acc=acc, tacho=2.5 - 2.5 * np.cos(2 * np.pi * theta), fs=fs)


@pytest.fixture()
def box_and_record(tmp_path):
    (tmp_path / "gb.toml").write_text(BOX)
    _record(tmp_path / "take.npz")
    return tmp_path / "gb.toml", tmp_path / "take.npz"


def test_a_fixed_frequency_modulation_is_no_shaft_whose_count_contradicts_both_meshes(box_and_record):
    import gearlab

    box, take = box_and_record
    report = gearlab.inspect_recording(take, box, vibration="acc", tacho="tacho", unit="m/s^2")
    check = report["check"]
    assert [s["matched"] for s in check["stages"]] == [True, True]
    assert check["differences"] == [], check["differences"]
    assert any("a modulation, not that shaft's order" in u for u in check["unresolved"])


def test_the_gap_s_structure_check_searches_effects_on_such_records():
    """The gap's structure line (structure_line, the diagnosis's and detection's check) on the same
    modulation, 124 input turns cut at the tacho: no tooth-count difference, the comb said unchecked."""
    from gearboxes import described_pair

    from gearlab.data.chain import Chain
    from gearlab.gap.structure import structure_line

    points, speed, turns = 1024, 31.0, 124
    theta = np.arange(turns * points) / points  # input turns
    t = theta / speed
    am = 1 + 0.1 * np.cos(2 * np.pi * 10.0 * t)
    x = sum(am * np.cos(2 * np.pi * h * m * theta) / h for m in (23.0, 23.0 * 19 / 59) for h in (1, 2, 3))
    x = x + 0.001 * np.random.default_rng(1).standard_normal(x.size)
    record: dict = {}
    chain = Chain(fs=points * speed, speed=speed, tacho_shaft="input")
    line = structure_line(x.reshape(turns, points), described_pair((23, 59), (19, 67)), 400, chain, None, record)
    assert line is None, line
