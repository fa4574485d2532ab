"""The commands on finished runs: rebuild a report, score new recordings, list runs, compare them."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from ..cliconv import conventional
from ..errors import GearlabInputError
from .output import console

app = conventional(typer.Typer())


@app.command()
def report(run_dir: Annotated[Path, typer.Argument(help="a run directory")]) -> None:
    """Rebuild report.html of a run directory.

    Example: gearlab report runs/quick/20260101-120000-000000
    """
    from ..notebook import open_run
    from ..report import write_report

    path = write_report(open_run(run_dir))
    console.print(f"wrote {path}")


@app.command()
def score(
    run_dir: Annotated[Path, typer.Argument(help="a finished detection run directory")],
    files: Annotated[list[Path], typer.Argument(help="new recordings of the run's target (any format it reads)")],
    condition: Annotated[
        str | None, typer.Option(help="the run's condition to score them in (default: the nearest speed)")
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="print the rows as JSON")] = False,
    key: Annotated[list[str], typer.Option(help="KEY=VALUE: a [target] files entry's key (tacho_shaft=output)")] = [],  # noqa: B006
    exit_code: Annotated[bool, typer.Option("--exit-code", help="exit 1 where a take is called")] = False,
) -> None:
    """Score new recordings with a finished detection run's trained methods and thresholds (nothing is trained again).

    Per record: its speed and how it was found, and the gear its change is localised on against the run's history, with the evidence (each shaft's z over its threshold, the tooth). Per method and unit (revolution, recordN): the units called over the threshold, the median score less the threshold, and the decision: most units called is a fault, or "other damage: <gear>" when the change lies on a gear the run does not watch (as the run's which-gear table calls it). Each row is appended to the run's scoring history (scoring/history.jsonl), whose trend per method the report and the TUI show; the last lines (trend:) say per condition which take was first called, by which methods, on which gear and tooth. A take that cannot be scored (a speed far from every condition's) is refused in one line; of several, it is named with why ('not scored') and the others are scored, with exit code 2. With --exit-code, for a script: 1 where any take is called (a fault or other damage, by any method and unit), else 3 where a take called with no gear localised is off its history's level by more than a factor of 1.25 ('level changed by a factor of 0.50 (sensor, gain or load changed?): record a new history'), 0 where none is, 2 as before.

    Example: gearlab score runs/det/20260101-120000-000000 today.csv
    """  # noqa: E501 (typer keeps line breaks in help text: one paragraph, one line)
    from ..notebook import score_recordings
    from ..terminal import all_scored, score_tables, score_trend

    rows = score_recordings(run_dir, files, condition, given=dict(k.partition("=")[::2] for k in key))
    if as_json:
        typer.echo(json.dumps([{k: v for k, v in r.items() if k != "scores"} for r in rows], indent=1))
    for item in [] if as_json else [*score_tables(rows, run_dir, console.width), *score_trend(run_dir)]:
        console.print(item)
    all_scored(rows, exit_code)  # a take refused of several: the others scored, exit 2; else a take called: 1


@app.command()
def runs(
    directory: Annotated[Path, typer.Argument(help="a folder of runs (searched 4 levels down)")] = Path("runs"),
    as_json: Annotated[bool, typer.Option("--json", help="print a JSON list")] = False,
) -> None:
    """List past runs, newest first: name, kind, start, duration, status, headline figure, run directory.

    Status: finished, failed, cancelled, running, stopped (killed or crashed: gearlab run --resume RUN_DIR continues it).

    Example: gearlab runs runs/quick
    """  # noqa: E501 (typer keeps line breaks in help text: one paragraph, one line)
    from dataclasses import asdict

    from ..runinfo import list_runs
    from ..terminal import print_table, runs_table

    found = list_runs(directory)
    if as_json:
        typer.echo(json.dumps([{**asdict(r), "path": str(r.path)} for r in found], indent=1))
        return
    if not found:
        console.print(f"no runs under {directory}", markup=False, highlight=False)
        return
    print_table(console, runs_table(found, console))


@app.command()
def compare(
    run_dirs: Annotated[list[Path], typer.Argument(help="two or more run directories of one kind")],
    html: Annotated[Path | None, typer.Option(help="also write a self-contained comparison page (HTML) here")] = None,
) -> None:
    """Compare runs of one kind: their tables side by side, their charts overlaid.

    Example: gearlab compare runs/expB/RUN_1 runs/expB/RUN_2 --html expB.html
    """
    import tempfile

    from ..compare import compare_html, compare_lines, load_runs, print_tables
    from ..files import atomic_write

    runs = load_runs(run_dirs)
    if html is not None and not html.parent.is_dir():
        raise GearlabInputError(f"--html {html}: directory {html.parent} does not exist")
    for line in compare_lines(runs):
        console.print(line, markup=False, highlight=False)
    _print_scenario_differences(run_dirs)
    print_tables(console, runs)  # the figures: rich tables, as at the end of a run
    if html is not None:
        with tempfile.TemporaryDirectory() as figures:  # the PNGs are inlined, then go
            atomic_write(html, compare_html(runs, Path(figures)))
        console.print(f"wrote {html}", markup=False, highlight=False)


def _print_scenario_differences(run_dirs: list[Path]) -> None:
    """The scenario keys whose values differ between the compared runs (A, B, ... as compare names them)."""
    from rich.text import Text

    from ..runinfo import scenario_differences
    from ..terminal import print_table

    rows = scenario_differences(run_dirs)
    if not rows:
        console.print("scenarios: the same (apart from their names)", markup=False, highlight=False)
        return
    table = Table(title=Text("scenario differences", style="bold"), title_justify="left")
    table.add_column("key")
    for i in range(len(run_dirs)):
        table.add_column(chr(ord("A") + i) if i < 26 else str(i + 1), overflow="fold")
    for key, values in rows:
        table.add_row(Text(key), *(Text(v) for v in values))
    print_table(console, table)
