"""Dataset specs, presets, the builder and the content-addressed cache (thesis 2.4.3, 4.1,
5.4.1; docs/physics.md, datasets): Tables 4.1, 5.1 and 5.2, labels, noise at an SNR, TSA, determinism,
cache keys and crash safety, bad specs.

Every test builds into its own cache directory (GEARLAB_CACHE = tmp_path)."""

from __future__ import annotations

import dataclasses
import io
import json
import os
import warnings
import zipfile

import numpy as np
import pytest

import gearlab.data.builder as builder
import gearlab.files
from gearlab.data.builder import build_dataset
from gearlab.data.cache import ARRAYS, entry_path, load, load_or_build, save
from gearlab.data.spec import (
    CH5_STEPS,
    DATASET_PRESETS,
    FAULTS,
    POINTS,
    DatasetSpec,
    NoiseSpec,
    dataset_preset,
)
from gearlab.errors import GearlabInputError
from gearlab.executors import LocalExecutor
from gearlab.registry import get_registry
from gearlab.signals import NOISE_KINDS

REG = get_registry()


@pytest.fixture(autouse=True)
def cache(tmp_path, monkeypatch):
    path = tmp_path / "cache"
    monkeypatch.setenv("GEARLAB_CACHE", str(path))
    return path


def small(base: str = "B-6-ch5", **changes) -> DatasetSpec:
    """A few samples of a preset: two teeth, the broken-tooth crack, four healthy."""
    few = dict(teeth=(1, 2), faults=(("crack", (20,)),), healthy=4)
    return dataset_preset(base).with_(**{**few, **changes})


def z1(spec: DatasetSpec) -> int:
    pair, _ = REG.get("model", spec.model).resolve(spec.preset)
    return pair.Z1


def class_counts(spec: DatasetSpec) -> dict[str, int]:
    """Samples per class from the spec alone (nothing built)."""
    teeth = len(spec.teeth) if spec.teeth is not None else z1(spec)
    counts = {"healthy": spec.healthy}
    for name, steps in spec.faults:
        counts[name] = len(steps) * teeth * spec.duplicates
    return counts


def raw(ds) -> np.ndarray:
    """Undo the standardisation: the rows in m/s^2 (float64)."""
    mean, std = ds.reference
    return ds.X.astype(np.float64) * std + mean


def rms(x, axis=-1):
    return np.sqrt(np.mean(np.square(x), axis=axis))


# --- presets: Tables 5.1, 5.2 and 4.1 -------------------------------------------------------

CH5 = {
    "A-pinion-ch5": ("ten_dof", "pinion_x", 16, 240, 48, 432, 25.2, 7.0),
    "A-casing-ch5": ("ten_dof", "casing_x", 16, 240, 48, 432, 25.2, 7.0),
    "B-6-ch5": ("six_dof", "pinion_y", 25, 375, 75, 675, 40.0, 20.0),
    "B-8-ch5": ("eight_dof", "pinion_y", 25, 375, 75, 675, 40.0, 20.0),
}


@pytest.mark.parametrize("name", list(CH5))
def test_chapter5_presets_count_tables_5_1_and_5_2(name):
    model, channel, Z1, healthy, per_fault, total, speed, load = CH5[name]
    spec = dataset_preset(name)
    assert (spec.model, spec.channel, spec.speed_hz, spec.load_nm) == (model, channel, speed, load)
    assert z1(spec) == Z1 and spec.teeth is None and spec.duplicates == 1
    assert spec.noise is None and not spec.tsa and spec.revolutions == 1
    assert [f for f, _ in spec.faults] == list(FAULTS) == ["crack", "chip", "spall", "pit"]
    assert spec.class_names == ("healthy", "crack", "chip", "spall", "pit")
    # three intensities per fault: the top three, and three middle ones for cracks (5.4.1)
    steps = dict(spec.faults)
    assert steps == CH5_STEPS
    assert steps["chip"] == steps["spall"] == steps["pit"] == (18, 19, 20)
    assert len(steps["crack"]) == 3 and set(steps["crack"]) <= set(range(10, 14))
    counts = class_counts(spec)
    assert counts == {"healthy": healthy, **{f: per_fault for f in FAULTS}}
    assert sum(counts.values()) == total
    assert healthy > total / 2  # "slightly more than 50 % of the dataset consists of healthy examples"


