"""The contract of a scenario kind: what the engine, the CLI, the TUI and the comparison call.

A kind is a module of gearlab.kinds registered by name in ``SCENARIO_KINDS`` (the
``kind = "..."`` of a scenario's [scenario] table). Everything outside the kind reaches it
through the names below and nothing else; ``tests/test_architecture.py`` checks that every
registered kind provides them. (The registry's *plugin* kinds — fault, model, adapter,
detector, effect — are another thing: gearlab.registry.KINDS.)
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Protocol, runtime_checkable

from ..charts import Chart
from ..events import EventSink
from ..runs import RunDir
from ..scenario import Scenario, Table

# how a kind's table.md may open with its verdict (a block before the first blank line): report.html, which opens
# with its own Verdict section, leaves that block out
VERDICT = "Verdict: "


@runtime_checkable
class ScenarioKind(Protocol):
    # The kind's tables beyond [scenario], [output] and [execution]: checked key by key before
    # any work (gearlab.engine.load_scenario).
    TABLES: Mapping[str, Table]
    # The [benchmark] keys that a run of a scenario file of this kind may set on its command line
    # (`gearlab gap FILE --trials N --seed S`; the TUI's run-with-options form offers them), or ().
    OVERRIDES: tuple[str, ...]

    def build(self, scenario: Scenario) -> Any:
        """The scenario's resolved spec, typed (the kind's `Spec` dataclass; the dataset
        kind: its list of dataset specs), which becomes scenario.spec; GearlabInputError naming
        file, table and key for anything the tables alone could not refuse."""

    def describe(self, scenario: Scenario) -> str:
        """One line of what the scenario will do (`gearlab validate`, the TUI's scenario view)."""

    def quick(self, scenario: Scenario) -> None:
        """Shrink scenario.spec for a smoke run, in place or by a smaller spec in its place
        (--quick; a resume shrinks alike)."""

    def unit_modules(self, scenario: Scenario) -> tuple[str, ...]:
        """The modules the run's units load first (torch, for a training): a local pool's workers have them
        loaded before their first unit, imported once by the process's forkserver where the run starts it
        (gearlab.engine.load_scenario keeps them as Scenario.unit_modules); () where its units load nothing of note."""

    def run(self, scenario: Scenario, run: RunDir, on_event: EventSink) -> None:
        """Do the work into *run*: append one record per finished unit (skipping those already
        in run.records(), so --resume redoes nothing), write summary.json and the tables."""

    def summary_lines(self, run: RunDir) -> list[str]:
        """What the CLI prints and the TUI shows of a finished run."""

    def records_table(self, scenario: Scenario, records: list[dict]) -> str:
        """A Markdown table of the records so far (a live or partial run; `gearlab compare`)."""

    def charts(self, scenario: Scenario, run: RunDir) -> list[Chart]:
        """The run's charts as data (the TUI draws them in the terminal; compare overlays them)."""

    def verdict_lines(self, summary: dict, records: list[dict]) -> list[str]:
        """The verdict of a finished run in a few sentences computed from its summary.json and
        records (report.html opens with it, `gearlab run` ends with it, the TUI shows it); []."""

    def verdict_table(self, summary: dict) -> str | None:
        """The run's table against its references (Markdown), or None where table.md says it all."""

    def compare_table(self, runs: list[tuple]) -> tuple[str, str] | None:
        """(title, Markdown table) of several runs side by side, *runs* being (letter, scenario,
        records, summary) in the order compared; None: `gearlab compare` letters each run's own table."""

    def table_title(self, summary: dict, index: int, table: str) -> str:
        """The title of report.html's *index*-th table (from 1, Markdown *table*) where the kind's text
        gave it none; "": report.html makes one of the table's header."""

    def figure_captions(self, summary: dict) -> dict[str, tuple[str, str]]:
        """{figure file stem: (the thesis figure it repeats or "", what it shows)} of the run's figures
        (run.figures), in the order report.html shows them; a figure not named is shown last, by name."""
