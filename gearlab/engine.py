"""The run engine shared by the CLI and the TUI: load and check a scenario, create or resume
its run directory, run its kind, write the report.

It sits above the scenario kinds (it looks a kind up by name in SCENARIO_KINDS) and above the
report; nothing below imports it. Progress goes out as gearlab.events.Event objects to one
callback: the CLI draws rich progress bars from them, the TUI its widgets.
"""

from __future__ import annotations

import threading
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from .confined import Confined
from .errors import GearlabInputError
from .events import PROGRESS, Event, EventSink, ignore_events, standing, telling_figures
from .executors import UnitLines
from .files import cannot_write, write_problem
from .kinds import SCENARIO_KINDS
from .kinds.common import executor_for, stored_forms
from .memo import keep_freed_heap
from .report import write_report
from .runinfo import Session
from .runs import RunDir, check_inputs
from .scenario import (
    EXECUTION_TABLE,
    OUTPUT_TABLE,
    SCENARIO_TABLE,
    Scenario,
    location,
    one_of,
    read_toml,
    validate_table,
    validate_tables,
)


class ProgressWatcher(threading.Thread):
    """Turns the progress/ folder into events: Event('unit', stage=unit, message=text) when a
    unit reports, and with an empty message when its file goes (the unit ended). The lines of
    units that report elsewhere (``elsewhere``: a Ray run's, Executor.unit_lines) count alike."""

    def __init__(self, run: RunDir, on_event: EventSink, every: float = 0.5):
        super().__init__(daemon=True)
        self.folder, self.on_event, self.every = run.file(PROGRESS), on_event, every
        self.elsewhere: UnitLines | None = None
        self.stopped = threading.Event()
        try:
            self.folder.remove_tree()  # left by a killed run
        except OSError:
            pass

    def run(self) -> None:
        shown: dict[str, str] = {}
        while not self.stopped.wait(self.every):
            shown = self.scan(shown)
        self.scan(shown, final=True)  # a last look: a unit that ended since the previous one still says so

    def scan(self, shown: dict[str, str], final: bool = False) -> dict[str, str]:
        """Send the reports that changed since *shown* and the ends of the units gone; the
        reports now shown. *final*: the last look waits for the lines from elsewhere."""
        now = {}
        try:
            reports = self.folder.files("*.txt")
        except (OSError, GearlabInputError):  # progress/ is no folder of the run's own: nothing to show
            reports = []
        for path in reports:
            try:
                now[path.stem.replace("__", "/")] = path.read_bytes(limit=1 << 16).decode(errors="replace")
            except (OSError, GearlabInputError):  # it went between the listing and the read
                continue
        elsewhere = self.elsewhere
        if elsewhere is not None:
            try:
                now.update(elsewhere(final))
            except Exception:  # a Ray session that broke: the run's own error says so; its lines go
                self.elsewhere = None
        for unit, text in now.items():
            if shown.get(unit) != text:
                self.on_event(Event("unit", stage=unit, message=text))
        for unit in shown.keys() - now.keys():
            self.on_event(Event("unit", stage=unit))
        return now

    def stop(self) -> None:
        """The last look, then the folder goes: empty once every unit ended (issue 41: a run left an
        empty progress/ beside its results, as it left its .lock)."""
        self.stopped.set()
        self.join()
        try:
            if self.elsewhere is not None:
                self.elsewhere.close()
        except Exception:  # (as in scan) never in the way of the run's own end or error
            pass
        try:
            self.folder.remove_tree()
        except (OSError, GearlabInputError):  # a file system that refuses: the next run's start removes it
            pass


def _serialised(on_event: EventSink) -> EventSink:
    """The sink, safe to call from the engine and the progress watcher alike."""
    lock = threading.Lock()

    def sink(event: Event) -> None:
        with lock:
            on_event(event)

    return sink