def test_b6_ch5_built_matches_table_5_2_with_correct_labels():
    spec = dataset_preset("B-6-ch5")
    ds = build_dataset(spec)
    n = 675
    assert ds.X.shape == (n, POINTS) == (675, 4096) and ds.X.dtype == np.float32
    assert np.all(np.isfinite(ds.X))
    for name in ("label", "fault", "intensity", "tooth", "rfa", "revolution", "domain"):
        assert getattr(ds, name).shape == (n,), name
    assert np.bincount(ds.label).tolist() == [375, 75, 75, 75, 75]
    assert np.array_equal(ds.fault, (ds.label > 0).astype(ds.fault.dtype))
    healthy = ds.label == 0
    assert np.all(ds.intensity[healthy] == 0) and np.all(ds.tooth[healthy] == 0) and np.all(ds.rfa[healthy] == 0)
    pair, _ = REG.get("model", "six_dof").resolve("meng2020")
    for c, (fault_name, steps) in enumerate(spec.faults, start=1):
        rows = ds.label == c
        assert set(ds.intensity[rows].tolist()) == set(steps)
        fault = REG.get("fault", fault_name)
        for step in steps:
            at = rows & (ds.intensity == step)
            assert sorted(ds.tooth[at].tolist()) == list(range(1, 26))  # each tooth 1..Z1 once
            want = fault.rfa(fault.at_step(pair, step), pair)
            np.testing.assert_allclose(ds.rfa[at], want, rtol=1e-6)
    # RFA: a crack at step 13 removes a much larger area than a full chip (Figure 2.32)
    assert ds.rfa[ds.label == 1].max() > ds.rfa[ds.label == 2].max()
    assert np.all(ds.revolution == 0) and np.all(ds.domain == 0) and ds.domains == ("B-6-ch5",)
    assert ds.meta["Z1"] == 25 and ds.meta["speed_hz"] == 40.0 and ds.meta["load_nm"] == 20.0
    assert ds.meta["fs_hz"] == 200e3  # 5000 steps per revolution, 200 per tooth: already whole
    # standardised against the healthy reference (eq. 2.112): the healthy rows have mean 0, std 1
    h = ds.X[healthy].astype(np.float64)
    assert abs(h.mean()) < 1e-5 and h.std() == pytest.approx(1.0, abs=1e-5)
    assert np.array_equal(ds.X[healthy][0], ds.X[healthy][-1])  # noise-free: all the same revolution
    # faults change the signal; the broken tooth's RMS is many times the healthy one's
    assert rms(ds.X[ds.label == 4]).min() > 0.99 * rms(h).mean()
    assert ds.key == spec.key()


def test_chapter5_a_casing_reduced_build_labels():
    spec = dataset_preset("A-casing-ch5").with_(teeth=(1, 16), healthy=3)
    ds = build_dataset(spec)
    assert ds.X.shape == (3 + 4 * 3 * 2, 4096) and ds.X.dtype == np.float32
    assert set(ds.tooth[ds.label > 0].tolist()) == {1, 16}
    assert sorted(set(ds.intensity[ds.label == 1].tolist())) == list(CH5_STEPS["crack"])
    steps_per_tooth = ds.meta["fs_hz"] / (25.2 * 16)
    assert steps_per_tooth == pytest.approx(round(steps_per_tooth), abs=1e-9)  # whole steps per tooth
    assert 200e3 <= ds.meta["fs_hz"] < 200e3 + 25.2 * 16


