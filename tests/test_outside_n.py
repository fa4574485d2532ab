"""A run-up scored day to day (issue 39 item 6; helper N): a take whose speed runs up or coasts down is scored on its
revolutions at the speed the run's history was taken at, and says so; the rest of it is not scored. The takes are
made here by plain numpy: the mesh tone, noise and tacho of tests/textrecords on a speed that rises linearly."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from detection_scenario import scenario, shared_run
from textrecords import FS, PULSES, record, text, write_zip

from gearlab.kinds import detection_scoring as D
from gearlab.parts import scoring
from gearlab.runs import RunDir

SPEED = 16.0  # Hz: the tiny scenario's history (textrecords)
WORDS = re.compile(r"scored on (\d+) of (\d+) revolutions at ([\d.]+) \.\. ([\d.]+) Hz \(the history's 16\.00 Hz ± ")


def runup(path, start: float, end: float, seconds: float, chip_outside: float = 0.0, seed: int = 5, teeth: int = 32):
    """A take whose speed rises linearly from *start* to *end* Hz over *seconds*: textrecords' mesh tone (order 32)
    and noise; with *chip_outside*, a chipped tooth's ring once a revolution where the speed lies outside the band
    the run's history holds (its in-band revolutions healthy); *teeth*: the mesh order. Returns each whole turn's mean
    speed (Hz)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * FS)) / FS
    rate = (end - start) / seconds
    theta = 0.4 + 2 * np.pi * (start * t + 0.5 * rate * t**2)
    speed = start + rate * t
    vib = np.sin(teeth * theta) + 0.3 * np.sin(2 * teeth * theta + 0.4) + 0.2 * np.sin(theta)
    if chip_outside:
        since = np.mod(theta - 1.0, 2 * np.pi) / (2 * np.pi * speed)
        ring = chip_outside * np.exp(-since * 2000.0) * np.sin(2 * np.pi * 1500.0 * since)
        vib += np.where(np.abs(speed - SPEED) > D.IN_BAND * SPEED, ring, 0.0)
    vib += 0.3 * rng.standard_normal(t.size)
    tacho = np.where(np.mod(theta * PULSES / (2 * np.pi), 1.0) < 0.3, 5.0, 0.05)
    write_zip(path, text(vib, tacho))
    turns = np.arange(np.ceil(theta[0] / (2 * np.pi)), np.floor(theta[-1] / (2 * np.pi)) + 1)
    return 1.0 / np.diff(np.interp(2 * np.pi * turns, theta, t))


@pytest.fixture(scope="module")
def finished(tmp_path_factory, module_cache):
    """A small finished detection run (tests/detection_scenario: two 16 Hz history takes, units revolution,
    record5 and record10), the matched filter beside the classical rows, and its folder for new takes."""
    folder = tmp_path_factory.mktemp("n")
    path = scenario(folder, methods=("matched_filter",))
    return shared_run(path, folder / "runs"), folder


def test_a_run_up_is_scored_on_its_revolutions_at_the_history_s_speed(cli, finished, quiet):
    out, folder = finished
    take = folder / "runup.zip"
    # 14 -> 19 Hz over 12 s: ~30 of its ~200 revolutions within 2.5 % of 16 Hz; the others carry a chipped tooth
    turns = runup(take, 14.0, 19.0, 12.0, chip_outside=4.0)
    inside = int(np.sum(np.abs(turns - SPEED) <= D.IN_BAND * SPEED))
    code, stdout, err = cli("score", out, take, "--json")
    assert code == 0, err
    rows = json.loads(stdout)
    said = {r["scored_on"] for r in rows}
    assert len(said) == 1, said
    (words,) = said
    n, total, low, high = WORDS.match(words).groups()
    assert abs(int(n) - inside) <= 2 and abs(int(total) - len(turns)) <= 2, (words, inside, len(turns))
    assert SPEED * (1 - D.IN_BAND) <= float(low) < float(high) <= SPEED * (1 + D.IN_BAND), words
    by = {(r["method"], r["unit"]): r for r in rows}
    assert by[("matched_filter", "revolution")]["units"] == int(n)  # the in-band revolutions, no other
    assert by[("fm4", "record10")]["units"] == int(n) // 10
    # the chipped revolutions outside the band are not scored: FM4 (the chip's ring once a revolution) calls no TSA
    # (before, the take, its mean speed 16.5 Hz within 5 % of the history's, was scored whole: a fault)
    assert {by[("fm4", u)]["decision"] for u in ("record5", "record10")} == {"healthy"}, words
    assert all(r["speed_hz"] == pytest.approx(SPEED, rel=D.IN_BAND) for r in rows)
    assert "its mean speed is its condition" not in rows[0]["speed_from"] and D.VARIES_WORDS in rows[0]["speed_from"]
    # the history and the report's trend say it; the printout too
    history = [h for h in scoring.read_history(RunDir.open(out)) if h["file"] == str(take)]
    assert history and all(h["scored_on"] == words for h in history)
    titles = "\n".join(c.title for c in D.score_trends(RunDir.open(out)))
    assert words in titles
    code, stdout, err = cli("score", out, take)
    assert code == 0 and words in " ".join(stdout.split()), stdout


