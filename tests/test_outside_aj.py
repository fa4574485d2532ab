"""Outside user AJ (issue 39 leftover): a run-up or coast-down without a tacho, a gearbox description giving its speed
from the mesh lines. A 14 -> 19 Hz run-up over 12 s (a 32/96 box) was read at 0.506 Hz: its mesh line smeared over a
30 % sweep, the narrow 1x shaft line was taken for the mesh, and 6 'revolutions' were kept. The take's speed is now
followed on its mesh line along its course, and a detection run's history, read without a tacho, scores its
revolutions at the history's speed."""

from __future__ import annotations

import json

import numpy as np
import pytest
from gearboxes import description, stage
from test_outside_n import WORDS, runup
from textrecords import FS, text, write_zip

from gearlab.data.recordings import cut_recording
from gearlab.gearbox import load_gearbox
from gearlab.kinds import detection_scoring as D
from gearlab.signals.checks import VARIES_WORDS

SPEED = 16.0  # Hz: the description's and the tiny detection run's history


def _two_stage(path, start: float, end: float, seconds: float) -> np.ndarray:
    """A 27/83 + 19/67 take whose speed moves linearly from *start* to *end* Hz over *seconds* (textrecords' format,
    its tacho column flat): both meshes and their 2nd harmonics, the 1x line, noise. Each whole turn's speed (Hz)."""
    t = np.arange(int(seconds * FS)) / FS
    theta = 0.4 + 2 * np.pi * (start * t + 0.5 * (end - start) / seconds * t**2)
    mid = theta * 27 / 83
    vib = 0.2 * np.sin(theta) + np.sin(27 * theta) + 0.3 * np.sin(54 * theta + 0.4)
    vib += 0.6 * np.sin(19 * mid + 1.0) + 0.2 * np.sin(38 * mid)
    vib += 0.3 * np.random.default_rng(3).standard_normal(t.size)
    write_zip(path, text(vib, np.zeros(t.size)))
    turns = np.arange(np.ceil(theta[0] / (2 * np.pi)), np.floor(theta[-1] / (2 * np.pi)) + 1)
    return 1.0 / np.diff(np.interp(2 * np.pi * turns, theta, t))


def _box(path, *stages) -> str:
    path.write_text(description(*(stage(*s) for s in stages), speed=f"{SPEED:g} Hz", near="input"))
    return str(path)


@pytest.mark.parametrize(
    "start, end, seconds, stages, declared",
    [
        (14.0, 19.0, 12.0, 1, None),  # the take: was 0.506 Hz, 6 revolutions
        (14.0, 19.0, 12.0, 1, SPEED),  # a declared speed: was read at 16 Hz whole, 191 'revolutions' all in band
        (19.0, 14.0, 8.0, 1, None),  # a coast-down: was refused, 'no line ... fits a mesh order'
        (20.0, 14.0, 3.0, 1, None),  # swept 190 Hz inside the tracking band: was refused too
        (12.0, 20.0, 8.0, 2, None),  # 50 %, two stages: was read 15.4 .. 16.6 Hz, 98 of 127 in band (13)
    ],
)
def test_a_run_up_without_a_tacho_is_followed_on_its_mesh_line(tmp_path, start, end, seconds, stages, declared):
    path = tmp_path / "take.zip"
    if stages == 1:
        turns, box = runup(path, start, end, seconds), _box(tmp_path / "box.toml", (32, 96))
    else:
        turns, box = _two_stage(path, start, end, seconds), _box(tmp_path / "box.toml", (27, 83), (19, 67))
    rec = cut_recording(str(path), vibration=0, fs=FS, gearbox=load_gearbox(box), speed_hz=declared)
    said = rec.angle_source
    assert said.startswith("speed followed on the mesh phase") and VARIES_WORDS in said, said
    assert rec.speed_hz == pytest.approx(0.5 * (start + end), rel=0.005), said  # the mean over time
    assert abs(len(rec.revolutions) - len(turns)) <= 1, (len(rec.revolutions), len(turns))
    # each revolution's speed, as the history's band cuts it: the take's range, the same count in band
    assert rec.speeds.min() == pytest.approx(turns.min(), rel=0.01) and rec.speeds.max() == pytest.approx(
        turns.max(), rel=0.01
    ), (rec.speeds.min(), rec.speeds.max(), turns.min(), turns.max())
    inside = [int(np.sum(np.abs(s / SPEED - 1) <= D.IN_BAND)) for s in (rec.speeds, turns)]
    assert abs(inside[0] - inside[1]) <= 1, inside


