"""Outside user BF (issue 39): a 19/47 + 29/71 reducer whose tacho pulses once per output turn, described with the
tacho on the input ([sensor] tacho = "input"). Read so, every order reads 6.056 x its own and the speed 1/6.056 of
the true: the detection run stopped with 'the history of condition '6.7 Hz' gives 2 'record30' units (its longest
record has 32 intermediate-shaft revolutions); expected at least 8: longer records, or shorter [detection]
blocks', the records' length blamed, before the structure check that names the tacho's shaft could run. A history
too short for its units is now first checked against the description. The takes are made here with numpy
(tests/test_inspect_tacho_misread.py's recording), 6 s each."""

from __future__ import annotations

from gearboxes import description, stage
from test_inspect_tacho_misread import STAGES, _record


def _scenario(tmp_path, tacho: str, seconds: float = 6.0) -> str:
    (tmp_path / "box.toml").write_text(
        description(
            stage(*STAGES[0]), stage(*STAGES[1], module="3 mm"), name="bf", speed="2400 rpm", load="80 N*m", tacho=tacho
        )
    )
    for i, name in enumerate(("h1", "h2", "t1", "t2")):
        _record(tmp_path / f"{name}.npz", tacho_shaft=2, marks=1, seconds=seconds, seed=10 + i)
    files = [f'{{ file = "{n}.npz", role = "history", label = "healthy" }}' for n in ("h1", "h2")]
    tests = (("t1", "healthy"), ("t2", "fault"))
    files += [f'{{ file = "{n}.npz", role = "test", label = "{label}" }}' for n, label in tests]
    path = tmp_path / "detect.toml"
    path.write_text(
        '[scenario]\nname = "bf"\nkind = "detection"\n[source]\ngearbox = "box.toml"\n'
        'faults = { "chip@intermediate gear" = [18] }\nhealthy = 8\n'
        '[target]\nvibration = "acc_ms2"\ntacho = "tach"\nfiles = [\n' + ",\n".join(files) + ",\n]\n"
        '[[methods]]\nadapter = "matched_filter"\n'
    )
    return path


def test_a_history_too_short_for_its_units_because_the_tacho_is_misread_is_told_the_tacho(tmp_path, cli):
    code, out, err = cli("run", _scenario(tmp_path, "input"), "--out", tmp_path / "runs", "--quick")
    assert code == 2, out + err
    (line,) = [x for x in err.strip().splitlines() if x.startswith("error:")]
    assert "[source] key 'gearbox': the history of condition" in line, line
    assert "the tacho reads the output shaft? give [target] tacho_shaft = 'output'" in line, line
    assert "longer records" not in line, line


def test_a_history_too_short_with_the_tacho_read_right_is_told_its_length(tmp_path, cli):
    # 2 s takes read by their output tacho: 32 intermediate-shaft turns each, one record30 unit (8 asked)
    code, out, err = cli("run", _scenario(tmp_path, "output", seconds=2.0), "--out", tmp_path / "runs", "--quick")
    assert code == 2, out + err
    (line,) = [x for x in err.strip().splitlines() if x.startswith("error:")]
    assert "[target] key 'files': the history of condition" in line and "longer records" in line, line