def load_scenario(
    path: str | Path | Confined,
    overrides: Mapping[str, Mapping[str, Any]] | None = None,
    base: str | Path | None = None,
) -> Scenario:
    """Read, validate and resolve a scenario; raises GearlabInputError with file/table/key.

    *path*: a scenario file, or a run directory's copy of one (RunDir.scenario_file()).
    *overrides* ({table: {key: value}}, e.g. the CLI's --executor or --trials) replace keys of
    the file before validation, so they are checked like the file's own values."""
    source = path if isinstance(path, Confined) else Path(path)
    path = source.path if isinstance(source, Confined) else source
    data = read_toml(source)
    if isinstance(source, Confined):  # a run's copy: made, perhaps, before a key moved
        data = stored_forms(data)
    for table, values in (overrides or {}).items():
        if not isinstance(data.get(table, {}), dict):
            raise GearlabInputError(f"{location(path, table)}: expected a table, to set {', '.join(values)} in")
        data.setdefault(table, {}).update(values)
    head = validate_table(path, "scenario", SCENARIO_TABLE, data.get("scenario", {})) if "scenario" in data else None
    if head is None:
        raise GearlabInputError(f"{path}: missing table [scenario] (with name, kind and description)")
    kind = one_of(*SCENARIO_KINDS)(head["kind"], location(path, "scenario", "kind"))
    module = SCENARIO_KINDS[kind]
    schema = {"scenario": SCENARIO_TABLE, "output": OUTPUT_TABLE, "execution": EXECUTION_TABLE, **module.TABLES}
    tables = validate_tables(path, schema, data)
    scenario = Scenario(
        path=path,
        name=head["name"],
        kind=kind,
        description=head["description"],
        tables=tables,
        raw=data,
        base=Path(base) if base is not None else path.parent,
    )
    scenario.spec = module.build(scenario)
    scenario.unit_modules = tuple(module.unit_modules(scenario))
    return scenario


def scenario_of(run: RunDir) -> Scenario:
    """The scenario as *run* ran it (shrunk alike when started with --quick)."""
    scenario = load_scenario(run.scenario_file(), run.meta().get("overrides") or None, base=run.base())
    if run.quick:
        SCENARIO_KINDS[scenario.kind].quick(scenario)
    return scenario


def run_scenario(
    scenario_path: str | Path | None = None,
    *,
    out: str | Path | None = None,
    resume: str | Path | None = None,
    quick: bool = False,
    overrides: Mapping[str, Mapping] | None = None,
    on_event: EventSink = ignore_events,
) -> RunDir:
    """Validate, then run a scenario into a new (or resumed) run directory. *overrides*
    ({table: {key: value}}) replace keys of the scenario file (see load_scenario); a resumed
    run may change only [execution] (where it runs, not what it computes)."""
    on_event = _serialised(on_event)
    if resume is not None:
        run = RunDir.open(Path(resume))
    else:
        if scenario_path is None:
            raise GearlabInputError("no scenario given")
        scenario = load_scenario(scenario_path, overrides)
        if quick:  # the shrunk scenario is checked again: refused before any folder is made
            SCENARIO_KINDS[scenario.kind].quick(scenario)
        run = RunDir.create(scenario.runs_folder(out), scenario, quick, overrides)
    try:
        lock = run.lock()
    except GearlabInputError:
        if resume is None:  # a new run that cannot even be locked (a full disk): leave none
            run.discard()
        raise
    with lock:  # held until the run ends: a second process in this directory is refused
        if resume is not None:
            scenario = _resumed_scenario(run, scenario_path, quick, overrides)
        on_event(Event("run", message=str(run.path)))
        keep_freed_heap()
        on_event(Event("log", message=f"scenario {scenario.name} ({scenario.kind}) -> {run.path}"))
        session = Session(run, scenario.tables.get("execution"))  # run.json: who, where, when
        watcher = ProgressWatcher(run, on_event)
        watcher.start()
        status = "failed"
        try:
            watcher.elsewhere = _ray_opened(scenario, on_event, str(run.path))
            with telling_figures(on_event) as finish:
                SCENARIO_KINDS[scenario.kind].run(scenario, run, on_event)
                write_report(run)
                finish()
            status = "finished"
        except (KeyboardInterrupt, SystemExit):  # Ctrl-C, or SIGTERM (a TUI's cancel)
            status = "cancelled"
            raise
        except GearlabInputError as exc:
            # Refused before any unit finished (e.g. by a check on the built datasets): leave no run behind.
            if resume is None and not run.records():
                run.discard()
                status = ""
            # a line a data file's reading names by its table alone ("[target] key 'files' entry 1 ..."): the
            # scenario it is a table of in front, as every other line names it
            if exc.args and isinstance(exc.args[0], str) and exc.args[0].startswith("["):
                exc.args = (f"{scenario.path}: {exc.args[0]}", *exc.args[1:])
            raise
        except OSError as exc:
            if write_problem(exc) is None:
                raise
            # A full disk, a read-only place: finished units are stored line by line, so a run
            # that has any is kept for --resume; one that has none is removed.
            kept = resume is not None or bool(run.records())
            if not kept:
                run.discard()
                status = ""
            then = (
                f"; the run is kept: once fixed, resume with: gearlab run --resume {run.path}"
                if kept
                else "; no run directory is left"
            )
            raise GearlabInputError(f"{cannot_write(exc, run.path)}{then}") from None
        finally:
            watcher.stop()
            if status:
                session.end(status, device=_trained_on(run) if status == "finished" else None)
    return run


