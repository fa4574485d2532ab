"""The `gearlab` command (typer + rich).

Exit codes: 0 success, 2 bad input (one clear line on stderr, no traceback), 1 internal error.
"""

from __future__ import annotations

import functools
import io
import json
import sys
import time
import traceback
import warnings
from collections.abc import Callable
from dataclasses import dataclass, fields
from inspect import Parameter, Signature, signature
from pathlib import Path
from typing import Annotated, get_type_hints

import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from .cliconv import HELP_NAMES, ConventionalGroup, conventional
from .errors import GearlabInputError

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
conventional(app)  # -h, SCENARIO / [SCENARIO], PATH / TEXT / INTEGER, no type beside a flag (gearlab.cliconv)
console = Console(soft_wrap=True)
err_console = Console(stderr=True, soft_wrap=True)


def _version(value: bool) -> None:
    if value:
        from importlib.metadata import PackageNotFoundError, version

        try:
            typer.echo(f"gearlab {version('gearlab')}")
        except PackageNotFoundError:  # a source tree that was never installed
            typer.echo("gearlab (not installed: no version)")
        raise typer.Exit()


@app.callback()
def _options(
    version: Annotated[
        bool, typer.Option("--version", callback=_version, is_eager=True, help="print gearlab's version and exit")
    ] = False,
) -> None:
    """gearlab: gear mesh stiffness, gearbox dynamics, fault classifiers and their calibration.

    Example: gearlab run scenarios/quick.toml --quick
    """


@app.command()
def plugins(as_json: Annotated[bool, typer.Option("--json", help="print a JSON list")] = False) -> None:
    """List every registered plugin: kind, name, source package and parameters.

    Example: gearlab plugins --json
    """
    from .registry import get_registry, kind_text, params_text

    registry = get_registry()
    rows = registry.describe()
    if as_json:
        problems = [{"package": p.package, "plugin": p.plugin, "problem": p.message} for p in registry.problems]
        typer.echo(json.dumps(rows + [{"kind": "problem", **p} for p in problems], indent=1))
        return
    table = Table(title="gearlab plugins")
    for col in ("kind", "name", "package", "parameters (unit, default, bounds)"):
        table.add_column(col)
    for row in rows:
        # rich would read "[mm]" as a style tag
        table.add_row(kind_text(row), row["name"], row["package"], escape(params_text(row)) or "-")
    console.print(table)
    for problem in registry.problems:
        console.print(f"[red]problem:[/red] {escape(str(problem))}")


STIFFNESS_HELP = """Time-varying mesh stiffness of a gear-pair preset over one pinion revolution.

Faults (repeat --fault for several, on the same or different teeth; KIND@wheel:TOOTH... on a wheel
tooth; on both gears the TVMS spans the hunting-tooth period, lcm(Z1, Z2) meshes):

  KIND@TOOTH=STEP            a step of the preset's ladder (Tables 2.5/2.6), 1 = healthy .. 20 = worst

  KIND@TOOTH:NAME=VALUE,...  explicit parameters with units; the rest take their defaults,
                             e.g. --fault "crack@3:q0=2 mm,q2=1.5 mm,nu=70 deg"
                                  --fault "spall@5:w_s=8mm,l_s=1mm,h_s=0.5mm,x_1=4mm"

`gearlab plugins` lists every fault's parameters, units, defaults and bounds.

Example: gearlab stiffness --preset luo2019 --fault crack@1=10 --plot tvms.png

A gear pair of your own: gearlab stiffness --gearbox my_gearbox.toml --stage 1 (docs/gearbox.md)
"""


