"""A [target] 'files' entry's 'file' may be a glob pattern (*, ?, [...], ** across folders): one
record per matched file, sorted by name, each with the entry's other keys (issue 39: a folder of
takes in a scenario of under 30 lines). A pattern matching nothing is one line, exit 2;
`gearlab validate` counts what each pattern matched; a resume refuses a file a pattern matches
that the run did not read."""

from __future__ import annotations

import numpy as np
import pytest

from gearlab.engine import load_scenario
from gearlab.errors import GearlabInputError
from gearlab.parts.measured import target_spec
from gearlab.runs import check_inputs, input_digests

FS, SPEED = 6400.0, 25.0
BOX = (
    '[gearbox]\nname = "b"\n[operation]\nspeed = "25 Hz"\nload = "40 N*m"\n'
    '[[stages]]\nmodule = "2 mm"\nface_width = "20 mm"\n'
    'pinion = { z = 21, bore = "20 mm" }\nwheel = { z = 53, bore = "30 mm" }\n'
)
HISTORY = ("history/take2.csv", "history/take1.csv", "history/2026/take3.csv")
TEST = ("test/a.csv", "test/b.csv")


def _take(path, amplitude: float) -> None:
    t = np.arange(int(FS * 2.0)) / FS
    x = amplitude * np.sin(2 * np.pi * 21 * SPEED * t) + 0.5 * np.sin(2 * np.pi * SPEED * t)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(f"# fs = {FS:g}\nacc\n" + "".join(f"{v:.6f}\n" for v in x))


@pytest.fixture
def folder(tmp_path):
    for i, name in enumerate(HISTORY + TEST):
        _take(tmp_path / name, 1.0 + 0.1 * i)
    (tmp_path / "history" / "notes.txt").write_text("not a take")
    (tmp_path / "box.toml").write_text(BOX)
    return tmp_path


def _files(history: str, test: str) -> str:
    return (
        f'files = [{{ file = "{history}", role = "history", label = "healthy" }}, '
        f'{{ file = "{test}", role = "test", label = "unknown", unit = "g" }}]\n'
    )


def _detection(folder, files: str):
    text = (
        '[scenario]\nname = "d"\nkind = "detection"\n[source]\ngearbox = "box.toml"\nfaults = { chip = [20] }\n'
        '[target]\nvibration = "acc"\nunit = "m/s^2"\nspeed = "25 Hz"\npositive = "fault"\n' + files
    )
    (folder / "d.toml").write_text(text)
    return folder / "d.toml"


def _table(history: str, test: str) -> dict:
    files = [
        {"file": history, "role": "history", "label": "healthy"},
        {"file": test, "role": "test", "label": "unknown", "unit": "g"},
    ]
    table = {"vibration": "acc", "tacho": "", "tacho_shaft": "", "speed": "25 Hz", "gearbox": "", "files": files}
    table |= {"transient": "none", "positive": "fault", "unit": "m/s^2"}
    return table | {k: None for k in ("pulses_per_rev", "sensitivity", "gain", "fs")}


def test_a_pattern_stands_for_each_file_it_matches_sorted_with_the_entry_s_keys(folder):
    files = target_spec(_table("history/**/*.csv", "test/?.csv"), "d.toml: [target]", folder).files
    assert [f.path for f in files] == [
        "history/2026/take3.csv",
        "history/take1.csv",
        "history/take2.csv",
        "test/a.csv",
        "test/b.csv",
    ]
    assert [f.resolved for f in files] == [str(folder / f.path) for f in files]
    assert [f.role for f in files] == ["history"] * 3 + ["test"] * 2
    assert {f.label for f in files if f.role == "test"} == {"unknown"}
    assert all(dict(f.keys) == {"unit": "g"} for f in files if f.role == "test")  # the entry's own key
    assert all(f.keys == () for f in files if f.role == "history")
    # '*' keeps to its folder (take3 is a folder below), '[...]' picks by a character, notes.txt is no csv
    one = target_spec(_table("history/*.csv", "test/[a].csv"), "w", folder).files
    assert [f.path for f in one] == ["history/take1.csv", "history/take2.csv", "test/a.csv"]
    # an absolute pattern gives absolute names
    absolute = target_spec(_table(f"{folder}/history/*.csv", "test/b.csv"), "w", folder).files
    assert [f.path for f in absolute][:2] == [str(folder / "history/take1.csv"), str(folder / "history/take2.csv")]
    assert [f.pattern for f in absolute] == [f"{folder}/history/*.csv"] * 2 + [""]


