"""The `gearlab` command (typer + rich).

Exit codes: 0 success, 2 bad input (one clear line on stderr, no traceback), 1 internal error.
"""

from __future__ import annotations

import os
import sys
import traceback
import warnings
from contextlib import contextmanager
from typing import Annotated

import typer

from ..cliconv import HELP_NAMES, ConventionalGroup
from ..errors import GearlabInputError
from . import results, running, tools, tui
from .output import err_console
from .running import Interrupted

# Each command imports what it needs inside its function (start-up time): `gearlab --help`, `validate` and `plugins`
# never load torch, numba or matplotlib. None of these imports hides a cycle (tests/test_architecture.py).

app = typer.Typer(
    cls=ConventionalGroup,
    add_completion=True,  # --install-completion / --show-completion (bash, zsh, fish, PowerShell)
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": HELP_NAMES},
    help="gearlab: gear mesh stiffness, gearbox dynamics, fault classifiers and their calibration.",
)
# One module per group of commands, each its own Typer app (typer's docs: One File Per Command), merged
# here at the top level in the order `gearlab --help` lists them.
app.add_typer(tools.app)
app.add_typer(running.app)
app.add_typer(results.app)
app.add_typer(tui.app)


def _version(value: bool) -> None:
    if value:
        from importlib.metadata import PackageNotFoundError, version

        try:
            typer.echo(f"gearlab {version('gearlab')}")
        except PackageNotFoundError:  # a source tree that was never installed
            typer.echo("gearlab (not installed: no version)")
        raise typer.Exit()


@contextmanager
def one_blas_thread():
    """numpy's and scipy's BLAS (two OpenBLAS libraries) on one thread: the others' products are small, and
    OpenBLAS's second thread spins on each while the other core is busy. Measured, `gearlab inspect` of a 12 s
    take with --gearbox on a 2-core machine at load 6 (median of 3, alternated): 9.3 -> 7.1 s of CPU, 41 -> 24 s;
    with --history of 3 records: 14.3 -> 9.7 s of CPU (signals.fixed_lines.clock_share: 0.2 s a line -> 0.3 ms).
    A library loaded later reads the variable, one loaded already (a notebook's, the tests') is limited; both as
    before afterwards."""
    from threadpoolctl import threadpool_limits  # (start-up time: 13 ms)

    before = os.environ.get("OPENBLAS_NUM_THREADS")
    os.environ["OPENBLAS_NUM_THREADS"] = "1"
    try:
        with threadpool_limits(1, user_api="blas"):
            yield
    finally:
        if before is None:
            os.environ.pop("OPENBLAS_NUM_THREADS", None)
        else:
            os.environ["OPENBLAS_NUM_THREADS"] = before


@app.callback()
def _options(
    ctx: typer.Context,
    version: Annotated[
        bool, typer.Option("--version", callback=_version, is_eager=True, help="print gearlab's version and exit")
    ] = False,
) -> None:
    """gearlab: gear mesh stiffness, gearbox dynamics, fault classifiers and their calibration.

    Example: gearlab run scenarios/quick.toml --quick
    """
    command = ctx.command.get_command(ctx, ctx.invoked_subcommand) if ctx.invoked_subcommand else None
    if command is not None and not getattr(command.callback, "trains", False):  # (running.trains)
        ctx.with_resource(one_blas_thread())  # until the command ends


def _warning_line(message, category, filename, lineno, file=None, line=None) -> None:
    """Warnings as one line on stderr, without Python's source-line echo."""
    err_console.print(f"warning: {message}", markup=False, highlight=False, soft_wrap=True)


def _click_exception():
    try:
        from typer._click import ClickException  # typer >= 0.2x vendors click as typer._click
    except ImportError:
        from click import ClickException
    return ClickException


def main() -> None:
    import signal

    # SIGTERM (kill, a TUI's cancel) unwinds like Ctrl-C, so that the process pool stops its
    # workers instead of leaving them computing as orphans; finished units are already stored.
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(128 + signal.SIGTERM))
    with warnings.catch_warnings():
        warnings.showwarning = _warning_line
        _main()


def _main() -> None:
    try:
        code = app(standalone_mode=False)
        if isinstance(code, int) and code:
            sys.exit(code)
    except GearlabInputError as exc:
        err_console.print(f"error: {exc}", markup=False, highlight=False, soft_wrap=True)
        sys.exit(2)
    except typer.Exit as exc:
        sys.exit(exc.exit_code)
    except typer.Abort:
        err_console.print("aborted")
        sys.exit(1)
    except Interrupted as exc:  # finished units are stored: the run goes on where it stopped
        err_console.print(
            f"interrupted; resume with: gearlab run --resume {exc.run_path}"
            if exc.run_path
            else "interrupted; no run directory was made yet",
            markup=False,
            highlight=False,
        )
        sys.exit(130)
    except OSError as exc:  # a full disk, a read-only place, outside a run (a report, --csv)
        from .files import cannot_write, write_problem

        if write_problem(exc) is None:
            _internal_error(exc)
        err_console.print(f"error: {cannot_write(exc)}", markup=False, highlight=False, soft_wrap=True)
        sys.exit(2)
    except Exception as exc:  # noqa: BLE001 - the last line of defence
        if isinstance(exc, _click_exception()):  # usage: a missing or malformed option, no such command
            message = exc.format_message()
            if not message:  # no arguments at all: the help
                exc.show()
            else:
                ctx = getattr(exc, "ctx", None)
                where = f"{ctx.command_path}: " if ctx is not None else ""
                err_console.print(f"error: {where}{message} (see --help)", markup=False, highlight=False)
            sys.exit(exc.exit_code)
        _internal_error(exc)


def _internal_error(exc: BaseException) -> None:
    traceback.print_exc()
    err_console.print(f"internal error: {type(exc).__name__}: {exc}", markup=False)
    sys.exit(1)
