"""Whether a line at a shaft's order follows the shaft or the clock: a fixed frequency (a mains hum) that lands on a
shaft's harmonic at this speed reads as that harmonic in the order spectrum; where the speed wanders within the take
their phases part. Demodulated at order k of the shaft's angle theta, a line of that order keeps its phase, while a
fixed one's phase turns by -(k theta - its straight-line fit): the phase's slope on that wander is 0 for an order,
1 for a fixed frequency (gearlab.inspect names such lines; a take too steady leaves them alike)."""

from __future__ import annotations

import numpy as np

from ..gearbox.match import UNEXPLAINED_FLOOR_DB, shaft_harmonic, tol_mesh

# The phase is read in Hann blocks this long, half overlapping: short enough to follow a speed's swing over seconds
# (box B's 0.37 Hz), long enough to part the line from its neighbours a few Hz away (another shaft's harmonics).
BLOCK_S = 0.5
# A block holds at least this many of its bins between the line and its nearest other line (a Hann window's main lobe
# is 2 bins wide each side): read in 0.5 s blocks, the 29/101 + 33/107 box's output 2nd harmonic (7.26 Hz, 41 Hz
# input) took in its 1st, 3.63 Hz away, whose phase turned with the speed's swing, and was said to follow the clock.
APART_BINS = 3.0
# Mains, whose harmonics a steady speed cannot tell from a shaft's order: 50 and 60 Hz, their 2nd and 3rd.
MAINS_HZ = tuple(m * hz for hz in (50.0, 60.0) for m in (1, 2, 3))
# The slope is trusted where 0 and 1 lie this many standard errors apart (3 each side of 1/2).
APART_SE = 6.0


