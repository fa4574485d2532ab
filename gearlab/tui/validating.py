"""The command palette's `Validate FILE`: `gearlab validate` of the file (gearlab.validate_scenario) in a worker
thread. For a detection scenario it reads the takes' tachos (14 s of a long history such as phm09_chip.toml's), and
on the app's own thread that froze the screen: no key was read until it ended. A line under the views says
"validating FILE ..." meanwhile; its end is notified as before (the OK line, the one-line error, a footer's
warnings). One validation at a time: a second Validate while one runs is refused, said so.

The validation runs in a daemon thread of its own, awaited by an async worker: quitting cancels the worker (Textual
cancels an app's workers as it exits) and the app's run returns without waiting for it. As a Textual thread worker
it ran in the event loop's default executor, which asyncio.run joins as the app's run ends: quitting closed the
screen, then the process waited for the validation (phm09_chip.toml's: 25 s after 'q' on a loaded 2-core machine;
now 0.1 s, as with nothing running). validate_scenario only reads files, so nothing is left half done
where the process ends under it; a result that comes after the app has gone is dropped.
"""

from __future__ import annotations

import asyncio
import threading
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

from textual import work
from textual.widgets import Static

from ..errors import GearlabInputError
from ..notebook import validate_scenario
from .catalog import ScenarioEntry

T = TypeVar("T")


class ValidatingLine(Static):
    """The line that says which file is being validated; hidden when none is."""

    DEFAULT_CSS = "ValidatingLine { height: auto; padding: 0 1; background: $boost; display: none; }"


class Validating:
    """GearlabApp's Validate (a mixin: the app holds `validated`, `directory`, `rescan`, `notify`)."""

    validating: Path | None = None  # the file being validated, None when none is

    def _validate(self, entry: ScenarioEntry) -> None:
        """Validate the entry's file in a worker thread; refused while another validation runs."""
        if self.validating is not None:
            self.notify(
                f"validating {self._listed_as(self.validating)} already: wait for its result, then validate again",
                severity="warning",
            )
            return
        self.validated.forget(entry.path)  # asked for: read afresh, whatever the files' times say
        self.validating = entry.path
        line = self.query_one(ValidatingLine)
        line.update(f"validating {self._listed_as(entry.path)} ... (the keys work meanwhile)")
        line.display = True
        self._validate_in_thread(entry.path)

    @work(group="validate")
    async def _validate_in_thread(self, path: Path) -> None:
        result = await in_daemon_thread(lambda: validated_in_thread(path), f"validate {path.name}")
        if self.is_running:  # landed as the app closes, before the worker is cancelled: its line may be gone
            self._validated(*result)

    def _validated(self, said: str | None, error: str | None, warned: list[str]) -> None:
        """Back on the app's thread: the result notified, the line hidden, the folder read again."""
        self.validating = None
        self.query_one(ValidatingLine).display = False
        if error is not None:
            self.notify(error, severity="error", title="invalid")
        else:
            self.notify(said, title="valid")
        for message in warned:
            self.notify(message, severity="warning", title="warning")
        self.rescan()

    def _listed_as(self, path: Path) -> str:
        return str(path.relative_to(self.directory)) if path.is_relative_to(self.directory) else str(path)


async def in_daemon_thread(read: Callable[[], T], name: str) -> T:
    """read() in a daemon thread of its own, awaited on the app's loop; what it raises is raised here. Cancelled (the
    app closing), the await ends at once and the thread's result, come later, is dropped (see the module's doc)."""
    loop = asyncio.get_running_loop()
    done: asyncio.Future = loop.create_future()

    def deliver(result: T | BaseException, failed: bool) -> None:  # on the app's thread
        if done.done():  # the awaiting worker was cancelled: nothing left to tell
            return
        if failed:
            done.set_exception(result)
        else:
            done.set_result(result)

    def run() -> None:
        try:
            result, failed = read(), False
        except BaseException as exc:  # handed to the app's thread, raised there (the worker fails)
            result, failed = exc, True
        try:
            loop.call_soon_threadsafe(deliver, result, failed)
        except RuntimeError:  # the app's loop closed: the app quit while this ran
            pass

    threading.Thread(target=run, name=name, daemon=True).start()
    return await done


def validated_in_thread(path: Path) -> tuple[str | None, str | None, list[str]]:
    """(the OK line, the one-line error, the warnings) of validate_scenario(*path*)."""
    # catch_warnings is process-wide: a warning the app's own thread raised meanwhile would be shown
    # with these; the app raises none of its own while it waits for keys
    with warnings.catch_warnings(record=True) as caught:  # a logger's footer the run's reader leaves out
        warnings.simplefilter("always")
        try:
            said, error = validate_scenario(path), None
        except GearlabInputError as exc:
            said, error = None, str(exc)
    return said, error, [str(w.message) for w in caught]
