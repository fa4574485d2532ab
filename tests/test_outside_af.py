"""Outside user AF (issue 39, docs/your_gearbox.md steps 3-5): recordings of a 23/59 + 19/67 box at 31 Hz
made with gearlab's own simulator and a hidden 4.5 kHz sensor resonance. The gap diagnosis named it
(sensor_bandwidth f_n 4.59 kHz, zeta 0.103 on 1.5 s takes). Step 4 says to copy summary.json's
corrected_effects into [corrected]: that form (["name", [["param", value], ...]]) was refused ('expected a
table {name = "...", ...}').
"""

from __future__ import annotations

from gearlab.effects import effects_from_tables


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