@pytest.mark.parametrize("kind", NOISE_KINDS)
@pytest.mark.parametrize("tsa", [False, True])
def test_chapter4_presets_count_table_4_1(kind, tsa):
    name = f"A-casing_{'TSA' if tsa else 'noise'}-{kind}"
    spec = dataset_preset(name)
    assert spec.name == spec.domain == name
    assert (spec.model, spec.channel, spec.speed_hz, spec.load_nm) == ("ten_dof", "casing_x", 25.2, 7.0)
    assert spec.revolutions == 60  # J = 60 (a 4 s simulation)
    assert spec.tsa is tsa
    assert spec.noise == NoiseSpec(kind, 0.0, spec.noise.seed)  # SNR 1 = 0 dB
    assert spec.duplicates == 5 and spec.teeth is None
    assert all(steps == tuple(range(1, 21)) for _, steps in spec.faults)
    counts = class_counts(spec)
    assert counts == {"healthy": 6400, "crack": 1600, "chip": 1600, "spall": 1600, "pit": 1600}
    assert sum(counts.values()) == 12800
    spec.check()


def test_chapter2_presets():
    for name, model, channel in (
        ("A-pinion", "ten_dof", "pinion_x"),
        ("A-casing", "ten_dof", "casing_x"),
        ("B-6", "six_dof", "pinion_y"),
        ("B-8", "eight_dof", "pinion_y"),
    ):
        spec = dataset_preset(name)
        assert (spec.model, spec.channel) == (model, channel)
        assert all(steps == tuple(range(1, 21)) for _, steps in spec.faults)
        c = class_counts(spec)
        assert c["crack"] == 20 * z1(spec) and c["healthy"] == 4 * c["crack"]
    assert set(DATASET_PRESETS) >= set(CH5) | {f"A-casing_noise-{k}" for k in NOISE_KINDS}


# --- noise and TSA (eq. 4.1-4.7) -----------------------------------------------------------


@pytest.mark.parametrize("kind", NOISE_KINDS)
@pytest.mark.parametrize("snr_db", [0.0, 6.0])
def test_noise_rms_matches_the_requested_snr(kind, snr_db):
    clean = build_dataset(small())
    noisy = build_dataset(small(noise=NoiseSpec(kind, snr_db, 3)))
    assert noisy.reference != clean.reference  # the noisy domain's own (noisy) healthy reference
    s, x = raw(clean), raw(noisy)
    ratio = rms(x - s) / rms(s)
    np.testing.assert_allclose(ratio, 10 ** (-snr_db / 20), rtol=1e-6)
    # and the noise is really there: no two healthy rows are alike any more
    h = noisy.X[noisy.label == 0]
    assert not np.array_equal(h[0], h[1])


def test_tsa_raises_the_snr_about_as_sqrt_j():
    J = 16
    spec = small(noise=NoiseSpec("gaussian", 0.0, 0), revolutions=J)
    clean = raw(build_dataset(small()))
    first = build_dataset(spec)  # the first of J noisy revolutions
    averaged = build_dataset(spec.with_(tsa=True))
    assert np.all(first.revolution == 0) and np.all(averaged.revolution == -1)
    residual_first = rms(raw(first) - clean)
    residual_tsa = rms(raw(averaged) - clean)
    ratio = residual_tsa / residual_first
    assert np.all(np.abs(ratio - 1 / np.sqrt(J)) < 0.2 / np.sqrt(J)), ratio
    assert np.mean(ratio) == pytest.approx(0.25, rel=0.05)
    # in dB: about 10 log10(J) = 12 dB better
    gain = 20 * np.log10(residual_first / residual_tsa)
    assert np.all(np.abs(gain - 10 * np.log10(J)) < 2.0), gain


def test_noise_does_not_depend_on_the_number_of_revolutions_when_not_averaging():
    """The noisy set keeps the first of J revolutions: J does not change it."""
    a = build_dataset(small(noise=NoiseSpec("laplace", 0.0, 1), revolutions=1))
    b = build_dataset(small(noise=NoiseSpec("laplace", 0.0, 1), revolutions=60))
    assert np.array_equal(a.X, b.X)


# --- determinism ---------------------------------------------------------------------------