@app.command(help=STIFFNESS_HELP)
def stiffness(
    preset: Annotated[
        str | None, typer.Option(help="gear-pair preset: luo2019 (Table 2.3) or meng2020 (Table 2.4)")
    ] = None,
    gearbox: Annotated[
        str | None, typer.Option(help="a gearbox description (.toml, docs/gearbox.md) or a built-in one's name")
    ] = None,
    stage: Annotated[int, typer.Option(help="with --gearbox: the stage whose gear pair to compute (1 = input)")] = 1,
    fault: Annotated[list[str] | None, typer.Option(help="KIND@TOOTH=STEP or KIND@TOOTH:NAME=VALUE,...")] = None,
    points: Annotated[int, typer.Option(help="samples over one pinion revolution")] = 4096,
    csv: Annotated[Path | None, typer.Option(help="write theta_rad,k_N_per_m to this CSV file")] = None,
    plot: Annotated[Path | None, typer.Option(help="write a PNG of the TVMS (with the healthy TVMS)")] = None,
    fillet: Annotated[bool, typer.Option(help="include the fillet-foundation term")] = True,
    root_region: Annotated[bool, typer.Option(help="include the straight root region d_1")] = True,
) -> None:
    from .files import atomic_write
    from .physics.stiffness import MeshStiffnessModel, StiffnessOptions
    from .settings import shown_values

    if not 64 <= points <= 1 << 20:
        raise GearlabInputError(f"--points: expected 64 .. {1 << 20}, got {points}")
    pair = _stiffness_pair(preset, gearbox, stage)
    placed = _placed_faults(pair, fault)
    _check_folders(csv, plot)
    model = MeshStiffnessModel(pair, StiffnessOptions(fillet=fillet, root_region=root_region))
    start = time.perf_counter()
    ms = model.mesh_stiffness(placed, points)
    elapsed = time.perf_counter() - start
    console.print(
        f"{pair.name}: Z1={pair.Z1}, Z2={pair.Z2}, contact ratio {pair.contact_ratio:.4f}; "
        f"TVMS mean {ms.k.mean():.5g} N/m, min {ms.k.min():.5g}, max {ms.k.max():.5g} ({elapsed * 1e3:.1f} ms)"
    )
    if ms.gear == "both":
        console.print(f"  both gears faulted: the hunting-tooth period, {pair.Z1 / ms.turns:.0f} meshes in the table")
    for p in placed:
        shown = ", ".join(shown_values(p.fault.params, p.params))
        console.print(f"  {p.label}: RFA {p.fault.rfa(p.params, pair.seen_from(p.gear)):.4f}  ({shown})")
    if csv is not None:
        atomic_write(csv, ms.csv_text())
        console.print(f"wrote {csv}")
    if plot is not None:
        from .plots import tvms_figure

        x = ms.theta / ms.turns  # the pinion angle over the table (a wheel turn, the hunting-tooth period)
        curves = [("healthy", x, model.healthy(points, ms.gear))] if placed else []  # on the table's grid
        label = " + ".join(p.label for p in placed) or "healthy"
        tvms_figure(curves + [(label, x, ms.k)], f"TVMS of {pair.name}: {label}", plot)
        console.print(f"wrote {plot}")


def _placed_faults(pair, options: list[str] | None) -> list:
    """The --fault options (KIND@[GEAR:]TOOTH=STEP or KIND@[GEAR:]TOOTH:NAME=VALUE,...) placed on *pair*."""
    from .physics.faults import place_fault_option
    from .registry import get_registry

    return [place_fault_option(get_registry(), pair, text, f"--fault {text!r}") for text in options or []]


def _check_folders(*paths: Path | None) -> None:
    """Refuse an output file whose folder does not exist, before any work."""
    for path in paths:
        if path is not None and not path.parent.exists():
            raise GearlabInputError(f"{path}: directory {path.parent} does not exist")


def _stiffness_pair(preset: str | None, gearbox: str | None, stage: int):
    """The gear pair of `gearlab stiffness`: a preset's, or a stage's of a gearbox description."""
    if preset is None and gearbox is None:
        raise GearlabInputError("Missing option '--preset' (a gear-pair preset) or '--gearbox' (a gearbox description)")
    if preset is not None and gearbox is not None:
        raise GearlabInputError("--preset and --gearbox: give one gear pair, not both")
    if preset is not None:
        from .physics.presets import gear_pair

        return gear_pair(preset)
    from .gearbox import gear_pair as stage_pair
    from .gearbox import resolve_gearbox

    box = resolve_gearbox(gearbox)
    if not 1 <= stage <= len(box.stages):
        count = len(box.stages)
        raise GearlabInputError(f"--stage: {box.source} has {count} stage(s); expected 1 .. {count}")
    return stage_pair(box, box.stages[stage - 1])


