"""Issue 41: the TUI's tree takes → and ← as docs/tui.md says (unfold / go to the first child,
fold / go to the parent), at 80x24 and 160x45 (the stage bars' ETA: tests/test_tui_edges.py)."""

import asyncio
from pathlib import Path

import pytest
from conftest import ROOT, unrendered
from test_tui import checked
from test_tui_edges import stiff_text
from textual.widgets import Tree

from gearlab.tui import GearlabApp

SIZES = [(160, 45), (80, 24)]


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """A scenarios folder holding a stiffness scenario with one finished quick run (test_tui_edges.stiff_text: the
    shipped stiffness_verification.toml at 512 points, whose run and charts cost a fraction of 4096's)."""
    from gearlab.engine import run_scenario

    base = tmp_path_factory.mktemp("arrows")
    sc = base / "scenarios"
    sc.mkdir()
    (sc / "stiff.toml").write_text(stiff_text() + f'\n[output]\ndir = "{base / "runs"}"\n')
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr("gearlab.plots.save", unrendered)  # these tests show no figure's pixels
        run_scenario(sc / "stiff.toml", quick=True)
    return sc


@pytest.mark.parametrize("size", SIZES)
def test_right_unfolds_and_enters_left_leaves_and_folds(folder, size):
    async def main():
        async with GearlabApp(folder).run_test(size=size) as pilot:
            await checked(pilot)
            tree = pilot.app.query_one("#browser", Tree)
            node = next(n for n in tree.root.children if str(n.label).endswith("stiff.toml"))
            tree.focus()
            tree.move_cursor(node)
            await pilot.pause()
            assert not node.is_expanded
            await pilot.press("right")
            assert node.is_expanded
            await pilot.press("right")
            assert tree.cursor_node is node.children[0]
            await pilot.press("left")
            assert tree.cursor_node is node and node.is_expanded
            await pilot.press("left")
            assert not node.is_expanded

    asyncio.run(main())


def test_the_docs_say_what_the_arrows_do():
    assert "→ ←" in (Path(ROOT) / "docs" / "tui.md").read_text()