def test_a_run_up_then_steady_take_is_followed_at_its_speed_not_half(tmp_path):
    # 8 -> 16 Hz in 1 s, then 2 s steady (test_outside_ae's history take) without its tacho: read along the angle
    # followed, its lines fit half the speed too, and the reading swung between the two: a constant 7.33 Hz, 21
    # 'revolutions'. The speed followed is the fundamental of that family
    speed = np.concatenate([np.linspace(8.0, 16.0, int(FS), endpoint=False), np.full(int(2 * FS), 16.0)])
    theta = 0.4 + 2 * np.pi * np.cumsum(speed) / FS
    vib = np.sin(32 * theta) + 0.3 * np.sin(64 * theta + 0.4) + 0.2 * np.sin(theta)
    vib += 0.3 * np.random.default_rng(5).standard_normal(theta.size)
    write_zip(tmp_path / "take.zip", text(vib, np.zeros(theta.size)))
    box = load_gearbox(_box(tmp_path / "box.toml", (32, 96)))
    rec = cut_recording(str(tmp_path / "take.zip"), vibration=0, fs=FS, gearbox=box)
    assert rec.speed_hz == pytest.approx(speed.mean(), rel=0.005), rec.angle_source
    assert abs(len(rec.revolutions) - 43) <= 1 and rec.angle_source.startswith("speed followed"), rec.angle_source
    assert abs(int(np.sum(np.abs(rec.speeds / SPEED - 1) <= D.IN_BAND)) - 33) <= 1, rec.speeds


def test_gearlab_score_cuts_a_run_up_without_a_tacho_to_the_history_s_speed(cli, tmp_path, no_figures):
    # a tiny detection run whose takes have no tacho column read (the speed from the description's mesh lines), then
    # `gearlab score` of the 14 -> 19 Hz run-up over 12 s: scored on its revolutions within 2.5 % of 16 Hz, as
    # with a tacho (was: read at 0.506 Hz). (A chip ringing outside the band, test_outside_n's, gave lines enough)
    from detection_scenario import run, scenario
    from textrecords import PULSES

    box = _box(tmp_path / "box.toml", (32, 96))
    path = scenario(tmp_path, methods=("matched_filter",))
    path.write_text(path.read_text().replace(f'tacho = "2"\npulses_per_rev = {PULSES}\n', f'gearbox = "{box}"\n'))
    out = run(cli, path, tmp_path / "runs")
    take = tmp_path / "runup.zip"
    turns = runup(take, 14.0, 19.0, 12.0)
    inside = int(np.sum(np.abs(turns / SPEED - 1) <= D.IN_BAND))
    code, stdout, err = cli("score", out, take, "--json")
    assert code == 0, err
    rows = json.loads(stdout)
    (words,) = {r["scored_on"] for r in rows}
    n, total, low, high = WORDS.match(words).groups()
    assert abs(int(n) - inside) <= 2 and abs(int(total) - len(turns)) <= 2, (words, inside, len(turns))
    assert SPEED * (1 - D.IN_BAND) <= float(low) < float(high) <= SPEED * (1 + D.IN_BAND), words
    by = {(r["method"], r["unit"]): r for r in rows}
    assert by[("matched_filter", "revolution")]["units"] == int(n) and by[("fm4", "record10")]["units"] == int(n) // 10
    # a steady history take keeps its path: the course's reach widens only where a take's ends show its speed move
    steady = cut_recording(str(tmp_path / "data" / "h1.zip"), vibration=0, fs=FS, gearbox=load_gearbox(box))
    assert steady.speed_hz == pytest.approx(SPEED, rel=1e-4) and len(steady.revolutions) == 39, steady.angle_source
    assert VARIES_WORDS not in steady.angle_source, steady.angle_source


def test_a_detection_run_cuts_a_run_up_test_take_without_a_tacho_to_the_history_s_speed(tmp_path):
    # the same take as a detection run's test take, the [target] without a tacho, its speed from the description's mesh
    # lines: cut to its revolutions in the history's band, as with a tacho (was: read whole at 0.506 Hz, 6 revolutions)
    from detection_scenario import scenario
    from textrecords import PULSES

    from gearlab.kinds.detection_records import read_target
    from gearlab.notebook import load_scenario

    box = _box(tmp_path / "box.toml", (32, 96))
    (tmp_path / "data").mkdir()
    turns = runup(tmp_path / "data" / "up.zip", 14.0, 19.0, 12.0)
    files = [("h1", "history", "healthy", 0.0), ("h2", "history", "healthy", 0.0), ("up", "test", "healthy", 0.0)]
    path = scenario(tmp_path, files=files, methods=("matched_filter",))
    path.write_text(path.read_text().replace(f'tacho = "2"\npulses_per_rev = {PULSES}\n', f'gearbox = "{box}"\n'))
    spec = load_scenario(path).spec
    ((_, cond),) = read_target(spec.target, spec.detection.blocks, lambda e: None, "here").items()
    (warning,) = [w for w in cond["warnings"] if w.startswith("../data/up.zip")]
    inside = int(np.sum(np.abs(turns / SPEED - 1) <= D.IN_BAND))
    n, total, low, high = WORDS.match(warning.split("; ", 1)[1]).groups()
    assert abs(int(n) - inside) <= 2 and abs(int(total) - len(turns)) <= 2, (warning, inside, len(turns))
    assert SPEED * (1 - D.IN_BAND) <= float(low) < float(high) <= SPEED * (1 + D.IN_BAND), warning
    assert "read whole at one speed" not in warning, warning
