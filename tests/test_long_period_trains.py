"""Trains of hunting-tooth pairs, whose steady response repeats only after more than MAX_PERIOD input
turns, simulate (issue 39, outside-user round 7): a 19/47 + 23/59 + 29/71 train (its meshes alone
repeat after 2773 turns) and damage on the output gear of a 19/71 + 28/47 train (3337 turns) were
refused ('can't be simulated'). The simulator reads each mesh's TVMS at its own gear's angle, so such
a train needs no grand period: a stretch of steady revolutions after the start-up transient has
decayed (a duration from the model's slowest mode), its records cut within it (builder.steady_stretch)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from gearboxes import description, stage

from gearlab.data import builder
from gearlab.data.simulated import simulated_record
from gearlab.gearbox.simulation import reference
from gearlab.kinds.common import DATASET_TABLE, dataset_spec
from gearlab.signals import resample_revolutions

MIXER = description(
    stage(19, 47),
    stage(23, 59, module="2.5 mm"),
    stage(29, 71, module="3 mm"),
    name="mixer",
    speed="40 Hz",
    load="60 N*m",
)
N_TRAIN = description(stage(19, 71), stage(28, 47, module="2.5 mm"), name="n", speed="40 Hz", load="60 N*m")
SHAFT3 = 19 * 23 / (47 * 59)  # the stage-3 pinion's shaft order
MESHES = (19.0, 19 * 23 / 47, 29 * SHAFT3)  # 19, 9.298, 4.570 input orders


def _order_power(x: np.ndarray, angle: np.ndarray, revolutions: int) -> np.ndarray:
    """Hann-windowed power spectrum of *revolutions* whole input turns of *x*: bin b is order b / revolutions."""
    revs = resample_revolutions(x, angle, 256, count=revolutions).reshape(-1)
    w = np.hanning(revs.size)
    return np.abs(np.fft.rfft(revs * w)) ** 2


def _on_grid(power: np.ndarray, order: float, revolutions: int) -> float:
    """Share of *power* within two bins (the Hann window's main lobe) of the multiples of *order*."""
    b = np.arange(power.size)
    grid = np.abs(b / (order * revolutions) - np.round(b / (order * revolutions))) * order * revolutions <= 2
    return float(power[grid].sum() / power.sum())


def test_a_three_stage_hunting_train_with_a_stage_3_fault_simulates_seconds_with_its_orders(tmp_path):
    (tmp_path / "mixer.toml").write_text(MIXER)
    R, fs = 100, 12_800.0  # 2.55 s at 40 Hz: 100 whole turns and a little
    common = dict(gearbox=str(tmp_path / "mixer.toml"), revolutions=R + 2, fs=fs, sim_fs=200_000, seed=1)
    chip = [{"name": "chip", "gear": "intermediate 2 pinion", "tooth": 3, "step": 20}]
    faulty, healthy = simulated_record(chip, **common), simulated_record([], **common)
    assert faulty.vibration.size == math.ceil((R + 2) / 40.0 * fs) and faulty.gears == ("intermediate 2 pinion",)
    assert faulty.period == healthy.period == 2773 and faulty.start == healthy.start  # the same seed: the same stretch
    # every stage's mesh: its strongest harmonic (of 6) a line at h x its order, 60 dB over its surroundings
    power = _order_power(healthy.vibration, healthy.angle, R)
    for mesh in MESHES:
        lines = []
        for h in range(1, 7):
            b = round(h * mesh * R)
            around = power[b - 30 : b + 31]
            lines.append((power[b - 1 : b + 2].max() / np.median(around), int(np.argmax(around)) - 30))
        top, where = max(lines)
        assert top > 1e6 and abs(where) <= 1, (mesh, lines)
    # the chip on the stage-3 pinion: what it adds lies on that shaft's orders (sidebands of every mesh
    # harmonic h x 4.570 +- k x 0.158), not on another shaft's
    added = _order_power(faulty.vibration - healthy.vibration, faulty.angle, R)
    assert np.std(faulty.vibration - healthy.vibration) > 0.01 * np.std(healthy.vibration)
    assert _on_grid(added, SHAFT3, R) > 0.95 and _on_grid(added, 19 / 47, R) < 0.5
    for h in (5, 6):
        for k in (-2, -1, 1, 2):
            b = round((h * MESHES[2] + k * SHAFT3) * R)
            assert added[b - 1 : b + 2].max() > 1e4 * np.median(added), (h, k)


def test_the_settle_duration_leaves_the_steady_response(tmp_path):
    # 19/71 + 28/47 healthy repeats after 71 turns: its whole-cycle steady response (settled by periods)
    # against a stretch settled by duration (the slowest mode's decay to 1e-6, twice over)
    (tmp_path / "n.toml").write_text(N_TRAIN)
    fs = builder.whole_steps_rate(200e3, 40.0, 19)
    task = builder.SimTask(
        "two_stage", reference(str(tmp_path / "n.toml")), fs, 40.0, 60.0, "casing_x", None, None, (1,)
    )
    cycle = builder.simulate_unit(tuple(task))[0].reshape(71, -1)
    stretch = builder.simulate_unit(tuple(task._replace(stretch=80)))[0].reshape(80, -1)
    settle = builder.settle_revolutions(builder._simulator(task.model, task.preset, fs), 40.0)
    assert settle == 16
    same = cycle[(settle + np.arange(80)) % 71]  # the stretch starts settle turns from the gears' zero
    assert np.abs(stretch - same).max() < 1e-9 * np.abs(cycle).max()


def test_a_dataset_of_the_hunting_train_puts_its_records_where_the_damaged_tooth_meshes(tmp_path):
    (tmp_path / "mixer.toml").write_text(MIXER)
    entry = {k: key.default for k, key in DATASET_TABLE.keys.items()}
    given = dict(gearbox="mixer.toml", faults={"chip@output gear": [20]}, teeth=[3], healthy=3, revolutions=4)
    spec = dataset_spec({**entry, **given}, "s.toml: [source]", Path(tmp_path))
    assert spec.fault_classes()["chip@s3-wheel"].period == 196883  # the output gear turns 12673/196883 a turn
    data, twin = builder.build_dataset(spec), builder.build_dataset(spec.with_(healthy_twin=True))
    assert data.X.shape == (4, 4096) and np.isfinite(data.X).all() and list(data.label) == [0, 0, 0, 1]
    assert np.array_equal(data.X[:3], twin.X[:3])
    # the fault's record starts in a revolution where output-gear tooth 3 meshes: its first revolution
    # holds the chip's impact, against its healthy twin (the same revolution of the healthy stretch)
    assert np.abs(data.X[3] - twin.X[3]).max() > 0.2 * np.abs(twin.X[3]).max()
    pairs = builder.placement.train_pairs(spec.check_model()[0], spec.preset)
    hits = builder.tooth_revolutions(pairs, 3, "wheel", 3, 23, 200)
    q = 19 * 23 * 29 / (47 * 59)  # output-gear teeth meshing per input turn
    assert hits == [math.floor((2 + m * 71) / q) - 23 for m in range(50) if 23 <= (2 + m * 71) / q < 223]


def test_a_dataset_run_of_the_hunting_train_ends(tmp_path, run_scenario, monkeypatch):
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mixer.toml").write_text(MIXER)
    run = run_scenario(
        '[scenario]\nname = "m"\nkind = "dataset"\n[[datasets]]\ngearbox = "mixer.toml"\nfaults = {}\nhealthy = 4\n'
    )
    assert (run / "report.html").exists()


@pytest.mark.parametrize("gear", ["output gear", "intermediate gear"])
def test_damage_past_the_period_on_a_two_stage_train_simulates(tmp_path, gear):
    # 19/71 + 28/47: the output gear's damage repeats after 3337 turns (refused), the intermediate gear's
    # after 71 (simulated whole, as before)
    (tmp_path / "n.toml").write_text(N_TRAIN)
    chip = [{"name": "chip", "gear": gear, "tooth": 2, "step": 20}]
    rec = simulated_record(chip, gearbox=str(tmp_path / "n.toml"), revolutions=30, fs=12_800, sim_fs=200_000, seed=2)
    assert rec.period == {"output gear": 3337, "intermediate gear": 71}[gear] and np.isfinite(rec.vibration).all()
    assert 0 <= rec.start < rec.period and rec.angle[0] < 2 * np.pi


def test_a_record_from_a_stretch_is_the_steady_response_at_its_start(tmp_path, monkeypatch):
    # 19/71 + 28/47 healthy (71 turns) made from a stretch (the limit lowered) against its whole steady
    # cycle read at the record's start (counted from the gears' zero, as a whole period's record is)
    # through the same anti-alias filter: the settle, the margins and the start's bookkeeping
    from scipy.interpolate import CubicSpline

    from gearlab.data import placement
    from gearlab.data.simulated import anti_alias

    tmp = tmp_path
    (tmp / "n.toml").write_text(N_TRAIN)
    monkeypatch.setattr(placement, "MAX_PERIOD", 10)
    rec = simulated_record([], gearbox=str(tmp / "n.toml"), revolutions=20, fs=20_000, sim_fs=200_000, seed=3)
    monkeypatch.setattr(placement, "MAX_PERIOD", 1000)
    fs_sim = builder.whole_steps_rate(200e3, 40.0, 19)
    sim = builder._simulator("two_stage", reference(str(tmp / "n.toml")), fs_sim)
    clean, _ = builder.steady_response(sim, [], 40.0, 60.0, rec.channel, (), whole_cycle=True)
    n = clean.size
    fine = np.fft.irfft(np.fft.rfft(clean) * anti_alias(np.arange(n // 2 + 1) * fs_sim / n, 20_000), 8 * n) * 8
    times = rec.start / 40.0 + np.arange(rec.vibration.size) / 20_000
    # the cycle's periodic cubic spline, solved on the stretch of it the record reads plus 400 samples each side
    # (the cycle's samples, wrapped): a spline's dependence on a sample decays as (2 - sqrt 3)^k, 1e-229 at 400;
    # within 2e-12 of the peak of the whole cycle's periodic spline (2.8 M samples solved for 20 turns' 0.9 M: 3 s)
    at = (times - times[0] // (n / fs_sim) * (n / fs_sim)) * (8 * fs_sim)  # fine samples from the cycle's start
    near = np.arange(math.floor(at[0]) - 400, math.ceil(at[-1]) + 401)
    steady = CubicSpline(near / (8 * fs_sim), fine[near % (8 * n)])(at / (8 * fs_sim))
    assert rec.period == 71 and np.abs(rec.vibration - steady).max() < 1e-5 * np.abs(steady).max()


def _n_train_spec(tmp_path, **given):
    (tmp_path / "n.toml").write_text(N_TRAIN)
    entry = {k: key.default for k, key in DATASET_TABLE.keys.items()}
    spec = dataset_spec({**entry, "gearbox": "n.toml", "faults": {}, **given}, "s.toml: [source]", Path(tmp_path))
    return spec.with_(noise=None)


def test_the_gap_source_rows_of_a_long_train_are_never_cut_across_its_stretch_end(tmp_path, monkeypatch):
    # 19/71 + 28/47 healthy (71 turns) as a long train (the limit lowered): its 128-turn stretch is no
    # period, so a TSA of 32 turns starting in its last 31 was joined end to start, a step no gearbox
    # makes (4 of these 12 rows at f759420, 9-15 % of the peak off any steady TSA). The gap's source
    # rows are the builder's healthy rows bit for bit (each record within the stretch), and each is
    # the TSA of the steady response's own 32 turns.
    from gearlab.data import placement
    from gearlab.gap.scoring import source_rows
    from gearlab.gap.views import healthy_rows

    spec = _n_train_spec(tmp_path, healthy=12, revolutions=32, tsa=True, seed=7)
    monkeypatch.setattr(placement, "MAX_PERIOD", 10)
    rows = source_rows(spec)
    assert np.array_equal(rows, healthy_rows(builder.build_dataset(spec)))
    monkeypatch.setattr(placement, "MAX_PERIOD", 1000)
    fs = builder.whole_steps_rate(spec.fs, 40.0, 19)
    task = builder.SimTask(spec.model, spec.preset, fs, 40.0, 60.0, spec.channel, None, None, (1,))
    cycle = builder.simulate_unit(tuple(task))[0].reshape(71, -1)  # the whole steady cycle
    settle = builder.settle_revolutions(builder._simulator(task.model, task.preset, fs), 40.0)
    for i, row in enumerate(rows):
        start = builder.stretch_start(spec.seed, i, 128, 32)
        steady = cycle[(settle + start + np.arange(32)) % 71].mean(axis=0)
        assert np.abs(row - steady).max() < 1e-5 * np.abs(steady).max(), i


def test_consecutive_gap_source_rows_past_a_long_train_s_stretch_are_a_longer_stretch_s(tmp_path, monkeypatch):
    # [diagnosis] healthy = 140 consecutive rows through a measured target's chain: the rows past the
    # 128-turn stretch were its first turns again (joined end to start: rows 126-139 off by up to 52 %
    # of the peak at f759420). Now the stretch is simulated as long as the record (140 rows and their
    # two neighbours): the rows equal those cut from a longer stretch (150 turns) through the chain.
    from gearlab.data import placement
    from gearlab.data.chain import Chain
    from gearlab.gap import scoring

    spec = _n_train_spec(tmp_path, healthy=140, seed=7)
    monkeypatch.setattr(placement, "MAX_PERIOD", 10)
    chain = Chain(fs=40.0 * 300.5, speed=40.0, fractions=(0.0, 0.25, 0.5), offset=0.0)
    rows = scoring.source_rows(spec, 0, chain, True)
    fs = builder.whole_steps_rate(spec.fs, 40.0, 19)
    task = builder.SimTask(spec.model, spec.preset, fs, 40.0, 60.0, spec.channel, None, None, (1,), (), 1, 150)
    longer = builder.simulate_unit(tuple(task))[0]
    rms = float(np.sqrt(np.mean(longer[: 142 * 4096] ** 2)))
    truth = scoring.measured_rows(spec.with_(seed=8), longer, 40.0, rms, chain, 19, True)
    assert rows.shape == truth.shape == (140, truth.shape[1])
    assert np.abs(rows - truth).max() < 1e-6 * np.abs(truth).max()


def test_the_hunting_bound_names_the_gears_as_the_description_does(tmp_path, monkeypatch):
    # damage on both gears of stage 2 past the hunting bound: the line said "faults chip@s2-pinion:3,
    # chip@s2-wheel:5", labels the user never wrote; now the gears as the description names its shafts
    from gearlab.errors import GearlabInputError
    from gearlab.physics import stiffness

    shafts = "".join(f'[[shafts]]\nname = "{name}"\n' for name in ("motor", "layshaft", "drum"))
    (tmp_path / "n.toml").write_text(N_TRAIN + shafts)
    both = [
        {"name": "chip", "gear": "layshaft pinion", "tooth": 3, "step": 20},
        {"name": "chip", "gear": "drum gear", "tooth": 5, "step": 20},
    ]
    monkeypatch.setattr(stiffness, "MAX_HUNTING_TURNS", 10)  # 28/47: lcm 1316 meshes, 47 pinion turns
    with pytest.raises(GearlabInputError) as e:
        simulated_record(both, gearbox=str(tmp_path / "n.toml"), revolutions=2, fs=12_800, sim_fs=200_000, seed=1)
    said = str(e.value)
    assert "'chip@layshaft pinion' (tooth 3) and 'chip@drum gear' (tooth 5) on both gears of stage 2" in said
    assert "after 47 turns of the stage 2 pinion, the layshaft pinion" in said
    assert "s2-" not in said and "\n" not in said