def clock_share(
    signal: np.ndarray, fs: float, angle: np.ndarray, order: float, block_s: float = BLOCK_S
) -> tuple[float, float] | None:
    """(slope, its standard error) of the line at *order* of the shaft whose angle per sample is *angle* (rad): ~0 it
    follows the shaft, ~1 the clock; None where the two cannot be told apart (the slope's error over 1/APART_SE: a
    steady speed, a line too weak, a take shorter than 6 blocks of *block_s* seconds)."""
    n, size = signal.size, int(block_s * fs)
    starts = np.arange(0, n - size + 1, size // 2)
    if starts.size < 6:
        return None
    t = np.arange(n) / fs
    centred, wander = t - t.mean(), angle - angle.mean()
    # its straight part (the speed's mean, a line's offset) taken out by least squares in closed form: polyfit's
    # Vandermonde solve cost a 60 s take at 51.2 kHz 1.3 s per line read
    wander = order * (wander - (centred @ wander) / (centred @ centred) * centred)
    window = np.hanning(size)
    base = (signal - signal.mean()) * np.exp(-1j * order * angle)
    phase = np.unwrap(np.angle([base[s : s + size] @ window for s in starts]))  # a block at a time: a long take's
    drift = np.array([wander[s : s + size] @ window for s in starts]) / window.sum()  # blocks would not fit at once
    middle = t[starts + size // 2]
    fit = np.column_stack([np.ones(starts.size), middle - middle.mean(), -drift])
    coef, *_ = np.linalg.lstsq(fit, phase, rcond=None)
    rest = phase - fit @ coef
    try:
        variance = float(rest @ rest / (starts.size - 3) * np.linalg.inv(fit.T @ fit)[2, 2])
    except np.linalg.LinAlgError:  # no wander at all: a speed held exactly
        return None
    if not variance >= 0.0:  # nearly no wander: the inverse's rounding made it negative (or nan), as singular
        return None
    error = variance**0.5
    return None if not error * APART_SE <= 1.0 else (float(coef[2]), error)


def fixed_on_orders(listed: list[dict], lines, table, take: tuple, f0: float, bin_: float) -> list[dict]:
    """The strong lines of *lines* (gearbox.speed.Lines, input orders read at *f0* Hz, *bin_* apart) below every mesh
    of *table* and its sidebands, at a shaft's whole order, not in *listed* (check_description's unexplained), whose
    phase follows the clock (clock_share of *take*: signal, fs, input angle), as check_description lists a line at no
    shaft's order ('not_an_order' True: box B's 50 Hz hum on its input's 2nd order at 25 Hz was read as that
    harmonic); and those at a mains frequency that a steady speed leaves alike ('not_an_order' None: either). Each
    with 'shaft_harmonic' [shaft, harmonic] and 'clock_share' (the slope, None where alike)."""
    below = min(float(s.mesh) - 3 * max(float(s.pinion_shaft_order), float(s.wheel_shaft_order)) for s in table.stages)
    out = []
    for x, amp, db in zip(map(float, lines.at), lines.amp, lines.db):
        shaft = shaft_harmonic(table, x, bin_) if db >= UNEXPLAINED_FLOOR_DB and x < below else None
        if shaft is None or any(u["order"] == x for u in listed):
            continue
        apart = np.abs(np.asarray(lines.at, float) - x)
        apart = apart[apart > 0]
        read = clock_share(*take, x, max(BLOCK_S, APART_BINS / (apart.min() * f0)) if apart.size else BLOCK_S)
        mains = any(abs(x * f0 - hz) <= tol_mesh(x, bin_) * f0 for hz in MAINS_HZ)
        if (read is not None and read[0] > 0.5) or (read is None and mains):
            h = round(x / float(table.shaft_orders[table.shafts.index(shaft)]))
            said = {"order": x, "amplitude": float(amp), "db_over_floor": float(db)}
            said["not_an_order"], said["clock_share"] = (None, None) if read is None else (True, read[0])
            out.append(said | {"shaft_harmonic": [shaft, h]})
    return out


# A line's smear in the order spectrum: a fixed frequency at order o read over a take whose speed spans (max - min) /
# mean = *swing* covers o x swing orders, its strongest part anywhere within (a sine swing's two horns lie at the
# ends); a mesh line read through a coarse angle (a hard-edged tacho on a slow shaft) is modulated by the angle's
# error, at most the speed's own swing, into sidebands in pairs about it. Plus this many bins: the window's main
# lobe, and how far a pair's two lines may sit off the mirror. Box S's hum (20/47 at 24.3 Hz, 0.43 % range) stood at
# 180.25 and 179.79 Hz, 0.019 orders apart within 7.41 x 0.0043 = 0.032; box T's mesh 2 (445.7 Hz, output tacho,
# 0.41 %) at 444.72 and 446.56 Hz, a pair within 9.9 x 0.0041 = 0.041 orders; its hum's 3rd at 180.22 Hz, 0.018
# orders from mesh 3 and no line on the other side, stays a line.
SMEAR_BINS = 2.0


def smear_merged(listed: list[dict], lines, swing: float, bin_: float) -> list[dict]:
    """*listed* (unexplained lines, each with 'order' and 'amplitude') less the skirts of stronger lines of *lines*
    (gearbox.speed.Lines, every peak read) under the take's speed range *swing*: a line within a listed line's smear
    (a fixed frequency's, listed once), or within an explained line's smear with a line on its mirror side (an order
    line's sidebands come in pairs). Merged into the stronger line, listed or explained already."""
    at, amp = np.asarray(lines.at, float), np.asarray(lines.amp, float)
    near = SMEAR_BINS * bin_
    said = [u["order"] for u in listed]

    def skirt(u: dict) -> bool:
        x = u["order"]
        for s in np.flatnonzero((amp > u["amplitude"]) & (np.abs(at - x) <= np.maximum(at, x) * swing + near)):
            if any(abs(at[s] - o) <= near / 4 for o in said) or np.any(np.abs(at - (2 * at[s] - x)) <= near):
                return True
        return False

    return [u for u in listed if not skirt(u)]


def modulation_pairs(listed: list[dict], lines, bin_: float, table=None) -> list[dict]:
    """*listed* (unexplained lines, each with 'order' and 'amplitude'), each of a pair mirrored about a stronger
    line of *lines* (within SMEAR_BINS bins) marked 'modulation' [that line's order, the offset], and where the offset
    is a whole harmonic of a shaft of *table* (gearbox.orders.OrderTable), 'modulation_shaft' [shaft, harmonic]: a
    localised change once a turn of that shaft spreads its mesh's sidebands past those the description lists (a
    33/89 press's cracked pinion: pairs 4, 5 and 6 input orders about its mesh). Without a shaft, a modulation at a
    rate no shaft turns at, not a fixed frequency: a user's 19/103 box at 3 Hz without a tacho, its speed swinging
    0.2 % at 0.37 Hz faster than the mesh's phase is followed, left pairs 0.123 orders about each mesh harmonic
    (52 dB), said 'not a gear order (a fixed frequency such as mains, or a bearing's)'."""
    at, amp = np.asarray(lines.at, float), np.asarray(lines.amp, float)
    near = SMEAR_BINS * bin_
    for u in listed:
        for v in listed:
            c = 0.5 * (u["order"] + v["order"])
            carrier = np.flatnonzero((np.abs(at - c) <= near / 2) & (amp > max(u["amplitude"], v["amplitude"])))
            if u["order"] < v["order"] and carrier.size:
                for w in (u, v):
                    d = abs(w["order"] - float(at[carrier[0]]))
                    w["modulation"] = [float(at[carrier[0]]), d]
                    shaft = None if table is None else _offset_shaft(table, d, tol_mesh(d, bin_) / 2)
                    if shaft:
                        w["modulation_shaft"] = shaft
    return listed


def _offset_shaft(table, d: float, tol: float) -> list | None:
    """[shaft, harmonic] of the shaft whose whole harmonic the offset *d* (input orders) lies nearest, within *tol*
    (a bin and the offset's own drift: two lines read alike), or None: the nearest, not the first, since a slow
    shaft's 7th (2.05) lies near the input's 2nd."""
    misses = [
        (abs(d - round(d / o) * o), name, round(d / o)) for name, o in zip(table.shafts, map(float, table.shaft_orders))
    ]
    misses = [m for m in misses if m[2] >= 1]
    miss, name, h = min(misses) if misses else (np.inf, "", 0)
    return [name, h] if miss <= tol else None


def modulation_words(line: dict) -> str:
    """Why a pair mirrored about a stronger line is listed (modulation_pairs), in the terminal's words."""
    if line.get("modulation_shaft"):
        shaft, h = line["modulation_shaft"]
        nth = {1: "1st", 2: "2nd", 3: "3rd"}.get(h, f"{h}th")
        return f"mirrored: sidebands at the {shaft} shaft's {nth} harmonic (a change once a turn of it?)"
    return "mirrored: a modulation at no shaft's rate (a speed swing?)"