def test_a_take_whose_shaft_turns_back_is_scored_on_one_side_and_says_which(cli, finished, quiet):
    # 3 s at 16 Hz, stopped and turned back within 0.2 s, 5 s at -16 Hz: the tacho's marks count the turns back as turns
    # on; scored 'on 79 of 129 revolutions at 16.00 .. 16.00 Hz', the turns back, with no word of it (na4 called the
    # healthy take at record10, 10.6 over 4.56: its averages are the history's run backwards)
    out, folder = finished
    t = np.arange(int(8.2 * FS)) / FS
    hz = np.interp(t, [0, 3.0, 3.1, 3.2, 8.2], [SPEED, SPEED, 0.0, -SPEED, -SPEED])
    theta = 0.3 + 2 * np.pi * np.cumsum(hz) / FS
    vib = (np.sin(32 * theta) + 0.3 * np.sin(64 * theta + 0.4) + 0.2 * np.sin(theta)) * (hz / SPEED) ** 2
    vib += 0.3 * np.random.default_rng(3).standard_normal(t.size)
    tacho = np.where(np.mod(theta * PULSES / (2 * np.pi), 1.0) < 0.3, 5.0, 0.05)
    take = write_zip(folder / "back.zip", text(vib, tacho))
    code, stdout, err = cli("score", out, take, "--json")
    assert code == 0, err
    rows = json.loads(stdout)
    (words,) = {r["scored_on"] for r in rows}
    assert words.startswith("scored on 79 of 129 revolutions at 16.00 .. 16.00 Hz, after the shaft reverses in its ")
    assert "turn of 3 .. 3.15 s (the history's 16.00 Hz" in words, words
    # called (na4, its averages run backwards against the history's): the call doubted, as the run's verdict doubts it
    called = {(r["method"], r["unit"]) for r in rows if r["decision"] == "fault"}
    assert called == {("na4", "record5"), ("na4", "record10")}, called
    assert words.endswith("; the take is called: the call may be the direction, where the history turned the other "
                          "way; record a take turning its way"), words  # fmt: skip
    code, stdout, err = cli("score", out, take)  # the printout says it too
    assert code == 0 and words in " ".join(stdout.split()), stdout


def test_a_take_wholly_outside_the_band_is_refused_in_one_line_with_its_counts(cli, finished, quiet):
    out, folder = finished
    take = folder / "fast.zip"
    # never near 16 Hz; its mesh order the run's description's (meng2020, 25/30), so its speed alone is refused
    runup(take, 20.0, 26.0, 6.0, teeth=25)
    code, _, err = cli("score", out, take)
    line = err.strip()
    assert code == 2 and len(line.splitlines()) == 1, err
    assert "more than 5% from every condition's history" in line and D.VARIES_WORDS in line, line
    assert re.search(
        r"; 0 of its \d+ revolutions within 2\.5% of the history's 16\.00 Hz \('16 Hz'\), a unit needs 1$", line
    )
    assert line.count("expected") == 1 and "its mean speed is its condition" not in line, line
    code, _, err = cli("score", out, take, "--condition", "16 Hz")  # asked: the same rule
    assert code == 2 and len(err.strip().splitlines()) == 1 and "0 of its" in err, err


def test_a_steady_take_is_scored_as_before(cli, finished, quiet, monkeypatch):
    out, folder = finished
    take = record(folder / "steady.zip", revolutions=40, chip=0.0, seed=21, phase=0.9)

    def never(*args, **kwargs):
        raise AssertionError("a steady take was cut to a band")

    monkeypatch.setattr(D, "in_band", never)
    code, stdout, err = cli("score", out, take, "--json")
    assert code == 0, err
    rows = json.loads(stdout)
    assert all(r["scored_on"] is None for r in rows) and D.VARIES_WORDS not in rows[0]["speed_from"]
    assert {r["units"] for r in rows if r["unit"] == "revolution"} == {39}  # every revolution the tacho completes


def test_the_longest_stretch_in_band_and_the_words_of_a_part_too_short_for_a_unit():
    speeds = np.array([16.0, 16.1, 18.0, 15.9, 16.0, 16.2, 17.0, 16.0])
    assert D._stretch(speeds, 16.0) == slice(3, 6)
    assert D._stretch(speeds + 5.0, 16.0) == slice(0, 0)
    meta = {"blocks": [5, 10], "unit_shaft": ["output", 73, 31]}
    said = D._units_of_part(meta, "a.csv", "scored on 3 of 90 input revolutions", 7)
    assert said.endswith("; record10 not scored: a unit needs 10 output-shaft revolutions, it has 7")
    with pytest.raises(D.GearlabInputError, match=r"^a\.csv: scored on .*: 0 output-shaft revolutions, a unit needs 1"):
        D._units_of_part(meta, "a.csv", "scored on 1 of 90 input revolutions", 0)


def test_a_cut_record_keeps_each_revolution_s_speed(tmp_path):
    from gearlab.data.recordings import cut_recording

    turns = runup(tmp_path / "r.zip", 14.0, 19.0, 4.0)
    rec = cut_recording(tmp_path / "r.zip", vibration=0, tacho="2", pulses_per_rev=PULSES, fs=FS)
    assert len(rec.speeds) == len(rec.revolutions) and D.VARIES_WORDS in rec.angle_source
    # each revolution's speed from the tacho's marks: the take's own, whichever mark its revolutions start at, within
    # 0.1 Hz (0.6 %, a mark read to a sample: 1/512 of a turn at 16 Hz), a quarter of the band's half-width
    assert 14.0 <= rec.speeds[0] < rec.speeds[0] + 4.0 < rec.speeds[-1] <= 19.0
    assert np.max(np.min(np.abs(rec.speeds[:, None] - turns[None, :]), axis=1)) < 0.1
    assert abs(len(rec.speeds) - len(turns)) <= 1