def test_builds_are_deterministic_across_runs_workers_and_chunks(monkeypatch):
    spec = small(
        teeth=(1, 2, 3),
        faults=(("crack", (20,)), ("spall", (20,))),
        healthy=5,
        noise=NoiseSpec("student_t", 0.0, 7),
        revolutions=4,
        tsa=True,
    )
    one = build_dataset(spec, LocalExecutor(1))
    again = build_dataset(spec, LocalExecutor(1))
    monkeypatch.setattr(builder, "CHUNK", 3)  # several noise tasks, spread over two processes
    two = build_dataset(spec, LocalExecutor(2))
    for ds in (again, two):
        for name in ARRAYS:
            assert np.array_equal(getattr(ds, name), getattr(one, name)), name
        assert ds.reference == one.reference
    other_seed = build_dataset(spec.with_(seed=1), LocalExecutor(1))
    assert not np.array_equal(other_seed.X, one.X)


def test_datasets_that_differ_in_signal_effects_alone_share_their_simulations(monkeypatch):
    """A corrected source (signal-level effects added) after its plain source simulates nothing new,
    and is the dataset it would be simulated afresh; an excitation-level effect simulates again."""
    spec = small(healthy=3)
    signal = spec.with_(effects=(("sensor_offset", (("offset", 2.0),)), ("sensor_noise", (("snr_db", 20.0),))))
    excitation = spec.with_(effects=(("load_level", (("factor", 1.1),)),))
    simulated = []
    simulate_unit = builder.simulate_unit
    monkeypatch.setattr(builder, "simulate_unit", lambda task: simulated.append(task) or simulate_unit(task))
    monkeypatch.setattr(builder, "_SIMULATED", builder.OrderedDict())
    build_dataset(spec, LocalExecutor(1))
    first = len(simulated)
    shared = build_dataset(signal, LocalExecutor(1))
    assert first > 0 and len(simulated) == first  # nothing simulated for the signal effects
    builder._SIMULATED.clear()
    afresh = build_dataset(signal, LocalExecutor(1))
    assert len(simulated) == 2 * first and np.array_equal(shared.X, afresh.X)
    build_dataset(excitation, LocalExecutor(1))
    assert len(simulated) == 3 * first
    newest = next(reversed(builder._SIMULATED.values()))
    monkeypatch.setattr(builder, "KEEP_SIMULATED", 2 * newest.nbytes)  # what a process keeps is bounded
    build_dataset(spec.with_(seed=5, load_nm=1.5 * builder.operating_point(spec)[1]), LocalExecutor(1))
    assert sum(r.nbytes for r in builder._SIMULATED.values()) <= 2 * newest.nbytes


# --- cache -------------------------------------------------------------------------------


def assert_same(a, b):
    for name in ARRAYS:
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and np.array_equal(x, y), name
    assert tuple(a.reference) == tuple(b.reference)
    assert tuple(a.domains) == tuple(b.domains)
    assert a.meta == b.meta


def test_load_or_build_twice_is_cached_and_identical(cache):
    spec = small(noise=NoiseSpec("laplace", 0.0, 1))
    first, cached = load_or_build(spec, LocalExecutor(1))
    assert cached is False
    assert [p.name for p in cache.iterdir()] == [f"{spec.key()}.npz"]
    second, cached = load_or_build(spec, LocalExecutor(1))
    assert cached is True
    assert_same(first, second)
    assert second.spec == spec


def test_cache_entry_is_a_plain_npz_without_pickle(cache):
    spec = small()
    load_or_build(spec, LocalExecutor(1))
    path = entry_path(spec)
    assert path.parent == cache
    with np.load(path, allow_pickle=False) as data:
        assert set(data.files) == set(ARRAYS) | {"meta"}
        for name in data.files:
            assert data[name].dtype != object, name
        meta = json.loads(str(data["meta"]))
    assert meta["key"] == spec.key()
    assert meta["spec"]["model"] == "six_dof"


VARIATIONS = {
    "effects": (("sensor_noise", (("kind", "gaussian"), ("snr_db", 10.0))),),
    "model": "eight_dof",
    "preset": "other",
    "channel": "pinion_x",
    "speed_hz": 41.0,
    "load_nm": 10.0,
    "faults": (("crack", (19,)),),
    "teeth": (1, 3),
    "duplicates": 2,
    "healthy": 5,
    "revolutions": 2,
    "noise": NoiseSpec("gaussian", 0.0, 0),
    "tsa": True,
    "seed": 1,
    "fs": 250e3,
    "healthy_twin": True,
    "unit_shaft": (1, 3),
}


