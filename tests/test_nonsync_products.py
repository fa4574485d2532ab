"""A gear fault's own products in the non-synchronous residual (gearlab.signals.nonsync.products). A tooth fault
modulates its mesh at every order of its shaft, and the mesh carries its sidebands by the mate it meshes with: their
products, k o_s + n o_m, are no whole order of either shaft, so they stay in the residual and its envelope. Beside a
gear named on that shaft, such a line is the gear's, not a bearing's (issue 39: a 37/89 box's chipped pinion was
called 'also other damage: non-synchronous (bearing-like), at order 2.17', 3 o_1 - 2 o_2, in 8 of 8 takes), while a
bearing's strikes beside it are still said."""

from __future__ import annotations

import numpy as np
import pytest
from gearboxes import description, stage
from scipy import signal
from scipy.io import wavfile

from gearlab.gearbox import load_gearbox, order_table
from gearlab.inspect import InspectOptions
from gearlab.signals import nonsync as NS

FS, SPEED, Z = 24000.0, 12.0, (37, 89)
BOX = description(stage(*Z, bores=("30 mm", "50 mm")), name="box37", speed="12 Hz", load="300 N*m", tacho="input")
PRODUCT = 3 - 2 * Z[0] / Z[1]  # 2.1685: three pinion-shaft orders less two of the wheel's


@pytest.fixture(scope="module")
def table(tmp_path_factory):
    path = tmp_path_factory.mktemp("products") / "box.toml"
    path.write_text(BOX)
    return order_table(load_gearbox(path))


def test_a_line_is_a_gear_s_product_on_its_shaft_s_lattice_to_half_a_bin_of_the_take(table):
    turns = 95
    assert NS.products(PRODUCT, table, turns) == ("input",)
    assert NS.products(PRODUCT + 0.4 / turns, table, turns) == ("input",)
    assert NS.products(PRODUCT + 0.6 / turns, table, turns) == ()
    # an outer race's ball pass, 3.57: no product of the pinion's shaft; 11 o_2 - o_1 of the wheel's (3.573: a
    # bearing's line lands on a named wheel's lattice by chance, 21 % of orders on this box)
    assert NS.products(3.57, table, turns) == ("output",)
    wheel = 5 * Z[0] / Z[1]  # the wheel's own 5th order (n = 0), read to the take's resolution, not to 1/32 order
    assert "output" in NS.products(wheel + 0.004, table, turns)
    assert "output" not in NS.products(wheel + 0.02, table, turns)


def test_a_line_beside_a_gear_is_excused_only_as_a_product_of_a_flagged_shaft(table):
    ns = {"changed": True, "order": PRODUCT, "shafts": ["input"], "locked": ""}
    assert NS.beside(ns, SPEED, ["input"]) == ""
    assert NS.beside(ns, SPEED, ["output"]) == f"non-synchronous (bearing-like), at order {PRODUCT:.2f}"