def test_a_globbed_scenario_reads_as_the_same_files_listed_one_by_one(folder):
    history = [f'{{ file = "{n}", role = "history", label = "healthy" }}' for n in sorted(HISTORY)]
    test = [f'{{ file = "{n}", role = "test", label = "unknown", unit = "g" }}' for n in TEST]
    listed = ", ".join(history + test)
    by_name = load_scenario(_detection(folder, f"files = [{listed}]\n")).spec.target.files
    globbed = load_scenario(_detection(folder, _files("history/**/take*.csv", "test/*.csv"))).spec.target.files
    assert [(f.path, f.resolved, f.role, f.label, f.keys) for f in globbed] == [
        (f.path, f.resolved, f.role, f.label, f.keys) for f in by_name
    ]


def test_validate_counts_what_each_pattern_matched(cli, folder):
    code, out, err = cli("validate", _detection(folder, _files("history/**/*.csv", "test/*.csv")))
    flat = " ".join((out + err).split())
    assert code == 0, out + err
    assert "5 measured records (3 history, 2 test; 'history/**/*.csv': 3 files, 'test/*.csv': 2 files)" in flat
    gap = (
        '[scenario]\nname = "g"\nkind = "gap"\n[source]\ngearbox = "box.toml"\n'
        '[target]\nvibration = "acc"\nunit = "m/s^2"\nspeed = "25 Hz"\n'
        'files = [{ file = "history/take*.csv", role = "history", label = "healthy" }]\n'
        "[accuracy]\nenabled = false\n"
    )
    (folder / "g.toml").write_text(gap)
    code, out, err = cli("validate", folder / "g.toml")
    assert code == 0, out + err
    assert "2 measured history records ('history/take*.csv': 2 files)" in " ".join((out + err).split())


def test_a_pattern_matching_no_file_is_one_line_and_exit_2(cli, folder):
    path = _detection(folder, _files("history/*.csv", "test/*.wav"))
    code, out, err = cli("validate", path)
    assert code == 2
    line = f"{path}: [target] key 'files' entry 2 key 'file': 'test/*.wav' matches no file"
    assert err.splitlines() == [f"error: {line}"], err
    with pytest.raises(GearlabInputError, match=r"^w key 'files' entry 1 key 'file': 'h/\*\.csv' matches no file$"):
        target_spec(_table("h/*.csv", "test/*.csv"), "w", folder)


def test_a_file_named_twice_through_a_pattern_names_both_entries(folder):
    table = _table("history/*.csv", "test/a.csv")
    table["files"].insert(1, {"file": "history/take2.csv", "role": "history", "label": "healthy"})
    with pytest.raises(GearlabInputError, match=r"entry 2: history/take2.csv is listed twice \(entry 1\)$"):
        target_spec(table, "w", folder)


class _Run:
    """A run directory as check_inputs reads it: its run.json's inputs."""

    def __init__(self, inputs, path):
        self.inputs, self.path = inputs, path

    def meta(self):
        return {"inputs": self.inputs}


def test_a_resume_refuses_a_take_a_pattern_matches_that_the_run_did_not_read(folder):
    scenario = load_scenario(_detection(folder, _files("history/*.csv", "test/*.csv")))
    run = _Run(input_digests(scenario), folder / "runs" / "d")
    assert {str(folder / n) for n in ("history/take1.csv", "history/take2.csv", *TEST)} <= set(run.inputs)
    check_inputs(run, scenario)  # nothing new: resumed
    _take(folder / "test" / "c.csv", 2.0)
    with pytest.raises(GearlabInputError, match=r"test/c.csv: a file the scenario names .* did not read"):
        check_inputs(run, scenario)


