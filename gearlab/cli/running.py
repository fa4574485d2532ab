"""The commands that run a scenario (validate, run, gap, transfer-benchmark) and their shared options."""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass, fields
from inspect import Parameter, Signature, signature
from pathlib import Path
from typing import Annotated, get_type_hints

import typer

from ..cliconv import conventional
from ..errors import GearlabInputError
from .output import console, err_console

app = conventional(typer.Typer())


@app.command()
def validate(scenario: Annotated[Path, typer.Argument(help="scenario TOML file (or a gearbox description)")]) -> None:
    """Check a scenario file without running it: unknown keys, types, ranges, plugin names.

    Example: gearlab validate scenarios/expB.toml
    """
    from ..notebook import validate_scenario

    console.print(validate_scenario(scenario), markup=False)


Out = Annotated[
    Path | None, typer.Option(help="base directory for the run directory (default: the scenario's output dir)")
]
Resume = Annotated[Path | None, typer.Option(help="continue the run in this run directory")]
Quick = Annotated[bool, typer.Option(help="shrink the scenario for a smoke run")]
Executor = Annotated[
    str | None,
    typer.Option(help="where units run: local (process pool) or ray (default: the scenario's execution table)"),
]
RayAddress = Annotated[
    str | None,
    typer.Option(help="Ray cluster address (default: RAY_ADDRESS, then the scenario's; none: a local Ray instance)"),
]
Device = Annotated[
    str | None,
    typer.Option(
        help="where networks train: auto (CUDA when present), cpu or cuda (default: the scenario's execution table)"
    ),
]
Events = Annotated[bool, typer.Option(help="progress as JSON lines on stdout (for front-ends such as the TUI)")]


@dataclass(frozen=True)
class Running:
    """The options of every command that runs a scenario, declared once (runs_a_scenario)."""

    out: Out = None
    resume: Resume = None
    quick: Quick = False
    executor: Executor = None
    ray_address: RayAddress = None
    device: Device = None
    events: Events = False


def trains(command: Callable[..., None]) -> Callable[..., None]:
    """*command* marked as one that trains: it keeps the BLAS threads the machine gives (its threads are set
    where it trains: learn/, gearlab.executors' pool and aside thread); every other command runs on one
    (cli.one_blas_thread)."""
    command.trains = True
    return command


def runs_a_scenario(command: Callable[..., None]) -> Callable[..., None]:
    """*command* with the Running options after its own, in the signature typer reads; *command*
    gets them gathered as its last parameter, `how` (a Running)."""
    own = [p for p in signature(command, eval_str=True).parameters.values() if p.name != "how"]
    hints = get_type_hints(Running, include_extras=True)  # the typer.Option of each
    shared = [
        Parameter(f.name, Parameter.KEYWORD_ONLY, default=f.default, annotation=hints[f.name]) for f in fields(Running)
    ]

    @functools.wraps(command)
    def with_options(**given) -> None:
        command(**{p.name: given[p.name] for p in own}, how=Running(**{f.name: given[f.name] for f in fields(Running)}))

    with_options.__signature__ = Signature(own + shared, return_annotation=None)
    with_options.__annotations__ = {p.name: p.annotation for p in own + shared}
    return trains(with_options)


@app.command()
@runs_a_scenario
def run(scenario: Annotated[Path | None, typer.Argument(help="scenario TOML file")] = None, *, how: Running) -> None:
    """Run a scenario headless; prints `run directory: PATH` as its last line.

    Progress goes to stderr: bars on a terminal, one log line per step otherwise.

    Example: gearlab run scenarios/quick.toml --quick (then: gearlab run --resume RUN_DIR)
    """
    if scenario is None and how.resume is None:
        raise GearlabInputError("give a SCENARIO file, or --resume RUN_DIR")
    _run(scenario, how, {})


def _execution(executor: str | None, ray_address: str | None, device: str | None) -> dict:
    """The [execution] keys set on the command line, checked with the scenario's own."""
    import os

    if ray_address:
        os.environ["RAY_ADDRESS"] = ray_address  # wins over the scenario's address, as Ray reads it too
    given = {"executor": executor, "device": device}
    given = {key: value for key, value in given.items() if value is not None}
    return {"execution": given} if given else {}


class Interrupted(Exception):
    """Ctrl-C during a run; run_path: its run directory (None when none was made yet)."""

    def __init__(self, run_path: str | None):
        super().__init__(run_path)
        self.run_path = run_path


def _run(scenario: Path | None, how: Running, overrides: dict) -> None:
    """Run the engine, drawing its events as progress bars (or printing them as JSON lines); *overrides*
    ({table: {key: value}}) beside the [execution] keys of *how*."""
    out, resume, quick, events = how.out, how.resume, how.quick, how.events
    overrides = {**_execution(how.executor, how.ray_address, how.device), **overrides}
    if not events and err_console.is_terminal:  # the engine's imports take seconds before its first event
        err_console.print(f"gearlab: starting {scenario or resume}", style="dim", markup=False, highlight=False)
    from ..kinds import SCENARIO_KINDS
    from ..notebook import load_scenario, run_scenario

    started: list[str] = []  # the run directory, once made: what Ctrl-C tells to resume

    def remembered(sink):
        def handle(event) -> None:
            if event.kind == "run":
                started.append(event.message)
            sink(event)

        return handle

    try:
        if events:
            result = run_scenario(
                scenario, out=out, resume=resume, quick=quick, overrides=overrides, on_event=remembered(_print_event)
            )
            typer.echo(f"run directory: {result.path}")
            return
        from ..terminal import ProgressView

        with ProgressView(err_console) as view:
            result = run_scenario(
                scenario, out=out, resume=resume, quick=quick, overrides=overrides, on_event=remembered(view.handle)
            )
    except KeyboardInterrupt:
        raise Interrupted(started[-1] if started else None) from None
    from ..terminal import print_results
    from ..verdict import verdict_lines

    kind = load_scenario(run=result).kind
    print_results(console, verdict_lines(result), SCENARIO_KINDS[kind].summary_lines(result))
    console.print(f"report: {result.path / 'report.html'}", markup=False, highlight=False)
    typer.echo(f"run directory: {result.path}")


