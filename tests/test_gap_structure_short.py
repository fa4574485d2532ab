"""The gap's structure check on records too short to tell a wheel's tooth count (issue 39, outside user
round 10, box D: 43/89 described with an 88-tooth wheel, three records of ~52 turns). `gearlab inspect`
said 'not checked: the tooth count of the wheel ... need 103 to tell a tooth more or less'; the gap run
said 'UNEXPLAINED' with no word that the wheel was never checked. The structure line now says what
passed unchecked, in inspect's words (gearbox.match.check_description's decision, not a second one)."""

import numpy as np
from gearboxes import described_pair

from gearlab.data.chain import Chain
from gearlab.gap.structure import _lines, _PairDescription, structure_line
from gearlab.gearbox.match import check_description, unchecked
from gearlab.kinds.gap_verdict import gap_lines

Z1, Z2, SPEED, POINTS = 43, 89, 9.0, 1024


def take(n: int, phase: float, seed: int) -> np.ndarray:
    """*n* input turns of a 43/89 record at uniform input angle (tacho on the input): the mesh's harmonics
    1-3 modulated by both shafts, the output shaft at its own phase where the record starts."""
    theta = 2 * np.pi * np.arange(n * POINTS) / POINTS
    mod = 1 + 0.1 * np.cos(Z1 / Z2 * theta + phase) + 0.2 * np.cos(theta + 0.3)
    x = sum(a * mod * np.cos(h * Z1 * theta + 0.6 * h) for h, a in ((1, 1.0), (2, 0.4), (3, 0.2)))
    return (x + np.random.default_rng(seed).normal(0, 0.05, x.size)).reshape(n, POINTS)


def records(turns: tuple[int, ...]) -> tuple[np.ndarray, Chain]:
    rows = np.concatenate([take(n, 1.0 + 2.1 * k, 30 + k) for k, n in enumerate(turns)])
    takes = turns if len(turns) > 1 else ()
    return rows, Chain(fs=POINTS * SPEED, speed=SPEED, tacho_shaft="input", takes=takes)


def test_a_wheel_too_few_turns_tell_is_said_unchecked_in_inspect_s_words():
    rows, chain = records((52, 52, 53))
    record: dict = {}
    assert structure_line(rows, described_pair((Z1, 88)), 400, chain, None, record) is None  # passes, unchecked
    line = record["unchecked"]["line"]
    assert line.startswith("structure not fully checked: the tooth count of the wheel on the output shaft ("), line
    assert "53 input revolutions, need " in line and "to tell a tooth more or less" in line, line
    longest = "within one record (the longest of 3: records laid end to end are in register on the input shaft only)"
    assert line.endswith(longest), line
    need = int(line.split("need ")[1].split(" ")[0])
    assert 53 < need <= 300, need  # the long record below tells it
    # the items are inspect's: its 'not checked' list on the longest record read against the description
    box = _PairDescription.of(Z1, 88)
    inspected = unchecked(check_description(_lines(rows[104:], 400), box, 53, True), box, None)
    assert record["unchecked"]["items"] and set(record["unchecked"]["items"]) <= set(inspected), inspected
    # the report's and the CLI's verdict lines carry it after the verdict
    summary = {
        "gap_before": 7.66e4,
        "gap_after": 7.66e4,
        "p_before": 0.005,
        "p_after": 0.005,
        "significant_before": True,
        "significant_after": True,
        "unexplained": True,
        "verdict": "unexplained",
        "views": {"mesh": {"share_before": 0.43}},
        "ranking": [{"name": "casing_path", "share_removed": 0.70, "params": {}}],
        "effects": [],
        "structure": {"unchecked": record["unchecked"]},
    }
    said = gap_lines(summary)
    assert said[1].startswith("UNEXPLAINED: no candidate effect closes the gap")
    assert said[2] == f"S{line[1:]}.", said
    assert not any("not fully checked" in s for s in gap_lines({**summary, "structure": {}}))


def test_records_long_enough_tell_the_wheel():
    rows, chain = records((300,))
    record: dict = {}
    line = structure_line(rows, described_pair((Z1, 88)), 400, chain, None, record)
    # read outward from the input's tacho, as an output tacho's line reads (issue 39: one wording)
    assert line is not None and line.startswith("stage 1 wheel: 89 teeth fit the recording, 88 described"), line
    assert "the wheel shows 89.0" in line, line
    right: dict = {}
    assert structure_line(rows, described_pair((Z1, Z2)), 400, chain, None, right) is None
    assert "unchecked" not in right, right["unchecked"]
