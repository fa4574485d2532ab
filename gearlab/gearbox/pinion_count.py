"""Which input-pinion tooth counts a record without a tacho allows (issue 39).

A mesh line alone cannot tell a pinion's count: z teeth at f Hz mesh where z' teeth at f z / z' do, and a
description's speed is nominal (±NOMINAL_RANGE). Only the input shaft's own lines tell them apart: the
sidebands of the first mesh (their spacing is the shaft's frequency, gearbox.speed.sideband_teeth) or a line
at the shaft's frequency. Later stages, the wheels' sidebands and the mesh harmonics read the same for
every count (their frequencies are the first mesh's times ratios of the other gears)."""

from __future__ import annotations

import math

import numpy as np

from ..signals.checks import fmt_hz
from .match import MIN_TEETH, tol_mesh
from .speed import DECLARED_RANGE, DRIFT, NOMINAL_RANGE, SIDEBAND_WINDOW, TEETH_AGREE, Lines, sideband_teeth

SHAFT_HARMONICS = 3  # a shaft's sidebands of a mesh, and its own harmonics, are read to the 3rd (as its combs are)


def allowed_counts(mesh_hz: float, declared: float) -> list[int]:
    """The whole pinion counts whose speed, *mesh_hz* / z, lies within the nominal range of *declared*."""
    low, high = mesh_hz / (declared * (1 + NOMINAL_RANGE)), mesh_hz / (declared * (1 - NOMINAL_RANGE))
    return [z for z in range(math.ceil(low), int(high) + 1) if z >= 1]


def pinion_evidence(lines: Lines, f0: float, revolutions: int, table, said: int, declared: float) -> tuple:
    """(the first mesh's line in Hz or None, the count the input shaft's lines show or None, [(z, Hz) of every
    other whole count the mesh line allows at a speed within the nominal range of *declared*]) of a record
    read at uniform input angle at *f0* Hz (*lines* in orders, *revolutions* read, *table*: the order table,
    *said*: the described pinion count). Lines another shaft explains are left out (a 57-tooth output wheel's
    3rd harmonic sideband, 3 x 500 / 57 Hz from a 500 Hz mesh, showed a 19-tooth pinion at 26.3 Hz)."""
    bin_ = 1.0 / revolutions
    i = lines.near(float(said), tol_mesh(float(said), bin_))
    if i is None:
        return None, None, []
    mesh_hz, df = float(lines.at[i] * f0), f0 * bin_
    in_hz = _other_shafts_out(Lines(lines.at * f0, lines.amp, lines.db), mesh_hz, table, said, df)
    counts = allowed_counts(mesh_hz, declared)
    others = [(z, mesh_hz / z) for z in counts if z != said]
    seen = sideband_teeth(in_hz, mesh_hz / said, table.stages[0], df)
    if seen is not None and abs(seen - round(seen)) <= TEETH_AGREE and round(seen) >= 1:
        return mesh_hz, int(round(seen)), others
    return mesh_hz, shaft_line_count(in_hz, mesh_hz, declared, df), others


def _other_shafts_out(lines: Lines, mesh_hz: float, table, said: int, df: float) -> Lines:
    """*lines* (Hz, at uniform angle: order x mean speed, bin *df*) without those a later shaft's sideband of a
    mesh harmonic (or its harmonic from 0 Hz), j <= SHAFT_HARMONICS, explains to half a bin (a refined line sits
    a small share of a bin from its frequency; a 33/131 pinion's sideband 1.2 bins from the wheel's 4th harmonic
    is the pinion's). The later shafts turn at (their order / the described count *said*) x the first mesh
    *mesh_hz* whatever the pinion's count. Beyond j = 3 a slow shaft's comb covers any line: a 29/109 + 21/81 +
    29/114 box's output at 0.617 Hz put its 57th within half a bin of the input's sideband at 35.18 Hz."""
    d = np.abs(lines.at - np.round(lines.at / mesh_hz) * mesh_hz)
    keep = np.ones(lines.at.size, bool)
    k = np.arange(1, SHAFT_HARMONICS + 1)
    for fo in (float(o) * mesh_hz / said for o in table.shaft_orders[1:]):
        keep &= np.abs(d[:, None] - k[None, :] * fo).min(axis=1) > 0.5 * df
    return Lines(lines.at[keep], lines.amp[keep], lines.db[keep])


