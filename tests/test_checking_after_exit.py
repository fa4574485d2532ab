"""The tree's marks validated in the background (tui.checking): a batch that lands while the app is already closing
(its screens being taken down) is dropped, not drawn on a tree that is gone. It raised NoMatches('#browser') out of
the app's run: a first screen left at once (benchmarks/startup.py's, a user's quick q) failed as a batch landed."""

from __future__ import annotations

import asyncio

from gearlab.tui import GearlabApp, checking


def test_a_batch_landing_while_the_app_closes_is_dropped(tmp_path, monkeypatch):
    (tmp_path / "a.toml").write_text('[scenario]\nname = "a"\nkind = "dataset"\n')
    app = GearlabApp(str(tmp_path))
    closing = []

    async def lands_as_the_app_closes(read, name):
        batch = read()  # validated at once (the file is a bad scenario: a mark all the same)
        while app.is_running or app.query("#browser"):  # held until the app closes its screens, then handed back
            await asyncio.sleep(0.001)
        closing.append(name)
        return batch

    monkeypatch.setattr(checking, "in_daemon_thread", lands_as_the_app_closes)

    async def quit_at_once():
        async with app.run_test() as pilot:
            await pilot.pause()
            assert app.entries and not app.entries[0].checked  # its mark still pending as the app is left

    asyncio.run(quit_at_once())  # raised WorkerFailed(NoMatches) where the batch was drawn
    assert closing, "the batch was not handed back while the app closed: nothing tested"
