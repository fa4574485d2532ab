"""The gate of simulate and compare (signals.which_template.structure_gap): the history's mesh harmonics
against the simulated healthy train's. Under heavy noise (benchmarks/localisation.py's random trains at
13.5 dB, development seed 11) the weak harmonics' powers are noise: read with the strong ones they spread
5.3-5.7 dB about the simulation's, the gate (then 5 dB) shut, and the intermediate shaft's two gears were left
to the width ("shaft, both gears"); over the history's lines alone 0.6-0.8 dB."""

from types import SimpleNamespace

import numpy as np

from gearlab.signals.which_template import SHAPE_DB, structure_gap


def test_harmonics_the_noise_buries_do_not_shut_the_gate():
    rng = np.random.default_rng(5)
    healthy = 10.0 ** (-0.25 * np.arange(24))  # simulated harmonic amplitudes, 5 dB less each
    power = 3.0 * healthy**2  # the history's: the same structure, another gain
    line = np.arange(24) < 12  # the twelve strong ones stand clear of the noise
    power[~line] = power[11] * rng.uniform(0.1, 2.0, (~line).sum())  # the rest: the noise's leftover
    lay = SimpleNamespace(carrier=np.ones(24, bool))
    gap = structure_gap(SimpleNamespace(power=power, line=line), lay, healthy)
    assert gap < 0.01 < SHAPE_DB, gap


def test_a_structure_that_differs_on_its_lines_still_shuts_it():
    rng = np.random.default_rng(6)
    healthy = 10.0 ** (-0.25 * np.arange(24))
    power = healthy**2 * 10 ** rng.normal(0.0, 1.0, 24)  # 10 dB of spread on every harmonic
    lay = SimpleNamespace(carrier=np.ones(24, bool))
    assert structure_gap(SimpleNamespace(power=power, line=np.ones(24, bool)), lay, healthy) > SHAPE_DB
