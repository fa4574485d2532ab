"""Issue 39: without a tacho, a mesh line alone cannot tell the input pinion's count (37 teeth at 24.53 Hz mesh
where 36 at 25.22 Hz do, both within a nominal 1500 rpm's ±6 %). Where the input shaft's lines (sidebands, a
shaft line) show the speed, inspect reads at it even where the described count fitted the nominal speed;
where nothing but the mesh tells the speed, the verdict says 'consistent if the input turns at S' and names
every other count the nominal range allows (--json: check.ambiguous), never a plain 'matches'."""

from __future__ import annotations

import json

import numpy as np
import pytest
from test_outside_round8 import _box, _record

from gearlab.inspect import InspectOptions, inspect_record


def _bare(path, z1: int, z2: int, f: float, shaft_line: float = 0.0, seed: int = 0) -> str:
    """A one-stage record without the input shaft's sidebands (the output shaft's only), with an optional
    line at the input shaft's frequency."""
    fs = 8192.0
    theta = 2 * np.pi * f * np.arange(int(160 / f * fs)) / fs
    mod = 1 + 0.1 * np.cos(z1 / z2 * theta + 1.0)
    x = sum(a * mod * np.cos(h * z1 * theta + 0.6 * h) for h, a in ((1, 1.0), (2, 0.4), (3, 0.2)))
    x = x + shaft_line * np.cos(theta + 0.2) + np.random.default_rng(seed).normal(0, 0.05, x.size)
    np.savez(path, acc_ms2=x, fs=fs)
    return str(path)


def test_the_input_pinion_s_sidebands_settle_the_speed_where_the_described_count_fitted_the_nominal_one(tmp_path):
    # 37/137 at 24.53 Hz described 36 at a nominal 1500 rpm: the speed search took 25.22 Hz (a 36-tooth mesh on
    # the line, within ±1 % of 25 Hz) and every row was read there; the sidebands, 24.53 Hz apart, say 37
    box = _box(tmp_path, 36, 137, "1500 rpm")
    report = inspect_record(_record(tmp_path / "r.npz", 37, 137, 24.5339, seed=104), box, InspectOptions("acc_ms2"))
    assert report["speed"]["mean_hz"] == pytest.approx(24.5339, rel=1e-3), report["speed"]
    assert report["matches"] is False
    assert report["check"]["stages"][0]["measured_order"] == pytest.approx(37.0, abs=0.05)
    assert "stage 1: mesh order 37 measured, 36 expected (a 37-tooth pinion" in report["verdict"], report["verdict"]
    assert report["check"]["ambiguous"] == []


def test_a_mesh_line_alone_is_consistent_only_if_the_speed_is_the_one_read_and_names_the_other_counts(tmp_path, cli):
    # The same record without the input shaft's sidebands: 'the description matches this recording' (36 teeth
    # at 25.22 Hz), where a 37-tooth pinion at 24.53 Hz gives the same line
    box = _box(tmp_path, 36, 137, "1500 rpm")
    path = _bare(tmp_path / "bare.npz", 37, 137, 24.5339, seed=104)
    report = inspect_record(path, box, InspectOptions("acc_ms2"))
    verdict = report["verdict"]
    assert "matches this recording" not in verdict and report["matches"] is not False, verdict
    assert "is consistent with this recording if the input turns at 25.22 Hz" in verdict, verdict
    assert "a 37-tooth pinion at 24.53 Hz" in verdict and "a 35-tooth pinion at 25.94 Hz" in verdict, verdict
    assert "a tacho or the measured speed (--speed) would decide" in verdict, verdict
    teeth = {a["pinion_teeth"]: a["speed_hz"] for a in report["check"]["ambiguous"]}
    assert 36 not in teeth and teeth[37] == pytest.approx(24.5339, rel=1e-3), teeth
    # every count's speed within the nominal ±6 %
    assert all(abs(hz / 25.0 - 1) <= 0.06 for hz in teeth.values()) and {35, 37} <= set(teeth), teeth
    code, out, _ = cli("inspect", path, "--gearbox", tmp_path / "box36_137.toml", "--vibration", "acc_ms2", "--json")
    assert code == 0 and 37 in [a["pinion_teeth"] for a in json.loads(out)["check"]["ambiguous"]], out


@pytest.mark.parametrize(
    "z1, z2, f, sidebands", [(37, 137, 24.5339, True), (37, 137, 24.5339, False), (33, 131, 24.6272, True)]
)
def test_the_input_shaft_s_own_lines_leave_a_right_description_a_plain_match(tmp_path, z1, z2, f, sidebands):
    # sidebands of the input shaft, or a line at its frequency, tell the count; a 33/131 pinion's sidebands
    # (24.63 Hz apart) lie 1.2 bins from the wheel's 4th harmonic (24.81 Hz): still the pinion's
    box = _box(tmp_path, z1, z2, "1500 rpm")
    if sidebands:
        path = _record(tmp_path / "r.npz", z1, z2, f, seed=104)
    else:
        path = _bare(tmp_path / "r.npz", z1, z2, f, shaft_line=0.3, seed=104)
    report = inspect_record(path, box, InspectOptions("acc_ms2"))
    assert report["matches"] is True and report["verdict"].startswith("the description 'fan' matches this recording"), (
        report["verdict"]
    )
    assert report["check"]["ambiguous"] == [] and report["speed"]["mean_hz"] == pytest.approx(f, rel=1e-3)
