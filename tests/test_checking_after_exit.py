"""The TUI's background validations (the tree's marks, tui.checking; the palette's Validate, tui.validating): a result
that lands while the app is already closing (its screens being taken down, the worker not yet cancelled) is dropped,
not drawn on widgets that are gone. It raised NoMatches out of the app's run: a first screen left at once
(benchmarks/startup.py's, a user's quick q) failed as a batch of marks landed."""

from __future__ import annotations

import asyncio

import pytest

from gearlab.tui import GearlabApp, checking, validating


@pytest.mark.parametrize("validate", [False, True], ids=["marks", "palette validate"])
def test_a_result_landing_while_the_app_closes_is_dropped(tmp_path, monkeypatch, validate):
    (tmp_path / "a.toml").write_text('[scenario]\nname = "a"\nkind = "dataset"\n')
    app = GearlabApp(str(tmp_path))
    closing = []

    async def lands_as_the_app_closes(read, name):
        result = read()  # validated at once (the file is a bad scenario: a result all the same)
        while app.is_running or app.query("#browser"):  # held until the app closes its screens, then handed back
            await asyncio.sleep(0.001)
        closing.append(name)
        return result

    for module in (checking, validating):
        monkeypatch.setattr(module, "in_daemon_thread", lands_as_the_app_closes)

    async def quit_at_once():
        async with app.run_test() as pilot:
            await pilot.pause()
            assert app.entries and not app.entries[0].checked  # its mark still pending as the app is left
            if validate:
                app._validate(app.entries[0])

    asyncio.run(quit_at_once())  # raised WorkerFailed(NoMatches) where the result was drawn
    assert len(closing) == 1 + validate, closing  # each handed back while the app closed: else nothing tested