@app.command()
def inspect(
    ctx: typer.Context,
    file: Annotated[Path, typer.Argument(help="a recording: .csv, .npz, .h5/.hdf5, .wav or .mat")],
    gearbox: Annotated[
        str | None, typer.Option(help="a gearbox description (.toml, docs/gearbox.md) or a built-in one's name")
    ] = None,
    vibration: Annotated[str | None, typer.Option(help="vibration channel (default: the only one)")] = None,
    tacho: Annotated[str | None, typer.Option(help="tacho channel: pulses or the shaft angle in rad")] = None,
    tacho_kind: Annotated[str, typer.Option(help="auto, angle or pulses")] = "auto",
    pulses_per_rev: Annotated[int | None, typer.Option(help="pulses per turn (default: \\[sensor], else 1)")] = None,
    tacho_shaft: Annotated[str | None, typer.Option(help="the tacho's shaft (default: \\[sensor], else input)")] = None,
    speed: Annotated[
        str | None, typer.Option(help="nominal input-shaft speed without a tacho, e.g. '25 Hz', '1500 rpm'")
    ] = None,
    fs: Annotated[str | None, typer.Option(help="sampling rate when the file has none, e.g. '20 kHz'")] = None,
    sensitivity: Annotated[str | None, typer.Option(help="sensor sensitivity, e.g. '10 mV/g'")] = None,
    gain: Annotated[str | None, typer.Option(help="volts per file unit, e.g. '0.5 mV'")] = None,
    unit: Annotated[
        str | None,
        typer.Option(help="vibration unit where its name and file say none: m/s^2, g, V, mV (+ --sensitivity)"),
    ] = None,
    history: Annotated[list[Path] | None, typer.Option(help="healthy records to localise the change against")] = None,
    history_key: Annotated[list[str] | None, typer.Option(help="a history file's own key: [FILE:]KEY=VALUE")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="print JSON")] = False,
    report_dir: Annotated[
        Path | None, typer.Option("--report", help="also write DIR/report.html and its figures (PNG)")
    ] = None,
) -> None:
    """What a recording holds: rate, duration, channels, speed, the order spectrum, TSA per shaft; with --gearbox, whether the description matches it (mesh orders, shaft orders, tooth counts); with --history, which shaft and gear carry a localised change against those healthy records, else whether a non-synchronous (bearing-like) envelope line passes their threshold.

    Example: gearlab inspect rig.csv --gearbox my_gearbox.toml --tacho tacho --history healthy1.csv --history healthy2.csv
    """  # noqa: E501 (typer keeps line breaks in help text: one paragraph, one line)
    from .inspect_report import show
    from .notebook import inspect_recording

    # the recording's options are inspect_recording's keywords, by name (its checks name them by flag)
    outputs = ("file", "history", "history_key", "as_json", "report_dir")
    options = {k: v for k, v in ctx.params.items() if k not in outputs}
    report = inspect_recording(file, history=history or (), history_keys=history_key, flag=_option, **options)
    show(report, console, as_json, report_dir)


@app.command()
def modes(
    model: Annotated[
        str | None, typer.Option(help="dynamic model: ten_dof, eight_dof, six_dof, ... (default: the --gearbox's)")
    ] = None,
    preset: Annotated[str | None, typer.Option(help="parameter preset (default: the model's first)")] = None,
    gearbox: Annotated[str | None, typer.Option(help="a gearbox description (file or built-in name)")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="print JSON")] = False,
) -> None:
    """Undamped natural frequencies (Hz) of a model at its mean mesh stiffness.

    `frequencies_hz` are those of the free model (every DOF, so a rigid-body 0 Hz mode when the shafts are free); `fixed_input_hz` those of the model as simulated, with the input shaft held at its fixed speed.

    Example: gearlab modes --model ten_dof; gearlab modes --gearbox my.toml
    """  # noqa: E501 (typer keeps line breaks in help text: one paragraph, one line)
    from .gearbox.simulation import label
    from .notebook import simulator

    sim = simulator(model, preset, gearbox=gearbox, flag=_option)  # its checks name the options here
    model = sim.model.name  # the --gearbox's when not given
    free = sim.natural_frequencies(fixed_input=False)
    fixed = sim.natural_frequencies(fixed_input=True)
    if as_json:
        typer.echo(
            json.dumps(
                {
                    "model": model,
                    "preset": sim.preset,
                    "mean_mesh_stiffness_N_per_m": sim.k_mean,
                    "frequencies_hz": free.tolist(),
                    "fixed_input_hz": fixed.tolist(),
                }
            )
        )
        return
    console.print(f"{model} ({label(sim.preset)}), mean mesh stiffness {sim.k_mean:.4g} N/m")
    console.print("free model (Hz):        " + ", ".join(f"{f:.1f}" for f in free))
    console.print("fixed input speed (Hz): " + ", ".join(f"{f:.1f}" for f in fixed))