def test_cache_key_changes_with_every_field_but_name_and_domain(monkeypatch):
    spec = small()
    fields = {f.name for f in dataclasses.fields(DatasetSpec)}
    assert fields == set(VARIATIONS) | {"name", "domain"}, "a new spec field: add it to VARIATIONS"
    keys = {spec.key()}
    for name, value in VARIATIONS.items():
        changed = spec.with_(**{name: value})
        assert changed.key() != spec.key(), name
        keys.add(changed.key())
    assert len(keys) == len(VARIATIONS) + 1
    assert spec.with_(name="renamed", domain="elsewhere").key() == spec.key()
    # noise fields, one by one
    noisy = spec.with_(noise=NoiseSpec("gaussian", 0.0, 0))
    for change in (NoiseSpec("laplace", 0.0, 0), NoiseSpec("gaussian", 3.0, 0), NoiseSpec("gaussian", 0.0, 1)):
        assert noisy.with_(noise=change).key() != noisy.key()
    # equal specs built separately have equal keys; the physics version is part of the key
    assert small().key() == spec.key()
    monkeypatch.setattr("gearlab.data.spec.PHYSICS_VERSION", "changed")
    assert spec.key() not in keys


def test_renamed_spec_is_served_from_the_cache():
    spec = small()
    load_or_build(spec, LocalExecutor(1))
    _, cached = load_or_build(spec.with_(name="same data", domain="same data"), LocalExecutor(1))
    assert cached is True


def test_truncated_entry_is_detected_removed_and_rebuilt(cache):
    spec = small()
    built, _ = load_or_build(spec, LocalExecutor(1))
    path = entry_path(spec)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.warns(UserWarning, match=rf"{path.name} is unreadable.*rebuilding"):
        again, cached = load_or_build(spec, LocalExecutor(1))
    assert cached is False
    assert_same(built, again)
    assert path.read_bytes() == data  # rebuilt and stored again, byte for byte
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert load_or_build(spec, LocalExecutor(1))[1] is True


def test_entry_of_another_spec_under_this_key_is_rebuilt(cache):
    spec, other = small(), small(seed=5, noise=NoiseSpec("gaussian", 0.0, 0))
    save(build_dataset(other))
    os.replace(entry_path(other), entry_path(spec))
    with pytest.warns(UserWarning, match="key mismatch"):
        assert load(spec) is None
    assert not entry_path(spec).exists()


def test_garbage_entry_is_rebuilt(cache):
    spec = small()
    cache.mkdir(parents=True, exist_ok=True)
    entry_path(spec).write_bytes(b"not a zip file")
    with pytest.warns(UserWarning, match="unreadable"):
        _, cached = load_or_build(spec, LocalExecutor(1))
    assert cached is False
    with np.load(entry_path(spec), allow_pickle=False) as data:
        assert data["X"].shape == (6, 4096)


def test_build_killed_midway_leaves_no_entry(cache, monkeypatch):
    spec = small()
    calls = []

    def killed(task):
        calls.append(1)
        raise KeyboardInterrupt  # a kill while the samples are made

    monkeypatch.setattr(builder, "noisy_rows", killed)
    with pytest.raises(KeyboardInterrupt):
        load_or_build(spec, LocalExecutor(1))
    assert calls
    assert not list(cache.glob("*.npz")) and not list(cache.glob(".*"))
    monkeypatch.undo()
    monkeypatch.setenv("GEARLAB_CACHE", str(cache))
    _, cached = load_or_build(spec, LocalExecutor(1))
    assert cached is False


class _OsKilledAt:
    """The os module, but one call raises as if the process were killed there."""

    def __init__(self, name):
        self.name = name

    def __getattr__(self, attr):
        if attr == self.name:

            def killed(*args, **kwargs):
                raise KeyboardInterrupt

            return killed
        return getattr(os, attr)


