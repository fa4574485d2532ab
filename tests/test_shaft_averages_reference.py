"""signals.shaft.shaft_averages gives what its plain form gives, to round-off, on a three-stage take (a 22/71 +
27/86 + 34/107 box's four shafts): the plain form, kept here as the reference, reads each shaft's turns by
numpy's own rfft, once per shaft and pass, nothing shared; shaft_averages splits the take's length at its prime
factor (signals.fft) and makes the record's spectrum and denser reading once where every shaft reads the record
itself (sweeps 0)."""

from __future__ import annotations

from fractions import Fraction
from types import SimpleNamespace

import numpy as np
import pytest

from gearlab.signals import shaft

POINTS = 512
TEETH = ((22, 71), (27, 86), (34, 107))


def take(R: int) -> tuple[np.ndarray, SimpleNamespace]:
    """R input revolutions (flat) of each shaft's mesh lines, their sidebands and noise, and the Layout reading
    each shaft's 1st to 3rd orders and its mesh orders."""
    speeds = [Fraction(1)]
    for zp, zw in TEETH:
        speeds.append(speeds[-1] * zp / zw)
    u = np.arange(R * POINTS) / POINTS  # input turns
    y = 0.3 * np.random.default_rng(R).standard_normal(u.size)
    orders, source, index = [], [], []
    for s, o in enumerate(speeds):
        mesh = [TEETH[s - 1][1] if s else None, TEETH[s][0] if s < len(TEETH) else None]  # its wheel, its pinion
        for k in [1, 2, 3] + [z for z in mesh if z]:
            y += np.cos(2 * np.pi * k * float(o) * u + k) / (1 + k / 10)
            orders.append(k * float(o))
            source.append(s)
            index.append(k)
    lay = SimpleNamespace(
        shafts=("input", "intermediate 1", "intermediate 2", "output"),
        shaft_orders=tuple(speeds),
        points=POINTS,
        orders=np.array(orders),
        source=np.array(source),
        index=np.array(index),
    )
    return y, lay


def reference(y: np.ndarray, lay, first: int, R: int, sweeps: int) -> tuple[np.ndarray, np.ndarray, int]:
    """shaft_averages in its plain form (its docstring): nothing shared between readings, numpy's rfft."""
    mean, noise = np.zeros(lay.orders.size, complex), np.zeros(lay.orders.size)
    shafts = sorted(set(lay.source.tolist()), key=lambda s: -lay.shaft_orders[s])
    layout = tuple((s, lay.shaft_orders[s], lay.shafts[s]) for s in shafts)
    cut, periods = shaft._cuts(lay.points, layout, first, R, y.size)
    waves = {}

    def turns(x: np.ndarray, s: int) -> np.ndarray:
        at = cut[s][0]
        if np.array_equal(at, np.round(at)):  # the input shaft: its own samples
            return x[np.round(at).astype(np.int64)]
        return shaft.read_at(np.fft.rfft(x), x.size, at)

    def at_samples(r: int, s: int) -> np.ndarray:
        spectrum = np.fft.rfft(waves[r])
        if lay.shaft_orders[r] < lay.shaft_orders[s]:  # a slower r: less its orders read from s
            spectrum[:: (lay.shaft_orders[r] / lay.shaft_orders[s]).denominator] = 0.0
        return shaft.read_at(spectrum, waves[r].size, cut[r][1], 4)

    def less_others(s: int) -> np.ndarray:
        return turns(y - sum(at_samples(r, s) for r in waves if r != s), s)

    for sweep in range(max(sweeps, 1)):
        for s in shafts:
            segments = less_others(s) if sweeps else turns(y, s)
            waves[s] = segments.mean(axis=0)
            if sweep == max(sweeps, 1) - 1:
                sel = lay.source == s
                m, v = shaft.averaged(segments, int(lay.index[sel].max()), 3)
                mean[sel], noise[sel] = m[lay.index[sel]], v[lay.index[sel]]
    for s in shafts[:-1] if sweeps else ():
        sel = lay.source == s
        m, v = shaft.averaged(less_others(s), int(lay.index[sel].max()), 3)
        noise[sel] = v[lay.index[sel]] + np.abs(mean[sel] - m[lay.index[sel]]) ** 2
    return mean, noise, int(periods)


# 67 and 263 revolutions: a prime at or below signals.fft.MATMUL and above it; the output shaft turns twice and 8 times
@pytest.mark.parametrize("R, first", [(67, 0), (263, 5)])
@pytest.mark.parametrize("sweeps", [0, 1, 2])
def test_shaft_averages_are_their_plain_form_s_to_round_off(R, first, sweeps):
    y, lay = take(R)
    mean, noise, periods = shaft.shaft_averages(y, lay, first, R, sweeps)
    ref_mean, ref_noise, ref_periods = reference(y, lay, first, R, sweeps)
    assert periods == ref_periods >= 2
    assert np.max(np.abs(mean - ref_mean)) <= 1e-9 * np.max(np.abs(ref_mean))
    assert np.max(np.abs(noise - ref_noise)) <= 1e-9 * np.max(ref_noise)
    assert np.all(ref_noise > 0)
