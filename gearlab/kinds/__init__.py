"""Scenario kinds, by the name a scenario gives in [scenario] kind. Each is a module that
fulfils gearlab.kinds.contract.ScenarioKind (TABLES, OVERRIDES, build, describe, quick, run,
summary_lines, records_table, charts); the helpers they share are in gearlab.kinds.common.

A kind's module is imported when first asked for: checking a scenario loads its own kind and
what that imports, not all eight (issue 42: 0.2 s of `gearlab validate` without bytecode caches)."""

from collections.abc import Callable, Iterator, Mapping

from .contract import ScenarioKind


def _stiffness():
    from . import stiffness

    return stiffness


def _dataset():
    from . import dataset

    return dataset


def _transfer():
    from . import transfer

    return transfer


def _noise_study():
    from . import noise_study

    return noise_study


def _gap():
    from . import gap

    return gap


def _gap_benchmark():
    from . import gap_benchmark

    return gap_benchmark


def _detection():
    from . import detection

    return detection


def _transfer_benchmark():
    from . import transfer_benchmark

    return transfer_benchmark


class _Kinds(Mapping):
    """The kinds' modules by name, each imported by its loader on first use (a module imports once)."""

    def __init__(self, loaders: dict[str, Callable[[], ScenarioKind]]):
        self.loaders = loaders

    def __getitem__(self, name: str) -> ScenarioKind:
        return self.loaders[name]()

    def __iter__(self) -> Iterator[str]:
        return iter(self.loaders)

    def __len__(self) -> int:
        return len(self.loaders)


SCENARIO_KINDS: Mapping[str, ScenarioKind] = _Kinds(
    {
        "stiffness": _stiffness,
        "dataset": _dataset,
        "transfer": _transfer,
        "noise_study": _noise_study,
        "gap": _gap,
        "gap_benchmark": _gap_benchmark,
        "detection": _detection,
        "transfer_benchmark": _transfer_benchmark,
    }
)

# The kinds `gearlab gap FILE` runs, the gap's diagnosis and its benchmark (`gearlab run` runs every
# kind): the command's own kinds are named here, with the registry, not in the CLI.
GAP_COMMAND_KINDS: tuple[str, ...] = ("gap", "gap_benchmark")
# The command that sets a kind's OVERRIDES from its options (`gearlab gap FILE --trials N --seed S`,
# gap_benchmark's): the TUI's run form calls it where a kind has them.
OVERRIDES_COMMAND = "gap"
