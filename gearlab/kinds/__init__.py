"""Scenario kinds. Each module gives TABLES (schema), build(scenario) -> spec,
describe(scenario) (one line of what it will do), quick(scenario) (shrink for a smoke run), run(scenario, run_dir, on_event) and
summary_lines(run_dir) (what the CLI and the TUI show of a finished run)."""

from . import dataset, noise_study, stiffness, transfer

SCENARIO_KINDS = {"stiffness": stiffness, "dataset": dataset, "transfer": transfer, "noise_study": noise_study}
from . import gap; SCENARIO_KINDS["gap"] = gap  # noqa: E402, E702 (one line per kind added after the first four)
from . import gap_benchmark; SCENARIO_KINDS["gap_benchmark"] = gap_benchmark  # noqa: E402, E702
from . import detection; SCENARIO_KINDS["detection"] = detection  # noqa: E402, E702