def shaft_line_count(in_hz: Lines, mesh_hz: float, declared: float, df: float, table=None, said=0) -> int | None:
    """The one pinion count the mesh line allows (allowed_counts) with a line at its shaft's frequency,
    mesh_hz / z (*in_hz*: lines in Hz, bin *df*), or None (none, or several); with *table* and the described
    count *said*, the lines later shafts explain left out first."""
    if table is not None:
        in_hz = _other_shafts_out(in_hz, mesh_hz, table, said, df)
    counts = allowed_counts(mesh_hz, declared)
    shaft = [z for z in counts if in_hz.near(mesh_hz / z, max(2.5 * df, DRIFT * mesh_hz / z)) is not None]
    return shaft[0] if len(shaft) == 1 else None


def alternatives_words(others: list[tuple], speed_key: str = "--speed", table=None) -> str:
    """'a 26-tooth pinion at 24.09 Hz gives the same line' for the other counts a mesh line allows; *speed_key*:
    where the measured speed is given (inspect's option; a scenario's key); with the order *table*, why the input's
    own lines cannot tell them (hidden_by)."""
    said = [f"a {z}-tooth pinion at {fmt_hz(hz)}" for z, hz in others]
    named = said[0] if len(said) == 1 else ", ".join(said[:-1]) + " or " + said[-1]
    why = hidden_by(table) if table is not None else ""
    return f"{named} gives the same mesh line{why}; a tacho or the measured speed ({speed_key}) would decide"


def hidden_by(table) -> str:
    """Where a later shaft turns once in a whole number of input turns, up to SHAFT_HARMONICS, the input's sidebands
    and lines are that shaft's harmonic's too and _other_shafts_out leaves them out: a 21/63 + 18/54 + 15/45 box
    with clear sidebands 1 order off its first mesh was told only 'a tacho or the measured speed would decide'."""
    for name, o in zip(table.shafts[1:], table.shaft_orders[1:]):
        turns = 1 / o
        if turns.denominator == 1 and turns <= SHAFT_HARMONICS:
            return (
                f" (the input turns {turns} times a turn of the {name} shaft: its sidebands and lines are that "
                "shaft's too, and tell no count)"
            )
    return ""


def no_speed_line(mesh_hz: float | None, declared: float, seen: bool = False) -> str:
    """No speed confirmed, in the words the verdict's speed line takes after the speed search's note: the
    pinion counts and speeds (within the nominal range of the *declared* one) the mesh line allows; *seen*:
    sidebands showed a count, but the rows read at its speed did not bear it out."""
    words = "no sideband of the input shaft confirms a speed"
    if seen:
        words = "the input shaft's sidebands confirm no speed (read at the one they show, the orders are off)"
    tells = "a tacho or the measured speed, --speed, tells"
    counts = allowed_counts(mesh_hz or 0.0, declared)
    if not counts:
        return f"{words} ({tells})"
    said = [f"a {z}-tooth pinion's at {fmt_hz(mesh_hz / z)}" for z in counts]
    if len(said) <= 4:
        allowed = said[0] if len(said) == 1 else ", ".join(said[:-1]) + " or " + said[-1]
    else:
        allowed = f"any pinion's from {counts[0]} teeth at {fmt_hz(mesh_hz / counts[0])} to {counts[-1]} at "
        allowed += fmt_hz(mesh_hz / counts[-1])
    return f"{words}: the mesh at {fmt_hz(mesh_hz)} is {allowed} ({tells} which)"