@app.command()
def simulate(
    out: Annotated[Path, typer.Option(help="output .npz: t, tacho, tvms and one acceleration array per channel")],
    model: Annotated[str | None, typer.Option(help="dynamic model: ten_dof, ... (default: the --gearbox's)")] = None,
    preset: Annotated[str | None, typer.Option(help="parameter preset (default: the model's first)")] = None,
    gearbox: Annotated[str | None, typer.Option(help="a gearbox description (file or built-in name)")] = None,
    speed: Annotated[float | None, typer.Option(help="input-shaft speed, Hz (default: the preset's)")] = None,
    load: Annotated[float | None, typer.Option(help="load torque T_l, N*m (default: the preset's)")] = None,
    fault: Annotated[list[str] | None, typer.Option(help="KIND@TOOTH=STEP or KIND@TOOTH:NAME=VALUE,...")] = None,
    duration: Annotated[float, typer.Option(help="simulated time, s")] = 0.4,
    fs: Annotated[float, typer.Option(help="integration and sampling rate, Hz")] = 200e3,
    plot: Annotated[Path | None, typer.Option(help="PNG of the steady signal and its spectrum")] = None,
) -> None:
    """Simulate a gearbox model (Newmark, fixed input speed) and save its signals.

    Example: gearlab simulate --model six_dof --fault crack@1=20 --out sim.npz --plot sim.png
    """
    import numpy as np

    from .files import atomic_write
    from .gearbox.simulation import label
    from .notebook import simulate_signals
    from .registry import get_registry

    if out.suffix != ".npz":
        raise GearlabInputError(f"--out {out}: expected a .npz file name")
    _check_folders(out, plot)
    with warnings.catch_warnings(record=True) as caught:  # held back: a refused input gets one error line
        warnings.simplefilter("always")
        result = simulate_signals(
            model,
            preset,
            gearbox=gearbox,
            speed=speed,
            load=load,
            faults=fault or (),
            duration=duration,
            fs=fs,
            flag=_option,
        )
    for w in caught:
        warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    buf = io.BytesIO()
    np.savez(buf, t=result.t, tacho=result.tacho, tvms=result.tvms, **result.channels)
    atomic_write(out, buf.getvalue())
    labels = ", ".join(p.label for p in result.faults) or "healthy"
    console.print(
        f"{result.model} ({label(result.preset)}, {labels}): {duration:g} s at {fs:g} Hz, {result.speed_hz:g} Hz, "
        f"{result.load_nm:g} N*m; simulation wall time {result.wall_s * 1e3:.1f} ms"
    )
    console.print(f"wrote {out} (channels: {', '.join(result.channels)})")
    if plot is not None:
        from .plots import signal_and_spectrum
        from .signals import cut_revolutions, revolution_starts, unwrap_tacho

        # The plot starts at the first steady revolution (transient detected on the first channel).
        first = next(iter(result.channels.values()))
        try:
            steady = cut_revolutions(first, result.fs, tacho=result.tacho).first_steady
        except GearlabInputError:
            steady = 0
        start = int(np.ceil(revolution_starts(unwrap_tacho(result.tacho))[steady]))
        pair, _ = get_registry().get("model", result.model).resolve(result.preset)  # the mesh the plot marks
        signal_and_spectrum(result, plot, mesh_hz=result.speed_hz * pair.Z1, start=start)
        console.print(f"wrote {plot} (steady from t = {result.t[start]:.3f} s)")


def _option(key: str) -> str:
    """The option of a keyword of the Python API (gearlab.notebook), as its errors name it here."""
    return "--" + key.replace("_", "-")