def _ray_opened(scenario: Scenario, on_event: EventSink, space: str) -> UnitLines | None:
    """A Ray run starts its local instance (15-30 s on 2 busy cores) or connects to its cluster as a
    stage of its own, before the kind's first: that time passed under the first bar, at 0 and with
    no word of Ray (issue 41). The kind's executor then finds the session open (one per process).
    Returns where the run's units report their lines on Ray (the session's board), read by the
    watcher: a cluster's nodes share no progress/ folder with this process."""
    if scenario.tables["execution"]["executor"] != "ray":
        return None
    executor = executor_for(scenario)
    where = f"connecting to the cluster at {executor.address}" if executor.address else "starting a local instance"
    on_event(Event("stage", stage="ray", total=1, message=f"Ray: {where}"))
    with standing(on_event, "ray", "waiting for Ray to answer"):  # says for how long after 3 s
        executor.open()
    on_event(Event("advance", stage="ray", done=1, total=1))
    return executor.unit_lines(space)


def _trained_on(run: RunDir) -> str | None:
    """Where the run's networks trained, when its summary says (run.json's device)."""
    try:
        device = run.summary().get("device")
    except (OSError, GearlabInputError):
        return None
    return device if isinstance(device, str) else None


def _resumed_scenario(
    run: RunDir, scenario_path: str | Path | None, quick: bool, overrides: Mapping[str, Mapping] | None = None
) -> Scenario:
    """The scenario a run was started with, shrunk alike if it was started with --quick;
    the results store made ready for appends. Called with the run directory locked."""
    if quick and not run.quick:
        raise GearlabInputError(f"--quick: the run in {run.path} was started without --quick; resume it without")
    if not scenario_path:  # the run's own copy, with the keys its command line set (--seed) set again
        started = run.meta().get("overrides", {})
        overrides = {t: {**started.get(t, {}), **(overrides or {}).get(t, {})} for t in {*started, *(overrides or {})}}
    scenario = load_scenario(
        scenario_path or run.scenario_file(), overrides, base=None if scenario_path else run.base()
    )
    if not run.started_with(scenario, stored_forms):
        if not scenario_path:
            raise GearlabInputError(
                f"{run.path}: the keys given on the command line differ from those the run was started "
                "with; resume without them or start a new run"
            )
        raise GearlabInputError(
            f"{scenario.path}: differs from the scenario the run in {run.path} was started "
            "with; resume without SCENARIO (the run keeps a copy) or start a new run"
        )
    check_inputs(run, scenario)
    if run.quick:
        SCENARIO_KINDS[scenario.kind].quick(scenario)
    run.truncate_partial()
    run.remove_temporaries()
    return scenario


def score_recordings(
    run: RunDir,
    files: list[Path],
    condition: str | None = None,
    on_event: EventSink = ignore_events,
    given: dict | None = None,
) -> list[dict]:
    """New recordings scored by a finished run's trained methods and thresholds (`gearlab score`):
    the run's kind must offer scoring (a `score` function: the detection kind); the rows are
    appended to the run's scoring history and the report is rebuilt to show its trend."""
    with run.lock():  # one process at a time in a run directory
        kind = (run.read_json("summary.json") or {}).get("kind")
        scorer = getattr(SCENARIO_KINDS.get(kind), "score", None)
        if scorer is None:
            raise GearlabInputError(
                f"{run.path}: "
                + (f"a {kind} run keeps no trained methods to score with" if kind else "not a finished run")
                + "; expected a finished detection run"
            )
        rows = scorer(run, files, condition, on_event, given)  # given: the new files' own channel keys
        write_report(run)
    return rows
