"""A tacho read on another shaft AND with another count of marks a turn (issue 39, an outside user's 19/47 + 29/71
reducer: a 1-mark tacho on the output shaft described as an input tacho of 2 marks): every order reads 12.11 x its
own. `gearlab inspect` named the tacho's shaft and marks (gearlab.inspect_tacho), but the gap diagnosis and a
detection run's check of its history against the description said 'stage 1 pinion: 230 teeth fit the recording,
19 described': a tooth count, not the tacho. Both now say the tacho line, read by the same inspect_tacho.misread.
The takes are made here with numpy (tests/test_inspect_tacho_misread.py's recording), 6 s each."""

from __future__ import annotations

import json

from gearboxes import description, stage
from test_inspect_tacho_misread import STAGES, _record

TACHO = "every order reads 12.11 x its own, as when a tacho on the output shaft is read as on the input: the tacho "
TACHO += "reads the output shaft? with "


def _box(tmp_path) -> None:
    # described: a tacho of 2 marks a turn on the input shaft ([sensor] pulses_per_rev, what the records are read with)
    text = description(
        stage(*STAGES[0]), stage(*STAGES[1], module="3 mm"), name="bi", speed="2400 rpm", load="80 N*m", tacho="input"
    )
    (tmp_path / "box.toml").write_text(text + "pulses_per_rev = 2\n")
    for i, name in enumerate(("h1", "h2", "t1", "t2")):  # a 1-mark tacho on the output shaft
        _record(tmp_path / f"{name}.npz", tacho_shaft=2, marks=1, seed=20 + i)


def _files(names) -> str:
    return ",\n".join(f'{{ file = "{n}.npz", role = "{role}", label = "{label}" }}' for n, role, label in names)


def test_a_detection_run_names_the_tacho_s_shaft_and_marks_not_a_tooth_count(tmp_path, cli):
    _box(tmp_path)
    files = _files((("h1", "history", "healthy"), ("h2", "history", "healthy"), ("t1", "test", "healthy")))
    path = tmp_path / "detect.toml"
    path.write_text(
        '[scenario]\nname = "bi"\nkind = "detection"\n[source]\ngearbox = "box.toml"\n'
        'faults = { "chip@intermediate gear" = [18] }\nhealthy = 8\n'
        '[target]\nvibration = "acc_ms2"\ntacho = "tach"\nfiles = [\n' + files + ',\n  { file = "t2.npz", role = '
        '"test", label = "fault" },\n]\n[[methods]]\nadapter = "matched_filter"\n'
    )
    code, out, err = cli("run", path, "--out", tmp_path / "runs", "--quick")
    assert code == 2, out + err
    (line,) = [x for x in err.strip().splitlines() if x.startswith("error:")]
    assert "[source] key 'gearbox': the history of condition" in line, line
    # the read count known (the description's 2): the marks named as a count, as inspect names them
    # a run has no inspect options: the keys of the scenario table that holds the records, with their values
    said = TACHO + "1 pulse(s) per revolution, not 2? ([target] tacho_shaft = 'output', pulses_per_rev = 1)"
    assert said in line, line
    assert "stage 1: mesh order 230.1 measured, 19 expected" in line, line
    assert "teeth" not in line, line


def test_the_gap_diagnosis_names_the_tacho_s_shaft_and_marks_not_a_tooth_count(tmp_path, cli):
    _box(tmp_path)
    path = tmp_path / "gap.toml"
    path.write_text(
        '[scenario]\nname = "bi_gap"\nkind = "gap"\n[source]\ngearbox = "box.toml"\n'
        '[target]\nvibration = "acc_ms2"\ntacho = "tach"\nfiles = [\n'
        + _files((("h1", "history", "healthy"), ("h2", "history", "healthy")))
        + ',\n]\n[diagnosis]\ncandidates = ["sensor_noise", "sensor_bandwidth", "casing_path"]\n'
        "[accuracy]\nenabled = false\n"
    )
    code, out, err = cli("run", path, "--out", tmp_path / "runs", "--quick")
    assert code == 0, out + err
    (summary,) = (tmp_path / "runs").rglob("summary.json")
    result = json.loads(summary.read_text())
    verdict = result["verdict"]
    assert verdict.startswith("structure differs: stage 1: mesh order 230.1 measured, 19 expected"), verdict
    # the count read (the description's 2, Chain.pulses_per_rev): the marks named as a count, as inspect names them
    said = TACHO + "1 pulse(s) per revolution, not 2? ([target] tacho_shaft = 'output', pulses_per_rev = 1)"
    assert said in verdict, verdict
    assert "teeth" not in verdict, verdict
    assert result["structure"]["tacho"]["shaft"] == "output", result["structure"]
    assert result["structure"]["tacho"]["marks_read_over_given"] == 2.0, result["structure"]
    assert abs(result["structure"]["tacho"]["factor"] - 12.11) < 0.01, result["structure"]
    assert any(line.startswith("note: structure differs: stage 1: mesh order 230.1") for line in out.splitlines()), out