BENCHMARK = "gap_benchmark.toml"


@app.command()
@runs_a_scenario
def gap(
    scenario: Annotated[str, typer.Argument(help="a gap scenario file (kind = \"gap\"), or 'benchmark'")],
    trials: Annotated[int | None, typer.Option(help="benchmark: number of trials (default: the scenario's)")] = None,
    seed: Annotated[
        int | None, typer.Option(help="benchmark: seed of the hidden draws (default: the scenario's)")
    ] = None,
    *,
    how: Running,
) -> None:
    """Diagnose the sim-to-real gap of a scenario, or run the blind benchmark of the diagnosis.

    `gearlab gap benchmark` runs scenarios/gap_benchmark.toml (from the current folder, else from the gearlab source tree) with --trials and --seed set on the command line; so does `gearlab gap FILE` for a gap_benchmark scenario file.

    Example: gearlab gap scenarios/gap_expB.toml --quick; gearlab gap benchmark --trials 4
    """  # noqa: E501 (typer keeps line breaks in help text: one paragraph, one line)
    from ..kinds import GAP_COMMAND_KINDS, SCENARIO_KINDS
    from ..notebook import load_scenario

    overrides: dict = {}
    given = _benchmark_keys(trials, seed)
    if scenario == "benchmark":
        path = _shipped_scenario(BENCHMARK)
        overrides.update(given)
    else:
        path = Path(scenario)
        if not path.exists() and "/" not in scenario and not scenario.endswith(".toml"):
            from ..errors import did_you_mean

            hint = did_you_mean(scenario, ["benchmark"])
            if hint:
                raise GearlabInputError(f"gap: '{scenario}' is neither a scenario file nor 'benchmark'{hint}")
        kind = load_scenario(path).kind
        if kind in GAP_COMMAND_KINDS and SCENARIO_KINDS[kind].OVERRIDES:  # a benchmark file takes --trials, --seed
            overrides.update(given)
        elif given:
            raise GearlabInputError("--trials and --seed belong to `gearlab gap benchmark` (or a gap_benchmark file)")
        elif kind not in GAP_COMMAND_KINDS:
            expected = " or ".join(f'"{k}"' for k in GAP_COMMAND_KINDS)
            raise GearlabInputError(
                f"{path}: [scenario] key 'kind': expected {expected} for `gearlab gap`, got "
                f'"{kind}" (run it with `gearlab run`)'
            )
    _run(None if how.resume else path, how, overrides)


def _benchmark_keys(trials: int | None, seed: int | None) -> dict:
    """The [benchmark] keys set on the command line: {"benchmark": {...}}, or {} when none is."""
    given = {key: value for key, value in (("trials", trials), ("seed", seed)) if value is not None}
    return {"benchmark": given} if given else {}


def _shipped_scenario(name: str) -> Path:
    """scenarios/*name* of the current folder, else of the gearlab source tree."""
    for folder in (Path("scenarios"), Path(__file__).resolve().parents[2] / "scenarios"):
        if (folder / name).is_file():
            return folder / name
    raise GearlabInputError(
        f"scenarios/{name} not found in the current folder nor in the gearlab source tree; "
        "give `gearlab run` a scenario file of its kind instead"
    )


@app.command("transfer-benchmark")
@runs_a_scenario
def transfer_benchmark(
    trials: Annotated[int | None, typer.Option(help="number of random targets (default: the scenario's)")] = None,
    seed: Annotated[
        int | None, typer.Option(help="seed of the draws: below 1000 development, else a reported figure")
    ] = None,
    only: Annotated[
        list[int] | None, typer.Option(help="run trial I alone (repeatable), drawn as in the full run")
    ] = None,
    *,
    how: Running,
) -> None:
    """Run gearlab's frozen recipe on random unseen targets, each beside its Bayes bound.

    Runs scenarios/transfer_benchmark.toml (from the current folder, else from the gearlab source tree) with --trials and --seed set on the command line. Selection rule: settings may be tuned on seeds below 1000; figures are reported on seeds never used before, chosen after the code is frozen.

    Example: gearlab transfer-benchmark --trials 24 --seed 1000; one trial again: --trials 24 --seed 3 --only 9
    """  # noqa: E501 (typer keeps line breaks in help text: one paragraph, one line)
    overrides = _benchmark_keys(trials, seed)
    if only:
        overrides.setdefault("benchmark", {})["only"] = list(only)
    path = None if how.resume else _shipped_scenario("transfer_benchmark.toml")
    _run(path, how, overrides)


def _print_event(event) -> None:
    print(event.to_json(), flush=True)
