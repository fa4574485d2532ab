"""The commands that need no scenario: plugins, a gear pair's stiffness, a recording's inspection,
a model's modes and signals."""

from __future__ import annotations

import io
import json
import time
import warnings
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table

from ..cliconv import conventional
from ..errors import GearlabInputError
from .output import console

app = conventional(typer.Typer())


@app.command()
def plugins(as_json: Annotated[bool, typer.Option("--json", help="print a JSON list")] = False) -> None:
    """List every registered plugin: kind, name, source package and parameters.

    Example: gearlab plugins --json
    """
    from ..registry import get_registry, kind_text, params_text

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
    from ..files import atomic_write
    from ..physics.stiffness import MeshStiffnessModel, StiffnessOptions
    from ..settings import shown_values

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
        from ..plots import tvms_figure

        x = ms.theta / ms.turns  # the pinion angle over the table (a wheel turn, the hunting-tooth period)
        curves = [("healthy", x, model.healthy(points, ms.gear))] if placed else []  # on the table's grid
        label = " + ".join(p.label for p in placed) or "healthy"
        tvms_figure(curves + [(label, x, ms.k)], f"TVMS of {pair.name}: {label}", plot)
        console.print(f"wrote {plot}")


def _placed_faults(pair, options: list[str] | None) -> list:
    """The --fault options (KIND@[GEAR:]TOOTH=STEP or KIND@[GEAR:]TOOTH:NAME=VALUE,...) placed on *pair*."""
    from ..physics.faults import place_fault_option
    from ..registry import get_registry

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
        from ..physics.presets import gear_pair

        return gear_pair(preset)
    from ..gearbox import gear_pair as stage_pair
    from ..gearbox import resolve_gearbox

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
    history: Annotated[
        list[Path] | None,
        typer.Option(
            help="healthy records to localise the change against, read with this take's --vibration, --tacho, --fs, "
            "--sensitivity, --gain, --unit (one acquisition chain); a file's own unit or rate contradicting them is "
            "refused"
        ),
    ] = None,
    history_key: Annotated[
        list[str] | None, typer.Option(help="a history file's own key: [FILE:]KEY=VALUE (KEY= drops the take's)")
    ] = None,
    takes: Annotated[
        str | None, typer.Option(help="a logger's column marking each sample's take: a row per take (FILE[KEY=N])")
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="print JSON")] = False,
    report_dir: Annotated[
        Path | None, typer.Option("--report", help="also write DIR/report.html and its figures (PNG)")
    ] = None,
) -> None:
    """What a recording holds: rate, duration, channels, speed, the order spectrum, TSA per shaft; with --gearbox, whether the description matches it (mesh orders, shaft orders, tooth counts); with --history, which shaft and gear carry a localised change against those healthy records, else whether a non-synchronous (bearing-like) envelope line passes their threshold. With --takes KEY, a logger's file of several takes: each take inspected, one row each (speed, mesh orders, level, whether it looks like the others; with --history, the call on each).

    Example: gearlab inspect rig.csv --gearbox my_gearbox.toml --tacho tacho --history healthy1.csv --history healthy2.csv
    """  # noqa: E501 (typer keeps line breaks in help text: one paragraph, one line)
    from ..inspect_report import show
    from ..notebook import inspect_recording

    # the recording's options are inspect_recording's keywords, by name (its checks name them by flag)
    outputs = ("file", "history", "history_key", "takes", "as_json", "report_dir")
    options = {k: v for k, v in ctx.params.items() if k not in outputs}
    if takes is not None:  # a logger's file of several takes: a row each (gearlab.inspect_takes)
        from ..inspect_takes import inspect_takes, show_takes

        if report_dir is not None:
            raise GearlabInputError(f"--report: one take's report; give one take, '{file}[{takes}=N]', without --takes")
        given = {"history": history or (), "history_keys": history_key, "flag": _option, **options}
        show_takes(inspect_takes(file, takes, **given), console, as_json)
        return
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
    from ..gearbox.simulation import label
    from ..notebook import simulator

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

    from ..files import atomic_write
    from ..gearbox.simulation import label
    from ..notebook import simulate_signals
    from ..registry import get_registry

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
        from ..plots import signal_and_spectrum
        from ..signals import cut_revolutions, revolution_starts, unwrap_tacho

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
