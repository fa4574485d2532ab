"""Scenario kinds, by the name a scenario gives in [scenario] kind. Each is a module that
fulfils gearlab.kinds.contract.ScenarioKind (TABLES, OVERRIDES, build, describe, quick, run,
summary_lines, records_table, charts); the helpers they share are in gearlab.kinds.common."""

from . import dataset, detection, gap, gap_benchmark, noise_study, stiffness, transfer, transfer_benchmark
from .contract import ScenarioKind

SCENARIO_KINDS: dict[str, ScenarioKind] = {
    "stiffness": stiffness,
    "dataset": dataset,
    "transfer": transfer,
    "noise_study": noise_study,
    "gap": gap,
    "gap_benchmark": gap_benchmark,
    "detection": detection,
    "transfer_benchmark": transfer_benchmark,
}

# The kinds `gearlab gap FILE` runs, the gap's diagnosis and its benchmark (`gearlab run` runs every
# kind): the command's own kinds are named here, with the registry, not in the CLI.
GAP_COMMAND_KINDS: tuple[str, ...] = ("gap", "gap_benchmark")