def sideband_counts(lines: Lines, stage, declared: float, df: float) -> tuple[float | None, list[tuple]]:
    """(the first stage's mesh line, Hz, or None; [(a line, the pinion's tooth count its sidebands show)])
    of a record read at the *declared* speed, its *lines* in Hz (bin *df*): each line, strongest first,
    where the described pinion's mesh could lie (within ±SIDEBAND_WINDOW of its count at the declared
    speed), tried as that mesh; the sidebands where the speed search looks for them (gearbox.speed.
    sideband_teeth) must put the pinion at a whole count (±TEETH_AGREE) and the speed, the line over it,
    within the nominal range (a 40-tooth mesh's 3rd subharmonic, read as the mesh of a 41-tooth one, made
    a 37-tooth pinion at 8.8 Hz). The mesh line: the strongest such."""
    said, first, found = stage.pinion_teeth, None, []
    for q in np.argsort(-lines.amp):
        at = float(lines.at[q])
        if abs(at / (declared * said) - 1) > SIDEBAND_WINDOW:
            continue
        first = at if first is None else first
        seen = sideband_teeth(lines, at / said, stage, df)
        if seen is None or abs(seen - round(seen)) > TEETH_AGREE or round(seen) < 1:
            continue
        if abs(at / round(seen) / declared - 1) <= NOMINAL_RANGE:
            found.append((at, round(seen)))
    return first, found


SIDEBANDS = "the input pinion's sidebands"  # inspect's words for what gave a pinion's count: sideband_counts
EVERY_STAGE = "the mesh lines of every stage"  # every_stage_count


def every_stage_count(lines: Lines, table, said: int, bin_: float) -> list[tuple[float, int]]:
    """[(the first mesh's line, in orders; the input pinion's count)]: the count other than *said* whose mesh
    orders, the described ones scaled by count / *said* (every later shaft turns at the first mesh over the
    described wheels), put a line (*lines*, in orders of a declared speed, bin *bin_*, trusted to
    ±DECLARED_RANGE) at a mesh harmonic (1-4) of every stage of a train of two or more, holding OUTWEIGH times
    the amplitude *said*'s orders find and any other count's; [] else (one stage: a line alone, the speed or
    the count, is at_declared's). A 15/47 + 19/58 + 22/63 box described with 16 teeth, no tacho, its sensor on
    the output: 'an 18-tooth pinion at 49.51 Hz' was read off stage 2's 3rd harmonic, 891 Hz; its lines at
    49 Hz are orders 15, 6.064 and 2.3 (weak lines within 1 % of 16, 6.468 and 2.453 too)."""

    def line(order: float) -> tuple[float, float] | None:  # (the fundamental its line puts the mesh at, amplitude)
        got = []
        for h in range(1, 5):
            i = lines.near(h * order, max(tol_mesh(h * order, bin_), DECLARED_RANGE * h * order))
            if i is not None:
                got.append((float(lines.at[i]) / h, float(lines.amp[i])))
        return max(got, key=lambda g: g[1]) if got else None

    def every(z: int) -> tuple[float, float]:  # (the first mesh, the amplitude found; 0 where a stage has none)
        found = [line(float(s.mesh) * z / said) for s in table.stages]
        return (found[0][0], sum(a for _, a in found)) if all(found) else (0.0, sum(g[1] for g in found if g))

    if len(table.stages) < 2:
        return []
    low, high = max(MIN_TEETH, round(0.75 * said)), round(1.34 * said)
    fits = sorted(((every(z), z) for z in range(low, high + 1)), key=lambda f: -f[0][1])
    (first, score), z = fits[0]
    if z == said or not first or any(f[0][1] * OUTWEIGH > score for f in fits[1:] if f[1] == said or f[0][0]):
        return []
    return [(first, z)]


OUTWEIGH = 3.0  # a count every stage's lines show holds 3 times the amplitude of the described (or another)
