"""What a finished run says, in a few sentences computed from its results: the verdict that
opens report.html, the end of `gearlab run` and the TUI's results. Each kind writes its own
(its verdict_lines and verdict_table, gearlab.kinds.contract); this module finds the run's kind.
"""

from __future__ import annotations

from pathlib import Path

from .kinds import SCENARIO_KINDS
from .runs import RunDir


def load_summary(run_path: Path) -> dict:
    return RunDir(Path(run_path)).summary()


def _records(run_path: Path) -> list[dict]:
    return RunDir(Path(run_path)).records()


def _kind(summary: dict):
    return SCENARIO_KINDS.get(summary.get("kind"))


def verdict_lines(run) -> list[str]:
    """The verdict of a finished run (a RunDir or its path); [] for kinds without one."""
    path = Path(getattr(run, "path", run))
    summary = load_summary(path)
    kind = _kind(summary)
    return kind.verdict_lines(summary, _records(path)) if kind is not None else []


def verdict_table(run) -> str | None:
    """A finished run's table as its kind tells it against its references (a transfer run's Bayes
    bound and thesis rows); None where the kind's own table.md says it all."""
    summary = load_summary(Path(getattr(run, "path", run)))
    kind = _kind(summary)
    return kind.verdict_table(summary) if kind is not None else None
