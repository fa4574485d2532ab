"""Quitting the TUI while its palette Validate runs, or while the tree's files are validated: the app ends at once,
not when the validation does (a detection history's tachos take 14 s of phm09_chip.toml). The validation was a Textual
thread worker, run in the event loop's default executor, which asyncio.run joins as the app's run ends: the screen
closed, the process waited."""

from __future__ import annotations

import asyncio
import threading

from test_tui import drive, until
from test_validate_screen import one_scenario_held

from gearlab.tui import GearlabApp, catalog


def returned_at_once_then_let_go(gate: threading.Event, ended: threading.Event, threads: str) -> None:
    """The app's run has returned: the held validation had not ended then; let go, it ends, and its threads (named
    *threads*...) are joined: their results had nowhere to go, dropped, nothing raised."""
    returned_before_the_validation_ended = not ended.is_set()
    gate.set()
    assert ended.wait(30)
    assert returned_before_the_validation_ended
    for thread in [t for t in threading.enumerate() if t.name.startswith(threads)]:
        thread.join(30)


def test_quitting_while_a_validation_runs_does_not_wait_for_it(tmp_path, monkeypatch):
    started, gate, ended = threading.Event(), threading.Event(), threading.Event()
    failed = []  # what the validation's thread raised after the app had gone, where anything

    def held(path):
        started.set()
        gate.wait(30)  # the test lets it go once the app's run has returned (the bound: a run that waits for it)
        ended.set()
        return f"OK: {path.name}"

    monkeypatch.setattr(threading, "excepthook", failed.append)
    folder = one_scenario_held(monkeypatch, tmp_path, held)
    notices = []

    async def script(pilot):
        app = pilot.app
        app.notify = lambda message, **kw: notices.append(message)
        (entry,) = app.entries
        app._validate(entry)
        while not started.is_set():
            await pilot.pause(0.01)
        await pilot.press("q")

    drive(GearlabApp(folder), script)  # asyncio.run of the app: its run over, its loop closed
    returned_at_once_then_let_go(gate, ended, "validate ")
    assert failed == [] and notices == [], (failed, notices)


def test_quitting_while_the_tree_s_marks_are_validated_does_not_wait_for_them(tmp_path, monkeypatch):
    # the tree's files are validated in the background after the first frame (gearlab.tui.checking), as Validate is
    started, gate, ended = threading.Event(), threading.Event(), threading.Event()
    failed, real = [], catalog.load_scenario

    def held(path=None, *, run=None):
        started.set()
        gate.wait(30)  # let go once the app's run has returned (the bound: a run that waits for it)
        ended.set()
        return real(path, run=run)

    monkeypatch.setattr(threading, "excepthook", failed.append)
    monkeypatch.setattr(catalog, "load_scenario", held)
    folder = one_scenario_held(monkeypatch, tmp_path, lambda path: f"OK: {path.name}")

    async def main():
        async with GearlabApp(folder).run_test() as pilot:
            await until(pilot, started.is_set, 30)
            await pilot.press("q")

    asyncio.run(main())
    returned_at_once_then_let_go(gate, ended, "check ")
    assert failed == [], failed
