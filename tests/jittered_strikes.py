"""Takes of a 39/61 single-stage box at about 30 Hz made with numpy, for the which-gear check in the envelope
(gearlab.signals.envelope_sync): the mesh's harmonics modulated in amplitude and phase by both shafts, both shafts'
lines, noise, the speed wandering a little; a damaged tooth strikes once per turn of its shaft and rings a structural
resonance at a fixed frequency in Hz (RING_ORDERS input orders at 30 Hz), each strike's instant jittering by up to
half a ring period, so the ring's carrier phase wanders from turn to turn and every shaft's synchronous average
cancels it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

PINION, WHEEL = 39, 61
BOX = (
    '[gearbox]\nname = "mill39"\n[operation]\nspeed = "30 Hz"\nload = "20 N*m"\n'
    '[[stages]]\nmodule = "2 mm"\nface_width = "20 mm"\n'
    f'pinion = {{ z = {PINION}, bore = "25 mm" }}\nwheel = {{ z = {WHEEL}, bore = "30 mm" }}\n'
    '[sensor]\nnear = "input"\ntacho = "input"\n'
)
FS, SPEED, SECONDS = 20_000.0, 30.0, 4.0
RING_ORDERS = 120.9  # the resonance, in input orders at SPEED
DAMPING = 0.03  # the resonance's damping ratio


@dataclass(frozen=True)
class Strike:
    shaft: str  # "input" or "output"
    angle: float  # the damaged tooth's angle on its shaft, in turns from the take's zero
    level: float  # the ring's peak over the mesh's first harmonic's amplitude
    jitter: float = 0.5  # each strike's instant off by up to this share of a ring period (uniform)


def wandering_turns(rng, first: int, speed: float, wander: float, seconds: float, fs: float):
    """(t (s), u: input turns from the angle's zero, starting at turn *first*, f: the speed (Hz)) of a take of
    *seconds* at *fs* whose speed wanders slowly (a random walk) by up to *wander* of *speed* (Hz)."""
    t = np.arange(int(seconds * fs)) / fs
    slow = np.cumsum(rng.standard_normal(t.size // 2000 + 2))
    slow = (slow - slow.mean()) / max(np.abs(slow - slow.mean()).max(), 1e-12)
    f = speed * (1 + wander * np.interp(t, np.linspace(0, seconds, slow.size), slow))
    return t, first + np.r_[0.0, np.cumsum(f[:-1]) / fs], f


def take(seed: int, strike: Strike | None = None, noise: float = 0.3, wander: float = 0.005):
    """(revolutions (R, 4096) from the take's first tacho mark, the first one's number from the input angle's zero
    modulo 61, the mean speed (Hz), FS) of a SECONDS take: each take starts at another turn of the train (the output
    anywhere), its speed wandering by *wander* of SPEED, *noise* the sd of the sensor's noise over the mesh's
    amplitude."""
    from gearlab.signals import POINTS, resample_revolutions

    rng = np.random.default_rng(seed)
    first = int(rng.integers(0, WHEEL))
    t, u, f = wandering_turns(rng, first, SPEED, wander, SECONDS, FS)
    th, out = 2 * np.pi * u, 2 * np.pi * u * PINION / WHEEL
    x = 0.3 * np.cos(th + 0.4) + 0.2 * np.cos(out + 1.1)
    for h, a in ((1, 1.0), (2, 0.5), (3, 0.25)):
        am = 1 + 0.2 * np.cos(th + 0.3) + 0.1 * np.cos(out + 1.0)
        x = x + a * am * np.cos(h * PINION * th + 0.1 * np.sin(th) + 0.05 * np.sin(out) + h)
    x = x + noise * rng.standard_normal(t.size)
    if strike is not None:
        x = x + _strikes(t, u, strike, rng)
    angle = th - 2 * np.pi * first  # from the first tacho mark: revolution 0 is the take's turn `first`
    return resample_revolutions(x, angle, points=POINTS), first, float(np.mean(f)), FS


def _strikes(t: np.ndarray, u: np.ndarray, s: Strike, rng) -> np.ndarray:
    """The rings of *s*'s tooth, struck as its shaft passes its angle (*u*: the input turns at each time *t*)."""
    turns = u if s.shaft == "input" else u * PINION / WHEEL
    hz = RING_ORDERS * SPEED
    at = np.arange(np.ceil(turns[0] - s.angle), np.floor(turns[-1] - s.angle) + 1) + s.angle
    when = np.interp(at, turns, t) + rng.uniform(-s.jitter, s.jitter, at.size) / hz
    tau = np.arange(int(8.0 / (DAMPING * 2 * np.pi * hz) * FS)) / FS  # eight decay times
    a = DAMPING * 2 * np.pi * hz
    out = np.zeros(t.size)
    for w in when:
        i = int(np.ceil(w * FS))
        n = min(tau.size, t.size - i)
        if i < 0 or n <= 0:
            continue
        d = tau[:n] + (i / FS - w)  # time since the strike at each sample
        # an acceleration's ring: the mode back at rest after it, so its area is nil (no synchronous low orders)
        out[i : i + n] += s.level * np.exp(-a * d) * np.sin(2 * np.pi * hz * d - np.arctan2(2 * np.pi * hz, a))
    return out