@pytest.mark.parametrize("where", ["fsync", "replace"])
def test_write_killed_midway_leaves_no_entry_and_no_partial_file(cache, monkeypatch, where):
    spec = small()
    monkeypatch.setattr(gearlab.files, "os", _OsKilledAt(where))
    with pytest.raises(KeyboardInterrupt):
        load_or_build(spec, LocalExecutor(1))
    assert list(cache.iterdir()) == []  # neither the entry nor its temporary file
    monkeypatch.setattr(gearlab.files, "os", os)
    assert load(spec) is None
    assert load_or_build(spec, LocalExecutor(1))[1] is False


def test_leftover_temporary_file_is_never_picked_up(cache):
    """What a hard kill (no cleanup) leaves behind: a partial temporary file next to the entry."""
    spec = small()
    cache.mkdir(parents=True, exist_ok=True)
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        z.writestr("X.npy", b"partial")
    leftover = cache / f".{spec.key()}.npz.abc123.tmp"
    leftover.write_bytes(buf.getvalue()[:40])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert load(spec) is None
        ds, cached = load_or_build(spec, LocalExecutor(1))
    assert cached is False and ds.X.shape == (6, 4096)
    assert entry_path(spec).exists()


# --- bad specs ------------------------------------------------------------------------------


def test_unknown_dataset_preset_suggests_the_close_one():
    with pytest.raises(GearlabInputError, match=r"unknown dataset preset 'B-6-ch4'.*did you mean 'B-6-ch5'"):
        dataset_preset("B-6-ch4")
    with pytest.raises(GearlabInputError, match=r"^here: unknown dataset preset"):
        dataset_preset("nope", where="here")


@pytest.mark.parametrize(
    "changes,pattern",
    [
        (dict(faults=(("crak", (20,)),)), r"unknown fault 'crak'.*did you mean 'crack'"),
        (dict(faults=(("crack", (0,)),)), r"fault 'crack' step 0 is outside 1\.\.20"),
        (dict(faults=(("crack", (21,)),)), r"fault 'crack' step 21 is outside 1\.\.20"),
        (dict(faults=(("crack", (2.5,)),)), r"step 2\.5 is outside"),
        (dict(teeth=(1, 26)), r"tooth 26 is outside 1\.\.25"),
        (dict(teeth=(0,)), r"tooth 0 is outside 1\.\.25"),
        (dict(healthy=-1), r"'healthy' must be a whole number >= 0, got -1"),
        (dict(duplicates=0), r"'duplicates' must be a whole number >= 1"),
        (dict(revolutions=0), r"'revolutions' must be a whole number >= 1"),
        (dict(tsa=True, revolutions=1), r"TSA needs revolutions >= 2"),
        (dict(noise=NoiseSpec("gauss", 0.0)), r"unknown noise kind 'gauss'.*did you mean 'gaussian'"),
        (dict(channel="casing_x"), r"model 'six_dof' has no channel 'casing_x'; its channels: pinion_x, pinion_y"),
        (dict(model="six_dfo"), r"unknown model 'six_dfo'.*did you mean 'six_dof'"),
        (dict(preset="meng2021"), r"unknown preset 'meng2021'.*did you mean 'meng2020'"),
        (dict(faults=(), healthy=0), r"no samples"),
    ],
)
def test_bad_specs_are_refused_before_building(changes, pattern, cache):
    spec = small(**changes)
    with pytest.raises(GearlabInputError, match=pattern) as info:
        build_dataset(spec)
    assert "\n" not in str(info.value)
    assert f"dataset '{spec.name}'" in str(info.value)
    assert not list(cache.glob("*.npz"))


def test_a_dataset_beyond_memory_is_refused_before_any_work(cli, tmp_path):
    path = tmp_path / "huge.toml"
    path.write_text(
        '[scenario]\nname = "huge"\nkind = "dataset"\n\n[[datasets]]\npreset = "B-6"\nhealthy = 1000000000000\n'
    )
    code, _, err = cli("run", path, "--out", tmp_path / "runs")
    assert code == 2 and "[[datasets]] #1: dataset 'B-6' would hold" in err and "at most 1000000" in err
    assert not (tmp_path / "runs").exists()
