"""The scenario tree's ✓/✗ marks, filled in while the tree is already on screen.

Validating the 19 shipped scenarios in full before the first frame (their kinds' modules imported, a stiffness
scenario's fault ladders built, a detection history's files read) took the TUI's first screen to 2.3 s of CPU. The
tree is now listed by name at once, each mark pending ("· name", dim), and a worker validates the files one by one
and sets each mark as it lands: the highlighted scenario first, then the others from the top. A file whose result
Validated keeps for its files' present state (a rescan of unchanged files) is marked at once, so a rescan queues
only the new and the edited ones. Selecting or running a scenario whose mark is still pending validates it then, on
the app's thread (Validated waits for the worker's file in progress, if any, and never reads a file twice).

The files are validated in daemon threads, a batch each (BATCH_S), awaited by an async worker as the palette's
Validate is (validating.in_daemon_thread): quitting cancels the worker and the app's run returns without waiting for
the batch in progress; its result, come after the app has gone, is dropped. The thread fills entries of its own,
copied into the tree's entries on the app's thread, so that the views never read an entry half filled.
"""

from __future__ import annotations

import time

from rich.text import Text
from textual import work

from .catalog import ScenarioEntry, check
from .validating import in_daemon_thread

# A thread validates files for about this long before their marks are shown together: a frame drawn for each
# mark as it landed (29 screen updates to the shipped scenarios' whole tree, 9 with the tree validated before the
# first frame) cost the app's thread more CPU than the drawing of the tree itself
BATCH_S = 0.1


def scenario_label(entry: ScenarioEntry, name: str) -> Text:
    """The tree's line of a scenario file: its mark (pending until it is validated) and its name."""
    if not entry.checked:
        return Text.assemble(("· ", "dim"), (name, "dim"))
    good = entry.ok or bool(entry.gearbox)
    label = Text.assemble(("✓ " if good else "✗ ", "green" if good else "red"), name)
    if entry.gearbox is not None:
        label.append(" gearbox", style="dim")
    return label


class Checking:
    """GearlabApp's marks (a mixin: the app holds `entries`, `validated`, `cwd`, `directory`, `tree`, `highlighted`,
    `scenario_of`, `_open`, `_run_label`)."""

    def _check_pending(self) -> None:
        """Validate the pending entries in the background, once the frame that lists them is drawn."""
        if any(not entry.checked for entry in self.entries):
            self.call_after_refresh(self._check_in_background)

    def _pending(self) -> list[ScenarioEntry]:
        """The entries whose marks are pending: the highlighted scenario's first, then from the top."""
        shown = self.scenario_of(self.highlighted())
        pending = [entry for entry in self.entries if not entry.checked]
        return sorted(pending, key=lambda entry: entry is not shown)  # a stable sort: the others keep their order

    @work(exclusive=True, group="checks")  # a rescan's worker replaces the one before
    async def _check_in_background(self) -> None:
        validated, cwd = self.validated, self.cwd
        while pending := self._pending():

            def read(paths=tuple(entry.path for entry in pending)) -> list[ScenarioEntry]:
                result: list[ScenarioEntry] = []
                began = time.monotonic()
                for path in paths:  # until BATCH_S has passed: the marks come a frame for several files
                    result.append(ScenarioEntry(path))
                    check(result[-1], validated, cwd)
                    if time.monotonic() - began > BATCH_S:
                        break
                return result

            batch = await in_daemon_thread(read, f"check {pending[0].path.name}")
            if not self.is_running:  # landed as the app closes, before the worker is cancelled: its tree may be gone
                return
            landed = [(entry, fresh) for entry, fresh in zip(pending, batch) if not entry.checked]
            for entry, fresh in landed:  # (one checked meanwhile was selected, and validated on the app's thread)
                entry.gearbox, entry.scenario, entry.error = fresh.gearbox, fresh.scenario, fresh.error
                entry.runs, entry.checked = fresh.runs, True
            self._show_checked([entry for entry, _ in landed], reopen=True)

    def _check_now(self, entry: ScenarioEntry | None) -> None:
        """A scenario selected or run before its mark came: validated now, on the app's thread."""
        if entry is not None and not entry.checked:
            check(entry, self.validated, self.cwd)
            self._show_checked([entry], reopen=False)

    def _show_checked(self, entries: list[ScenarioEntry], reopen: bool) -> None:
        """The entries' nodes: their marks, their runs below them; the views drawn again when one is highlighted."""
        tree = self.tree
        for node in tree.root.children:
            entry = node.data
            if not any(entry is done for done in entries):  # (an entry a rescan replaced has no node)
                continue
            node.set_label(scenario_label(entry, str(entry.path.relative_to(self.directory))))
            for run in entry.runs:
                node.add_leaf(self._run_label(run), data=run)
            node.allow_expand = bool(entry.runs)
            if reopen and self.highlighted() is entry:
                self._open(entry, switch=False)
        tree.styles.width = tree.fit_width()
