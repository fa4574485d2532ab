"""The verdict's line on a box whose own mesh lines differ from the simulator's as much as a sensor or path
effect moves them (gearlab.gap.line_levels): said with its numbers where the box's lines scatter about the
simulator's, not where the records are the simulator's behind a filter."""

from __future__ import annotations

import numpy as np
import pytest

from gearlab.gap.conclusion import verdict_text
from gearlab.gap.line_levels import SAID_DB, line_mismatch, mismatch_of, relative_levels, told
from gearlab.kinds.gap_verdict import gap_lines

Z1, P, HARMONICS = 27, 4096, 8
ORDERS = Z1 * np.arange(1, HARMONICS + 1)


def _rows(gains_db, seed: int, n: int = 40) -> np.ndarray:
    """*n* revolutions of a 27-tooth mesh's 8 harmonics (levels falling as k^-0.6, times *gains_db*), fixed
    phases, and noise 40 dB under the lines."""
    rng = np.random.default_rng(seed)
    theta = 2 * np.pi * np.arange(P) / P
    phases = np.random.default_rng(5).uniform(0, 2 * np.pi, HARMONICS)
    amplitude = np.arange(1, HARMONICS + 1) ** -0.6 * 10 ** (np.asarray(gains_db) / 20)
    clean = sum(a * np.cos(k * theta + p) for a, k, p in zip(amplitude, ORDERS, phases))
    return clean + rng.normal(0, 0.01 * np.std(clean), (n, P))


def _lowpass_db(f_c_order: float, poles: int = 2) -> np.ndarray:
    """A Butterworth low-pass's gain (dB) at the harmonics, its corner at shaft order *f_c_order*."""
    return -10 * np.log10(1 + (ORDERS / f_c_order) ** (2 * poles))


BOX = np.array([7.5, -12.5, -3.7, 0.4, -4.1, -1.4, 15.0, -1.1])  # a 27/61 box's lines over the simulator's, dB


def test_the_relative_levels_are_the_harmonics_gains_less_their_mean():
    (d,) = relative_levels(_rows(BOX + 6.0, 1), _rows(np.zeros(HARMONICS), 2), z1=Z1, max_order=360)
    assert d == pytest.approx(BOX - BOX.mean(), abs=0.05)
    lacking = BOX.copy()
    lacking[5] = -400.0
    # a harmonic one set lacks (at its noise) is left out of every set; fewer than three lines tell no shape
    plain, fitted = _rows(np.zeros(HARMONICS), 2), _rows(lacking, 3)
    assert [d.size for d in relative_levels(_rows(BOX, 1), plain, fitted, z1=Z1, max_order=360)] == [7, 7]
    assert relative_levels(_rows(BOX, 1), plain, z1=Z1, max_order=2 * Z1)[0].size == 0


def test_a_box_whose_lines_scatter_about_the_simulators_is_said_a_filtered_simulator_is_not():
    plain = _rows(np.zeros(HARMONICS), 2)
    filtered = _lowpass_db(3000 / 25)  # a 2-pole low-pass at 3 kHz, 25 Hz shaft: 0 to -11 dB over the harmonics
    assert np.sqrt(np.mean((filtered - filtered.mean()) ** 2)) == pytest.approx(3.8, abs=0.05)  # SAID_DB's scale
    fits = {"sensor_lowpass": _rows(filtered, 3), "casing_path": _rows(0.3 * filtered, 4)}
    # that box behind the low-pass: even the true low-pass, fitted, leaves its own 7.7 dB RMS, over SAID_DB; a
    # path that moves the lines a third as far matches them a little better (7.1 dB) and is the one said
    target = _rows(BOX + filtered, 1)
    record = line_mismatch(target, plain, {"sensor_lowpass": fits["sensor_lowpass"]}, Z1, 360)
    own = np.sqrt(np.mean((BOX - BOX.mean()) ** 2))
    assert record["name"] == "sensor_lowpass" and record["harmonics"] == HARMONICS, record
    assert record["left_db"] == pytest.approx(own, abs=0.1) and record["left_db"] > SAID_DB and told(record)
    both = BOX + filtered
    assert record["plain_db"] == pytest.approx(np.sqrt(np.mean((both - both.mean()) ** 2)), abs=0.1)
    record = line_mismatch(target, plain, fits, Z1, 360)
    assert record["name"] == "casing_path" and SAID_DB < record["left_db"] < own and told(record), record
    # the simulator's own box behind the low-pass: the fit that matches it leaves nothing to say
    record = line_mismatch(_rows(filtered, 1), plain, fits, Z1, 360)
    assert record["name"] == "sensor_lowpass" and record["left_db"] < 0.1 and not told(record), record
    assert record["plain_db"] > SAID_DB  # though the plain source's lines differ as much as the filter moves them
    # no line-shaping fit: nothing to say
    assert not told(line_mismatch(_rows(BOX, 1), plain, {}, Z1, 360))


