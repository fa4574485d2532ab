"""The TUI validates a scenario once per state of its files (gearlab.tui.catalog.Validated): moving
through the tree, back and forth, and a rescan of unchanged files validate nothing again; an
edited scenario, an edited file it names, or `Validate` in the palette do."""

from __future__ import annotations

import os
import shutil

import pytest
from test_tui import STIFFNESS, checked, drive
from textual.widgets import Tree

from gearlab.errors import GearlabInputError
from gearlab.tui import GearlabApp, catalog


@pytest.fixture
def validations(monkeypatch):
    """Each call of the TUI's load_scenario: the file's name, or 'run <stamp>' for a run's."""
    calls, real = [], catalog.load_scenario

    def spy(path=None, *, run=None):
        calls.append(f"run {run.path.name}" if run is not None else path.name)
        return real(path, run=run)

    monkeypatch.setattr(catalog, "load_scenario", spy)
    return calls


def later(path, seconds: int = 5) -> None:
    """Move a file's modification time on: an edit within the file system's clock tick looks the same."""
    stat = path.stat()
    os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns + seconds * 10**9))


def test_moving_through_the_tree_validates_each_scenario_and_run_once(tmp_path, monkeypatch, validations):
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)
    folder = tmp_path / "scenarios"
    folder.mkdir()
    (folder / "stiff.toml").write_text(STIFFNESS.replace("{runs}", str(tmp_path / "runs")))
    (folder / "tail.toml").write_text(
        STIFFNESS.replace('name = "stiff"', 'name = "other"').replace("{runs}", str(tmp_path / "runs"))
    )
    run = tmp_path / "runs" / "stiff" / "20260101-000000-000000"
    run.mkdir(parents=True)
    shutil.copy(folder / "stiff.toml", run / "scenario.toml")

    async def script(pilot):
        app = pilot.app
        tree = app.query_one("#browser", Tree)
        tree.focus()
        assert sorted(validations) == ["stiff.toml", "tail.toml"]
        assert tree.cursor_node.data.path.name == "stiff.toml"
        await pilot.press("right")  # unfold stiff.toml
        for _ in range(2):  # down to its run, then to tail.toml, and back up twice
            for key in ("down", "down", "up", "up"):
                await pilot.press(key)
                await pilot.pause()
        assert tree.cursor_node.data.path.name == "stiff.toml"
        assert "20260101-000000-000000" in str(app.query_one("#results-status").render())  # the run was shown
        assert sorted(validations) == ["run 20260101-000000-000000", "stiff.toml", "tail.toml"]
        await pilot.press("f5")  # nothing changed: nothing validated again
        await pilot.pause()
        assert len(validations) == 3
        (folder / "tail.toml").write_text((folder / "tail.toml").read_text().replace("crack ladder", "edited"))
        later(folder / "tail.toml")
        await pilot.press("f5")
        await checked(pilot)  # the edited file only, in the background
        assert validations[3:] == ["tail.toml"]
        tail = next(n for n in tree.root.children if n.data.path.name == "tail.toml")
        assert tail.data.scenario.description == "edited"
        app._validate(tail.data)  # the palette's Validate reads the file afresh
        await app.workers.wait_for_complete()  # in a worker thread
        await checked(pilot)  # its end rescans: the file, forgotten, validated again for its mark
        assert validations[4:] == ["tail.toml"]

    drive(GearlabApp(folder), script)


def test_a_file_the_scenario_names_and_an_error_are_kept_with_the_files_state(tmp_path, monkeypatch):
    calls, made = [], object()

    def fake(path=None, *, run=None):
        calls.append(path)
        if "wrong" in path.read_text():
            raise GearlabInputError(f"{path}: [stiffness] key 'points': wrong")
        return made

    monkeypatch.setattr(catalog, "load_scenario", fake)
    box = tmp_path / "box.toml"
    box.write_text("[gearbox]\n")
    scenario = tmp_path / "s.toml"
    scenario.write_text('[target]\ngearbox = "box.toml"\nname = "not a file"\n')
    validated = catalog.Validated()
    assert validated.scenario(scenario) is made and validated.scenario(scenario) is made
    assert len(calls) == 1
    later(box)  # the gearbox it names was edited
    assert validated.scenario(scenario) is made and len(calls) == 2
    scenario.write_text('[target]\ngearbox = "box.toml"\nname = "wrong"\n')
    later(scenario, 10)
    for _ in range(2):  # the error is kept too, and raised again
        with pytest.raises(GearlabInputError, match="wrong"):
            validated.scenario(scenario)
    assert len(calls) == 3
    validated.forget(scenario)
    with pytest.raises(GearlabInputError):
        validated.scenario(scenario)
    assert len(calls) == 4
