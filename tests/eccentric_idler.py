"""Takes of the PHM 2009 rig's train (32T input pinion, 96T / 48T idler, 80T output gear) made with numpy, for the
which-gear check in the envelope (gearlab.signals.envelope_sync): both meshes' harmonics (32 and 16 input orders)
modulated in amplitude by the shafts their gears sit on, the shafts' lines, noise, the speed wandering a little. The
idler's 48T pinion may be eccentric: the second mesh's amplitude follows 1 + *eccentric* cos(idler angle), once per
idler turn, smooth; the 80T gear's own small once- and few-per-turn modulation (its run-out and pitch errors, on a
healthy gear too) multiplies it, so the mesh carries products of the two shafts' lines: at orders of neither shaft
(16 ± 1/3 ± j/5), which only the train's period (15 input turns) repeats. A tooth may also strike once per turn of
its shaft and ring a resonance whose carrier phase wanders (tests/jittered_strikes.py's strike), which every
synchronous average cancels."""

from __future__ import annotations

import dataclasses

import jittered_strikes as J
import numpy as np
from jittered_strikes import Strike

BOX = "phm09"  # the rig's built-in description
FS, SECONDS = 20_000.0, 4.0
PERIOD = 15  # input turns of the train (idler 5, output 3)
CHIP_KAPPA = (32 / (2 * np.pi)) ** 2  # the chip's dent: a von Mises bump of about a pitch's sd (2 pi / 32 rad)
OUTPUT = (0.3, 0.2, 0.12, 0.08, 0.05, 0.04)  # the 80T gear's modulation of its mesh, per output-shaft harmonic


def take(
    seed: int,
    speed: float = 40.0,
    eccentric: float = 0.0,
    strike: Strike | None = None,
    noise: float = 0.3,
    phase: float = 2.2,
    chip: tuple[float, float] | None = None,
    runout: float = 0.0,
):
    """(revolutions (R, POINTS) from the take's first tacho mark, the first one's number from the input angle's zero
    modulo PERIOD, the mean speed (Hz), FS) of a SECONDS take at about *speed* Hz (wandering by 0.5 %), the idler's
    48T pinion *eccentric* (its mesh's amplitude 1 + eccentric cos(idler angle)), *strike* on its shaft ("input",
    "idler" or "output"; a ring at RING_ORDERS of 30 Hz in Hz), *noise* the sensor noise's sd over the first mesh's
    amplitude."""
    from gearlab.signals import POINTS, resample_revolutions

    rng = np.random.default_rng(seed)
    first = int(rng.integers(0, PERIOD))
    t, u, f = J.wandering_turns(rng, first, speed, 0.005, SECONDS, FS)  # u: input turns from the angle's zero
    th, idler, out = 2 * np.pi * u, 2 * np.pi * u / 3, 2 * np.pi * u / 5
    x = 0.3 * np.cos(th + 0.4) + 0.2 * np.cos(idler + 1.1) + 0.15 * np.cos(out + 2.0)
    gear = 1 + sum(a * np.cos((j + 1) * out + 0.7 * j) for j, a in enumerate(OUTPUT))
    dent = 0.0 if chip is None else chip[1] * np.exp(CHIP_KAPPA * (np.cos(th - 2 * np.pi * chip[0]) - 1))
    for h, a in ((1, 1.0), (2, 0.5), (3, 0.25)):  # the first mesh: the input pinion on the idler's 96T gear
        am = (1 + 0.2 * np.cos(th + 0.3) + 0.1 * np.cos(idler + 1.0)) * (1 - dent)
        x = x + a * am * np.cos(h * 32 * th + h)
    for h, a in ((1, 0.8), (2, 0.4), (3, 0.2)):  # the second: the idler's 48T pinion on the output's 80T gear
        am = (1 + 0.1 * np.cos(idler + 0.5) + eccentric * np.cos(idler + phase)) * gear
        x = x + a * am * np.cos(h * 16 * th + 2 * h + h * runout * np.sin(idler + phase))
    x = x + noise * rng.standard_normal(t.size)
    if strike is not None:
        shaft = {"input": 1, "idler": 3, "output": 5}[strike.shaft]  # input turns a turn of the strike's shaft
        x = x + J._strikes(t, u / shaft, dataclasses.replace(strike, shaft="input"), rng)
    angle = th - 2 * np.pi * first  # from the first tacho mark: revolution 0 is the take's turn `first`
    return resample_revolutions(x, angle, points=POINTS), first, float(np.mean(f)), FS