def _take(seed: int, chip: float = 0.0, bearing: float = 0.0, seconds: float = 8.0):
    """(m/s², each input turn's angle) of the 37/89 box at about 12 Hz as the issue's takes were made: 4 mesh
    harmonics modulated in amplitude and phase by both shafts (the box's own phases), shaft lines, a slow speed
    wander of 0.3 %, a path through a 3.1 kHz resonance, noise 20 dB under; *chip*: the pinion's tooth, its mesh
    changed once a turn and a strike ringing the resonance; *bearing*: strikes at 3.57 input orders slipping 1 %,
    ringing 4.6 kHz."""
    rng, box = np.random.default_rng(seed), np.random.default_rng(1002)
    n = int(seconds * FS)
    wander = signal.filtfilt(*signal.butter(2, 0.5 / (FS / 2)), rng.standard_normal(n))
    a_in = 2 * np.pi * np.cumsum(SPEED * (1 + 0.003 * wander / wander.std())) / FS + rng.uniform(0, 2 * np.pi)
    a_out = a_in * Z[0] / Z[1]
    am = 1 + 0.25 * np.cos(a_in + box.uniform(0, 6.28)) + 0.2 * np.cos(a_out + box.uniform(0, 6.28))
    am += 0.08 * np.cos(2 * a_in + box.uniform(0, 6.28))
    pm = 0.3 * np.sin(a_in + box.uniform(0, 6.28)) + 0.25 * np.sin(a_out + box.uniform(0, 6.28))
    loc = chip * np.exp(-0.5 * (np.angle(np.exp(1j * (a_in - 0.7))) / (2 * np.pi / Z[0] * 0.8)) ** 2)
    x = np.zeros(n)
    for k in range(1, 5):
        amp = 4.0 * np.sqrt(2) * 0.8 ** (k - 1) * box.uniform(0.6, 1.0)
        x += amp * am * (1 - 0.5 * loc) * np.cos(k * (Z[0] * a_in + pm + 1.5 * loc) + box.uniform(0, 6.28))
    for a in (a_in, a_out):
        x += 0.6 * np.cos(a + box.uniform(0, 6.28)) + 0.2 * np.cos(2 * a + 1)
    ring = signal.iirpeak(3100.0, 6.0, FS)
    strikes = np.zeros(n)
    strikes[np.flatnonzero(np.diff(np.floor((a_in - 0.7) / (2 * np.pi))) > 0) + 1] = 100.0 * chip
    y = 0.7 * x + 2.0 * signal.lfilter(*ring, x) + signal.lfilter(*ring, strikes)
    if bearing:
        turns, at, hits = a_in / (2 * np.pi), a_in[0] / (2 * np.pi) + rng.uniform(0, 0.2), []
        while at < turns[-1]:
            hits.append(at)
            at += (1 + 0.01 * rng.standard_normal()) / 3.57
        idx = np.searchsorted(turns, hits)
        struck = np.zeros(n)
        struck[idx[idx < n]] = bearing
        y += signal.lfilter(*signal.iirpeak(4600.0, 8.0, FS), struck)
    return y + rng.normal(0, 0.1 * y.std(), n), a_in


@pytest.fixture(scope="module")
def takes(tmp_path_factory):
    folder = tmp_path_factory.mktemp("products_takes")
    (folder / "box.toml").write_text(BOX)
    made = {
        **{f"history{k}": {"seed": k} for k in (1, 2, 3)},
        "chip": {"seed": 11, "chip": 0.6},
        "chip_bearing": {"seed": 12, "chip": 0.6, "bearing": 60.0},
    }
    for name, kw in made.items():
        y, a_in = _take(**kw)
        counts = np.stack([y / 9.80665 * 0.1, np.where(np.mod(a_in, 2 * np.pi) < 0.9, 4.0, 0.0)], 1) / 5.0 * 32767
        wavfile.write(folder / f"{name}.wav", int(FS), np.round(counts).astype(np.int16))  # 100 mV/g, 5 V full scale
    return folder, load_gearbox(folder / "box.toml")


def _inspected(takes, name: str) -> dict:
    from gearlab.inspect_history import localisation

    folder, box = takes
    history = [str(folder / f"history{k}.wav") for k in (1, 2, 3)]
    keys = InspectOptions(vibration="0", tacho="1", gain=5.0, sensitivity=0.1 / 9.80665)
    return localisation(str(folder / f"{name}.wav"), history, box, keys)


def test_a_chipped_pinion_s_products_with_its_wheel_are_not_called_a_bearing_beside_it(takes):
    got = _inspected(takes, "chip")
    ns = got["nonsync"]
    assert got["named"] == "input pinion 37T (stage 1)", got["summary"]
    assert got["call"] == "localised change: input pinion 37T (stage 1)", got["call"]
    assert ns["changed"] and "input" in ns["shafts"], ns  # its line: a product of the pinion's shaft and its wheel's


def test_a_bearing_s_strikes_beside_the_chipped_pinion_are_still_said(takes):
    got = _inspected(takes, "chip_bearing")
    ns = got["nonsync"]
    assert got["named"] == "input pinion 37T (stage 1)", got["summary"]
    assert ns["changed"] and ns["shafts"] == [], ns
    assert got["call"].startswith(
        "localised change: input pinion 37T (stage 1); also other damage: non-synchronous (bearing-like), at order "
    ), got["call"]