def test_mismatch_of_reads_every_line_shaping_fit_on_a_measured_target():
    made = []

    class Run:
        target = _rows(BOX, 1)
        pair = type("Pair", (), {"Z1": Z1})()
        settings = type("Settings", (), {"max_order": 360})()

        @staticmethod
        def spec(name, params):
            return (name, tuple(sorted(params.items())))

        @staticmethod
        def judged(effects):
            made.append(effects)
            return _rows(
                np.zeros(HARMONICS) if not effects else 0.5 * BOX if effects[0][0] == "casing_path" else 0 * BOX, 2
            )

    ranking = [
        {"name": "sensor_noise", "params": {"snr_db": 0.7}, "share_removed": 0.85},
        {"name": "sensor_lowpass", "params": {"f_c": 3000.0, "order": 2}, "share_removed": 0.8},
    ]
    dropped = [{"name": "sensor_noise", "params": {"snr_db": 1.0}}, {"name": "casing_path", "params": {"mf": 2.0}}]
    record = mismatch_of(Run, {"chain": {"fs_hz": 20000.0}, "ranking": ranking, "dropped_effects": dropped})
    # the noise alone left out; the path that takes half the box's own mismatch matches best
    assert [e[0][0] if e else None for e in made] == ["casing_path", "sensor_lowpass", None], made
    assert record["name"] == "casing_path" and record["params"] == {"mf": 2.0}, record
    assert record["left_db"] == pytest.approx(record["plain_db"] / 2, abs=0.1), record
    made.clear()
    assert mismatch_of(Run, {"ranking": ranking}) is None and not made  # a simulated target: the simulator's box
    assert mismatch_of(Run, {"chain": {}, "ranking": ranking[:1]}) is None  # the noise alone shapes no line
    # the same effect at its final fit and at round 1's: both compared, told apart by name
    record = mismatch_of(
        Run, {"chain": {}, "ranking": [{**dropped[1], "params": {"mf": 3.0}}], "dropped_effects": dropped}
    )
    assert record["name"] == "casing_path" and record["params"] == {"mf": 2.0}, record


def test_the_verdict_and_the_report_say_why_no_effect_can_be_told():
    record = {"harmonics": 8, "plain_db": 8.1, "left_db": 7.4, "name": "sensor_lowpass"}
    said = verdict_text({"verdict": "unexplained", "unexplained": True, "lines_differ": record})
    assert said.startswith("unexplained: the records' mesh lines differ from the simulator's by 8.1 dB RMS"), said
    assert "and by 7.4 dB beside the fit that matches them best, sensor_lowpass:" in said, said
    assert "no sensor or path effect can be told on these records" in said, said
    views = {"mesh": {"share_before": 0.53}}
    summary = dict(views=views, gap_before=3999.0, gap_after=3999.0, unexplained=True, verdict=said)
    lines = gap_lines({**summary, "dropped": "sensor_noise (final fit: snr_db = 0.7) fitted, then not named"})
    # after the stand-ins' line, which it explains
    assert lines[-2].startswith("Effects sensor_noise (final fit") and lines[-1].endswith("can tell one)."), lines
    assert lines[-1].startswith("The records' mesh lines differ from the simulator's by 8.1 dB RMS"), lines
    assert verdict_text({"verdict": "unexplained", "unexplained": True}) == "unexplained"
