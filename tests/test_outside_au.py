"""Outside user AU (issue 39: inspect never says a right description differs): a 27/52 + 40/70 box at 38.03 Hz,
simulated by gearlab at 200 kHz and resampled to 25.6 kHz (the lead's fresh seed 5235, box 115), carries stage 1's
194th mesh harmonic folded about the simulator's rate: 200 kHz - 194 x 1026.7 Hz = 813.4 Hz, order 21.389, 20 dB
over the floor, alone 0.6201 above stage 2's mesh (20.769), no order of any shaft. Stage 2's pinion comb took it
as the intermediate shaft's order: 'the pinion on the intermediate shaft shows 33.5 ± 0.2 teeth (mesh order 20.77
/ shaft order 0.6201), 40 described' of the true description, on a TTL and a cosine tacho. A shaft's sidebands and
its mesh lie at whole multiples of its order, so a comb reading no whole count is no shaft's (sideband_combs.whole).
Records written by hand here, the tone put where the simulation put it."""

from __future__ import annotations

import numpy as np
import pytest
from gearboxes import description, shaft_orders, stage

import gearlab
import gearlab.gearbox.match as match

TRUE = ((27, 52), (40, 70))
F0, FS, SECONDS = 38.03, 6400.0, 4.0
TONE = 21.389  # orders of the input: 813.4 Hz at 38.03 Hz


def _take(tmp_path, seed=0, wheel_sidebands=0.0, kind="ttl"):
    rng = np.random.default_rng(seed)
    t = np.arange(int(SECONDS * FS)) / FS
    theta = 2 * np.pi * F0 * t + 1.7
    orders = shaft_orders(TRUE)
    x = np.zeros(t.size)
    for k, (z1, _) in enumerate(TRUE):
        lift = 1 + wheel_sidebands * np.cos(orders[k + 1] * theta + k)
        for h in (1, 2, 3):
            x += (1.0 if k else 0.6) / h * lift * np.cos(h * z1 * orders[k] * theta + 0.4 * h + k)
    x += rng.standard_normal(t.size) * 0.02
    x += 0.012 * np.cos(TONE * theta + 0.3)  # ~20 dB over the floor, as in the simulation
    tacho = np.where(np.mod(theta, 2 * np.pi) < 0.2 * np.pi, 5.0, 0.0) if kind == "ttl" else 2.5 - 2.5 * np.cos(theta)
    np.savez(tmp_path / "take.npz", acc=x, tacho=tacho, fs=FS)
    return tmp_path / "take.npz"


def _inspect(tmp_path, take, teeth):
    box = tmp_path / "box.toml"
    stages = (stage(*teeth[0]), stage(*teeth[1], module="3 mm", width="25 mm", bores=("30 mm", "40 mm")))
    box.write_text(description(*stages, name="au115", speed="38.03 Hz", load="30 N*m", near="input", tacho="input"))
    return gearlab.inspect_recording(take, box, vibration="acc", tacho="tacho", unit="m/s^2")


def test_the_tone_is_no_shaft_s_order_and_reads_no_whole_count():
    m2 = 27 * 40 / 52
    assert abs((TONE - m2) - 0.6201) < 0.001
    z = m2 / (TONE - m2)
    assert 0.4 < abs(z - round(z))
    # 72.09 output orders, 41.19 intermediate: 4 bins or more off every shaft's harmonic
    assert all(abs(TONE - o * round(TONE / o)) > 3 / (F0 * SECONDS) for o in shaft_orders(TRUE))


@pytest.mark.parametrize("kind", ["ttl", "cos"])
def test_the_true_description_matches_beside_a_tone_no_shaft_carries(tmp_path, kind):
    report = _inspect(tmp_path, _take(tmp_path, kind=kind), TRUE)
    assert report["matches"] is True, report["verdict"]


def test_without_the_whole_count_rule_the_tone_reads_33_5_teeth(tmp_path, monkeypatch):
    monkeypatch.setattr(match, "whole", lambda *args: True)
    report = _inspect(tmp_path, _take(tmp_path), TRUE)
    assert report["matches"] is False and "shows 33.5" in report["verdict"], report["verdict"]


@pytest.mark.parametrize("said", [((27, 52), (40, 69)), ((27, 52), (40, 71))])
def test_a_wheel_count_off_is_still_called_out_from_its_sidebands(tmp_path, said):
    report = _inspect(tmp_path, _take(tmp_path, wheel_sidebands=0.3), said)
    assert report["matches"] is False, report["verdict"]
    assert "shows 70.0" in report["verdict"], report["verdict"]