@app.command()
def validate(scenario: Annotated[Path, typer.Argument(help="scenario TOML file (or a gearbox description)")]) -> None:
    """Check a scenario file without running it: unknown keys, types, ranges, plugin names.

    Example: gearlab validate scenarios/expB.toml
    """
    from .data.readers.headers import footers_said
    from .gearbox import validated_description
    from .notebook import load_scenario

    if not (said := validated_description(scenario)):  # a description alone was told 'missing table [scenario]'
        s = footers_said(lambda: load_scenario(scenario))  # a logger's footer the run's reader leaves out: said
        said = f"OK: {scenario}: scenario '{s.name}' (kind {s.kind}); {describe_spec(s)}"
    console.print(said, markup=False)


def describe_spec(s) -> str:
    from .kinds import SCENARIO_KINDS

    return SCENARIO_KINDS[s.kind].describe(s)


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
    return with_options


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
    from .kinds import SCENARIO_KINDS
    from .notebook import load_scenario, run_scenario

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
        from .terminal import ProgressView

        with ProgressView(err_console) as view:
            result = run_scenario(
                scenario, out=out, resume=resume, quick=quick, overrides=overrides, on_event=remembered(view.handle)
            )
    except KeyboardInterrupt:
        raise Interrupted(started[-1] if started else None) from None
    from .terminal import print_results
    from .verdict import verdict_lines

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
    from .kinds import GAP_COMMAND_KINDS, SCENARIO_KINDS
    from .notebook import load_scenario

    overrides: dict = {}
    given = _benchmark_keys(trials, seed)
    if scenario == "benchmark":
        path = _shipped_scenario(BENCHMARK)
        overrides.update(given)
    else:
        path = Path(scenario)
        if not path.exists() and "/" not in scenario and not scenario.endswith(".toml"):
            from .errors import did_you_mean

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
    for folder in (Path("scenarios"), Path(__file__).resolve().parents[1] / "scenarios"):
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


@app.command()
def report(run_dir: Annotated[Path, typer.Argument(help="a run directory")]) -> None:
    """Rebuild report.html of a run directory.

    Example: gearlab report runs/quick/20260101-120000-000000
    """
    from .notebook import open_run
    from .report import write_report

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

    Per record: its speed and how it was found, and the gear its change is localised on against the run's history, with the evidence (each shaft's z over its threshold, the tooth). Per method and unit (revolution, recordN): the units called over the threshold, the median score less the threshold, and the decision: most units called is a fault, or "other damage: <gear>" when the change lies on a gear the run does not watch (as the run's which-gear table calls it). Each row is appended to the run's scoring history (scoring/history.jsonl), whose trend per method the report and the TUI show; the last lines (trend:) say per condition which take was first called, by which methods, on which gear and tooth. A take that cannot be scored (a speed far from every condition's) is refused in one line; of several, it is named with why ('not scored') and the others are scored, with exit code 2. With --exit-code, for a script: 1 where any take is called (a fault or other damage, by any method and unit), 0 where none is, 2 as before.

    Example: gearlab score runs/det/20260101-120000-000000 today.csv
    """  # noqa: E501 (typer keeps line breaks in help text: one paragraph, one line)
    from .notebook import score_recordings
    from .terminal import all_scored, score_tables, score_trend

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

    from .runinfo import list_runs
    from .terminal import print_table, runs_table

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

    from .compare import compare_html, compare_lines, load_runs, print_tables
    from .files import atomic_write

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

    from .runinfo import scenario_differences
    from .terminal import print_table

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


@app.command()
def tui(directory: Annotated[Path, typer.Argument(help="folder of scenario files")] = Path("scenarios")) -> None:
    """Browse scenarios, run them and watch progress, read and compare results, list plugins.

    Example: gearlab tui scenarios (then ? lists the keys)
    """
    if not directory.is_dir():
        raise GearlabInputError(f"{directory}: no such directory of scenario files")
    from .tui import run_tui

    code = run_tui(directory)
    if code:  # the app ended on an internal error (Textual printed it): not a success
        raise typer.Exit(1)


def _print_event(event) -> None:
    print(event.to_json(), flush=True)


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
