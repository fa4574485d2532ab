"""`gearlab tui`: the Textual front-end (gearlab.tui) on a folder of scenarios."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ..cliconv import conventional
from ..errors import GearlabInputError
from .running import trains

app = conventional(typer.Typer())


@app.command()
@trains  # the runs it starts
def tui(directory: Annotated[Path, typer.Argument(help="folder of scenario files")] = Path("scenarios")) -> None:
    """Browse scenarios, run them and watch progress, read and compare results, list plugins.

    Example: gearlab tui scenarios (then ? lists the keys)
    """
    if not directory.is_dir():
        raise GearlabInputError(f"{directory}: no such directory of scenario files")
    from ..tui import run_tui

    code = run_tui(directory)
    if code:  # the app ended on an internal error (Textual printed it): not a success
        raise typer.Exit(1)