def test_a_message_on_a_pattern_entry_s_key_names_the_entry_as_written(folder):
    table = _table("history/*.csv", "test/*.csv")  # entry 1: two files; entry 2: the third and fourth
    table["files"][1]["label"] = "faulty"
    with pytest.raises(GearlabInputError, match=r"^w key 'files' entry 2 key 'label': 'faulty' is not the positive"):
        target_spec(table, "w", folder)
    table["files"][1] |= {"label": "fault", "speed": "25 Hz", "tacho": "acc"}
    with pytest.raises(GearlabInputError, match=r"^w key 'files' entry 2 key 'vibration': the same column as the"):
        target_spec(table, "w", folder)


def test_the_tui_validates_a_scenario_again_when_a_take_joins_its_pattern_s_folder(folder):
    from gearlab.tui.catalog import Validated

    path = _detection(folder, _files("history/*.csv", "test/*.csv"))
    validated = Validated()
    assert len(validated.scenario(path).spec.target.files) == 4
    _take(folder / "test" / "c.csv", 2.0)
    assert len(validated.scenario(path).spec.target.files) == 5


def _dataset(folder, file: str, name: str = "") -> object:
    text = '[scenario]\nname = "ds"\nkind = "dataset"\n[[datasets]]\n' + f'file = "{file}"\nvibration = "acc"\n'
    text += 'unit = "m/s^2"\nspeed = "25 Hz"\n' + (f'name = "{name}"\n' if name else "")
    (folder / "ds.toml").write_text(text)
    return folder / "ds.toml"


def _gap(folder, file: str) -> object:
    text = (
        '[scenario]\nname = "g"\nkind = "gap"\n[source]\ngearbox = "box.toml"\n'
        f'[target]\nfile = "{file}"\nvibration = "acc"\nunit = "m/s^2"\nspeed = "25 Hz"\n[accuracy]\nenabled = false\n'
    )
    (folder / "g.toml").write_text(text)
    return folder / "g.toml"


def test_a_dataset_entry_s_pattern_stands_for_a_dataset_of_each_file(folder):
    """[[datasets]] file = pattern: one measured dataset per matched file, named by its file (before: the
    pattern was read as a file's name, 'no such file')."""
    specs = load_scenario(_dataset(folder, "history/*.csv")).spec
    assert [(s.name, s.path) for s in specs] == [(n, str(folder / f"history/{n}.csv")) for n in ("take1", "take2")]
    one = load_scenario(_dataset(folder, "test/[a].csv", name="first")).spec
    assert [(s.name, s.path) for s in one] == [("first", str(folder / "test/a.csv"))]


def test_a_single_file_key_reads_the_one_file_its_pattern_matches(folder):
    """A gap [target]'s 'file' (a key of one record, as a transfer's): a pattern of one file reads it."""
    target = load_scenario(_gap(folder, "test/[b].csv")).spec.target
    assert target.path == str(folder / "test/b.csv")


@pytest.mark.parametrize(
    "make, pattern, line",
    [
        (_gap, "history/*.csv", "[target] key 'file': 'history/*.csv' matches 2 files (history/take1.csv, history/"),
        (_gap, "test/*.wav", "[target] key 'file': 'test/*.wav' matches no file"),
        (_dataset, "test/*.wav", "[[datasets]] #1 key 'file': 'test/*.wav' matches no file"),
        (
            lambda f, p: _dataset(f, p, name="x"),
            "test/*.csv",
            "[[datasets]] #1 key 'name': 'x' names one dataset, and 'test/*.csv' matches 2 files",
        ),
    ],
)
def test_a_pattern_a_single_file_key_cannot_read_is_one_line_and_exit_2(cli, folder, make, pattern, line):
    path = make(folder, pattern)
    code, out, err = cli("validate", path)
    assert code == 2, out + err
    assert len(err.splitlines()) == 1 and err.startswith(f"error: {path}: {line}"), err
