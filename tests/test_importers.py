"""Import of measured vibration (gearlab.data.importers; docs/real_data.md).

A synthetic "measured" record with a known analytic waveform is written in every supported
format; importing it must give the revolutions computed directly from the waveform, the
labels, and a standardisation against the healthy revolutions. Every bad file must give
one GearlabInputError line with the key fact in it, truncated files included.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, replace
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.io
import scipy.io.wavfile

from gearlab.data import cache
from gearlab.data.importers import MeasuredSpec, import_measured, read_channels
from gearlab.errors import GearlabInputError

TWO_PI = 2 * np.pi
FS = 50_000.0  # Hz
SPEED = 25.0  # Hz, input shaft: 2000 samples per revolution
TURNS = 20
N = int(FS / SPEED * TURNS)  # 40 000 samples
PHI0 = 0.3  # shaft angle at the first sample (rad): revolutions start at θ = 2π, 4π, …
K_FAULT = 10  # the revolutions from θ = 2π·K_FAULT on carry the fault burst
NOISE = 1e-3  # standard deviation of the added noise
P = 4096
COMPLETE = 19  # complete revolutions: θ runs from 0.3 to 0.3 + 2π·19.9995, so k = 1 … 19
HEALTHY = K_FAULT - 1  # revolutions k = 1 … 9 healthy, 10 … 19 faulty
LABELS = np.array([0] * HEALTHY + [1] * (COMPLETE - HEALTHY))


# --- the synthetic record ------------------------------------------------------------------


def wrap(theta):
    return (theta + np.pi) % TWO_PI - np.pi


def clean(theta):
    """Noise-free vibration at shaft angle θ: shaft orders 1, 2, a 16-tooth mesh order, and in
    the fault half a burst once per revolution (narrow Gaussian at mid-revolution, order 40)."""
    s = np.cos(theta) + 0.5 * np.cos(2 * theta + 0.4) + 0.3 * np.cos(16 * theta + 1.0)
    local = np.mod(theta, TWO_PI)
    burst = 0.8 * np.exp(-0.5 * ((local - np.pi) / 0.05) ** 2) * np.sin(40 * theta)
    return s + burst * (theta >= TWO_PI * K_FAULT)


def pulse_train(theta, volts=5.0, edge_samples=8):
    """Once-per-revolution pulse, high for half a turn, with linear edges whose mid-level
    crossings fall exactly at θ = 2πk (rising) and π + 2πk (falling)."""
    width = edge_samples * TWO_PI * SPEED / FS  # edge duration as an angle
    c = wrap(theta - np.pi / 2)  # angle from the nearest pulse centre
    return volts * np.clip(0.5 + (np.pi / 2 - np.abs(c)) / width, 0.0, 1.0)


@dataclass
class Record:
    t: np.ndarray
    theta: np.ndarray
    acc: np.ndarray
    tacho: np.ndarray
    pulses: np.ndarray
    label: np.ndarray  # class names per sample
    index: np.ndarray  # class indices per sample


def make_record(n=N, transient=0.0, seed=0):
    theta = PHI0 + TWO_PI * SPEED * np.arange(n) / FS
    t = np.arange(n) / FS
    acc = clean(theta) * (1 + transient * np.exp(-t / 0.04)) + NOISE * np.random.default_rng(seed).standard_normal(n)
    index = (theta >= TWO_PI * K_FAULT).astype(np.int64)
    return Record(t, theta, acc, wrap(theta), pulse_train(theta), np.where(index, "fault", "healthy"), index)


def standardised(E, healthy):
    ref = E[healthy]
    return (E - ref.mean()) / ref.std()


def expected_rows(labelled=True):
    """The 19 revolutions computed directly from the waveform, standardised like the importer."""
    theta = TWO_PI * (1 + np.arange(COMPLETE)[:, None] + np.arange(P) / P)
    return standardised(clean(theta), LABELS == 0 if labelled else slice(None))


# --- writers, one per format ------------------------------------------------------------


def write_csv(path, columns, comments=(), formats=None):
    formats = formats or {}
    cols = [np.char.mod(formats.get(k, "%.17g"), v) if v.dtype.kind != "U" else v for k, v in columns.items()]
    lines = [f"# {c}" for c in comments] + [",".join(columns)] + [",".join(row) for row in zip(*cols)]
    path.write_text("\n".join(lines) + "\n")
    return path


def write_npz(path, arrays):
    np.savez(path, **arrays)
    return path


def write_mat73(path, variables):
    """A MATLAB v7.3 MAT-file: HDF5 behind a 512-byte user block holding MATLAB's header;
    variables stored transposed, text as uint16 character codes."""
    with h5py.File(path, "w", userblock_size=512) as f:
        for name, value in variables.items():
            if isinstance(value, str):
                ds = f.create_dataset(name, data=np.array([[ord(c)] for c in value], dtype=np.uint16))
                ds.attrs["MATLAB_class"] = np.bytes_("char")
                ds.attrs["MATLAB_int_decode"] = np.int32(2)
            else:
                ds = f.create_dataset(name, data=np.atleast_2d(np.asarray(value, dtype=np.float64)).T)
                ds.attrs["MATLAB_class"] = np.bytes_("double")
    header = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan  1 00:00:00 2024 HDF5 schema 1.00 ."
    header = header.ljust(116) + b"\x00" * 8 + b"\x00\x02" + b"IM"
    with open(path, "r+b") as f:
        f.write(header)
    return path


def write_formats(directory: Path, rec: Record) -> dict[str, tuple[Path, dict, float]]:
    """Every format: (file, MeasuredSpec options, tolerance on the standardised revolutions)."""
    d = directory
    out = {}
    out["csv"] = (
        write_csv(d / "rec.csv", {"t": rec.t, "acc": rec.acc, "tacho": rec.tacho, "label": rec.label}),
        dict(vibration="acc", tacho="tacho", labels="label"),
        1e-2,
    )
    out["npz"] = (
        write_npz(d / "rec.npz", {"acc": rec.acc, "tacho": rec.tacho, "label": rec.label, "fs": FS}),
        dict(vibration="acc", tacho="tacho", labels="label"),
        1e-2,
    )
    with h5py.File(d / "rec.h5", "w") as f:  # nested, rate as an attribute of the group
        g = f.create_group("rig")
        g.attrs["fs"] = FS
        g["acc"], g["tacho"] = rec.acc, rec.tacho
        g.create_dataset("label", data=rec.label.astype(object), dtype=h5py.string_dtype())
    out["h5"] = (d / "rec.h5", dict(vibration="rig/acc", tacho="rig/tacho", labels="rig/label"), 1e-2)
    scipy.io.wavfile.write(d / "rec32.wav", int(FS), np.stack([rec.acc, rec.tacho], 1).astype(np.float32))
    out["wav-float32"] = (d / "rec32.wav", dict(vibration="0", tacho="1"), 1e-2)
    full = 0.9 * 32767
    pcm = np.stack([rec.acc / np.abs(rec.acc).max(), rec.pulses / 5.0], 1) * full
    scipy.io.wavfile.write(d / "rec16.wav", int(FS), np.round(pcm).astype(np.int16))
    out["wav-int16"] = (d / "rec16.wav", dict(vibration="0", tacho="1"), 1.5e-2)  # 16-bit quantisation
    # MATLAB variables are rows (1×N); 'fs' last so that any truncation loses something needed.
    scipy.io.savemat(
        d / "rec5.mat", {"acc": rec.acc[None], "tacho": rec.tacho[None], "label": rec.index[None], "Fs": FS}
    )
    out["mat5"] = (d / "rec5.mat", dict(vibration="acc", tacho="tacho", labels="label"), 1e-2)
    write_mat73(d / "rec73.mat", {"acc": rec.acc, "tacho": rec.tacho, "label": rec.index, "fs": FS})
    out["mat73"] = (d / "rec73.mat", dict(vibration="acc", tacho="tacho", labels="label"), 1e-2)
    return out


@pytest.fixture(scope="module")
def rec():
    return make_record()


@pytest.fixture(scope="module")
def files(tmp_path_factory, rec):
    return write_formats(tmp_path_factory.mktemp("measured"), rec)


def spec_for(path, **options):
    return MeasuredSpec(name="rig", path=str(path), **options)


def fails(spec, *facts):
    """The import raises one GearlabInputError line containing every fact; returns it."""
    with pytest.raises(GearlabInputError) as info:
        import_measured(spec)
    message = str(info.value)
    assert "\n" not in message
    for fact in facts:
        assert fact in message, message
    return message


# --- round trips -----------------------------------------------------------------------


FORMATS = ["csv", "npz", "h5", "wav-float32", "wav-int16", "mat5", "mat73"]


@pytest.mark.parametrize("fmt", FORMATS)
def test_round_trip_gives_the_directly_computed_revolutions(files, fmt):
    path, options, tol = files[fmt]
    ds = import_measured(spec_for(path, **options))
    labelled = "labels" in options
    assert ds.X.shape == (COMPLETE, P) and ds.X.dtype == np.float32
    assert np.abs(ds.X - expected_rows(labelled)).max() < tol
    assert list(ds.revolution) == list(range(COMPLETE))
    if labelled:
        assert list(ds.label) == list(LABELS) and list(ds.fault) == list(LABELS)
        assert ds.meta["reference"] == "labelled healthy"
    else:
        assert set(ds.label) == {-1} and set(ds.fault) == {-1}
        assert ds.meta["reference"] == "all revolutions (unlabelled)"
    ref = ds.X[ds.label <= 0].astype(np.float64)  # healthy, or all when unlabelled
    assert abs(ref.mean()) < 1e-5 and abs(ref.std() - 1) < 1e-5
    assert ds.meta["fs_hz"] == pytest.approx(FS, rel=1e-12) and ds.meta["speed_hz"] == pytest.approx(SPEED, rel=1e-6)
    assert ds.meta["transient_revolutions"] == 0 and ds.meta["complete_revolutions"] == COMPLETE
    assert ds.domains == ("rig",) and set(ds.domain) == {0}
    assert set(ds.intensity) == {0} and set(ds.tooth) == {0} and np.isnan(ds.rfa).all()
    assert ds.spec.path == str(path)


@pytest.mark.parametrize("fmt", FORMATS)
def test_read_channels_gives_arrays_and_the_files_rate(files, rec, fmt):
    path, options, _ = files[fmt]
    channels, fs = read_channels(path, [options["vibration"]])
    assert fs == pytest.approx(FS, rel=1e-9)
    acc = channels[options["vibration"]]
    assert acc.shape == (N,)
    if fmt != "wav-int16":  # the 16-bit file holds the normalised signal
        assert np.allclose(acc, rec.acc, atol=1e-6)


def test_tacho_kind_is_detected(files, rec, tmp_path):
    wrapped_0_2pi = np.mod(rec.theta, TWO_PI)  # an encoder's [0, 2π)
    path = write_npz(
        tmp_path / "r.npz",
        {"acc": rec.acc, "pulses": rec.pulses, "angle": wrapped_0_2pi, "continuous": rec.theta, "fs": FS},
    )
    reference = import_measured(spec_for(files["npz"][0], vibration="acc", tacho="tacho")).X
    for tacho, kind in (("pulses", "pulses"), ("angle", "angle"), ("continuous", "angle")):
        ds = import_measured(spec_for(path, vibration="acc", tacho=tacho))
        assert ("pulses" in ds.meta["angle_source"]) == (kind == "pulses"), ds.meta["angle_source"]
        assert ds.X.shape == (COMPLETE, P)
        assert np.abs(ds.X - reference).max() < 1e-3  # the same revolutions whatever the tacho
    forced = import_measured(spec_for(path, vibration="acc", tacho="pulses", tacho_kind="pulses"))
    assert np.array_equal(forced.X, import_measured(spec_for(path, vibration="acc", tacho="pulses")).X)


def test_nominal_speed_without_tacho(rec, tmp_path):
    path = write_npz(tmp_path / "r.npz", {"acc": rec.acc, "fs": FS})
    ds = import_measured(spec_for(path, vibration="acc", speed_hz=SPEED))
    # The angle is zero at the first sample: revolution r spans θ = 0.3 + 2π(r + p/P).
    theta = PHI0 + TWO_PI * (np.arange(COMPLETE)[:, None] + np.arange(P) / P)
    assert ds.X.shape == (COMPLETE, P)
    assert np.abs(ds.X - standardised(clean(theta), slice(None))).max() < 1e-2
    assert "nominal speed" in ds.meta["angle_source"] and ds.meta["speed_hz"] == pytest.approx(SPEED)


def test_whole_record_label_and_the_given_rate(rec, tmp_path):
    path = write_npz(tmp_path / "r.npz", {"acc": rec.acc, "tacho": rec.tacho, "cond": np.array("crack")})
    ds = import_measured(
        spec_for(path, vibration="acc", tacho="tacho", labels="cond", fs=FS, class_names=("crack", "healthy"))
    )  # class 0 is the reference
    assert set(ds.label) == {0} and set(ds.fault) == {0} and ds.meta["fs_source"] == "given"
    mat = tmp_path / "r.mat"
    write_mat73(mat, {"acc": rec.acc, "tacho": rec.tacho, "cond": "healthy", "Fs": FS})
    ds = import_measured(spec_for(mat, vibration="acc", tacho="tacho", labels="cond"))
    assert set(ds.label) == {0} and len(ds) == COMPLETE


def test_start_up_transient_is_dropped(tmp_path):
    rec = make_record(transient=1.0)  # amplitude doubled at the start, settling within ~4 revolutions
    path = write_npz(tmp_path / "r.npz", {"acc": rec.acc, "tacho": rec.tacho, "label": rec.label, "fs": FS})
    ds = import_measured(spec_for(path, vibration="acc", tacho="tacho", labels="label"))
    dropped = ds.meta["transient_revolutions"]
    assert 2 <= dropped <= 6 and len(ds) == COMPLETE - dropped
    assert list(ds.revolution) == list(range(dropped, COMPLETE))
    assert list(ds.label) == list(LABELS[dropped:])  # the fault half is not taken for a transient
    kept = import_measured(spec_for(path, vibration="acc", tacho="tacho", labels="label", transient="none"))
    assert len(kept) == COMPLETE and kept.meta["transient_revolutions"] == 0


def test_csv_rates_from_rounded_times_and_from_a_comment(rec, tmp_path):
    # Times written to the microsecond (as spreadsheets do): 0.02 s steps rounded.
    cols = {"time": rec.t, "acc": rec.acc, "tacho": rec.tacho}
    path = write_csv(tmp_path / "r.csv", cols, formats={"time": "%.6f"})
    ds = import_measured(spec_for(path, vibration="acc", tacho="tacho"))
    assert ds.meta["fs_hz"] == pytest.approx(FS, rel=1e-5)
    assert import_measured(spec_for(path, vibration="acc", tacho="tacho", fs=FS)).meta["fs_hz"] == FS
    path = write_csv(tmp_path / "c.csv", {"acc": rec.acc, "tacho": rec.tacho}, comments=["rig 3, run 7", "fs = 50000"])
    ds = import_measured(spec_for(path, vibration="acc", tacho="tacho"))
    assert ds.meta["fs_hz"] == FS and len(ds) == COMPLETE


def test_key_follows_file_bytes_and_options_not_name(files, tmp_path):
    path, options, _ = files["npz"]
    spec = spec_for(path, **options)
    assert len(spec.key()) == 24 and spec.key() == replace(spec, name="other").key()
    assert spec.key() != replace(spec, points=2048).key()
    copy = tmp_path / "copy.npz"
    copy.write_bytes(path.read_bytes())
    assert replace(spec, path=str(copy)).key() == spec.key()
    data = path.read_bytes()
    copy.write_bytes(data[:-1] + bytes([data[-1] ^ 1]))
    assert replace(spec, path=str(copy)).key() != spec.key()


def test_imported_dataset_goes_through_the_cache(files, tmp_path, monkeypatch):
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    path, options, _ = files["csv"]
    spec = spec_for(path, **options)
    ds = import_measured(spec)
    cache.save(ds)
    back = cache.load(spec)
    assert back is not None and np.array_equal(back.X, ds.X) and np.array_equal(back.label, ds.label)
    assert back.meta == json.loads(json.dumps(ds.meta))


# --- bad files -------------------------------------------------------------------------


def test_file_missing_and_unknown_extension(tmp_path):
    fails(spec_for(tmp_path / "nothing.csv", vibration="acc", speed_hz=25), "nothing.csv", "no such file")
    (tmp_path / "r.xls").write_text("acc\n1\n")
    fails(
        spec_for(tmp_path / "r.xls", vibration="acc", speed_hz=25), "unknown file type '.xls'", ".csv", ".zip", ".mat"
    )


@pytest.mark.parametrize(
    "suffix,fmt", [(".npz", "NPZ"), (".h5", "HDF5"), (".wav", "WAV"), (".mat", "MATLAB"), (".csv", "CSV")]
)
def test_corrupt_file(tmp_path, suffix, fmt):
    path = tmp_path / f"bad{suffix}"
    path.write_bytes(b"\xff\xfe garbage \x00\x81" * 40)
    fails(spec_for(path, vibration="acc", speed_hz=25), f"cannot read {path} as {fmt}:")


def test_missing_channel_lists_what_exists(files):
    path, _, _ = files["npz"]
    fails(
        spec_for(path, vibration="acc1", speed_hz=25),
        "no vibration channel 'acc1'",
        "(did you mean 'acc'?)",
        "the file has channels: acc, tacho, label (and the sampling rate 'fs')",
    )
    fails(
        spec_for(files["h5"][0], vibration="rig/acc", tacho="rig/tach"),
        "no tacho channel 'rig/tach'",
        "did you mean 'rig/tacho'",
    )
    wav = spec_for(files["wav-int16"][0], vibration="2", speed_hz=25)
    fails(wav, "no vibration channel '2'", "the file has channels: 0, 1")


def test_non_numeric_channels(rec, tmp_path, files):
    fails(
        spec_for(files["csv"][0], vibration="label", speed_hz=25),
        "vibration channel 'label' is not numeric: 'healthy' at sample 0",
    )
    acc = np.char.mod("%.9g", rec.acc)
    acc[5] = ""
    path = write_csv(tmp_path / "e.csv", {"t": rec.t, "acc": acc})
    fails(
        spec_for(path, vibration="acc", speed_hz=25),
        "vibration channel 'acc' is not numeric: an empty field at sample 5",
    )
    path = write_npz(tmp_path / "two.npz", {"acc": np.stack([rec.acc, rec.acc], 1), "fs": FS})
    fails(spec_for(path, vibration="acc", speed_hz=25), "vibration channel 'acc' has shape (40000, 2)")


def test_nan_and_inf_are_located(rec, tmp_path):
    acc, tacho = rec.acc.copy(), rec.tacho.copy()
    acc[1234] = np.nan
    tacho[77] = np.inf
    path = write_npz(tmp_path / "r.npz", {"acc": acc, "tacho": rec.tacho, "fs": FS})
    fails(
        spec_for(path, vibration="acc", tacho="tacho"), "r.npz", "vibration channel 'acc' contains NaN at sample 1234"
    )
    path = write_npz(tmp_path / "s.npz", {"acc": rec.acc, "tacho": tacho, "fs": FS})
    fails(spec_for(path, vibration="acc", tacho="tacho"), "tacho channel 'tacho' contains inf at sample 77")


def test_channels_of_different_lengths(rec, tmp_path):
    path = write_npz(tmp_path / "r.npz", {"acc": rec.acc, "tacho": rec.tacho[:-10], "label": rec.label[:5], "fs": FS})
    fails(
        spec_for(path, vibration="acc", tacho="tacho"),
        "tacho channel 'tacho' has 39990 samples but vibration channel 'acc' has 40000",
    )
    fails(spec_for(path, vibration="acc", speed_hz=25, labels="label"), "labels channel 'label' has 5 samples")


def test_sampling_rate_errors(rec, tmp_path, files):
    path = write_npz(tmp_path / "none.npz", {"acc": rec.acc})
    fails(
        spec_for(path, vibration="acc", speed_hz=25),
        "no sampling rate: the file has no 'fs'/time and none was given (--fs / fs = ...)",
    )
    fails(
        spec_for(files["wav-float32"][0], vibration="0", tacho="1", fs=48000.0),
        "fs = 48000 Hz, disagrees with the WAV header",
        "50000 Hz",
    )
    path = write_npz(tmp_path / "neg.npz", {"acc": rec.acc, "fs": -5.0})
    fails(spec_for(path, vibration="acc", speed_hz=25), "sampling rate 'fs' must be positive, got -5 Hz")
    fails(spec_for(files["npz"][0], vibration="acc", speed_hz=25, fs=0.0), "sampling rate fs must be positive")
    for bad, shown in (("50k", "'50k'"), (np.array([1.0, 2.0]), "2 values")):
        path = write_npz(tmp_path / "field.npz", {"acc": rec.acc, "fs": bad})
        fails(spec_for(path, vibration="acc", speed_hz=25), "sampling rate field 'fs' must be one number in Hz", shown)
    path = write_npz(tmp_path / "two.npz", {"acc": rec.acc, "fs": FS, "t": np.arange(N) / 48000.0})
    fails(spec_for(path, vibration="acc", speed_hz=25), "sampling rates in the file disagree", "48 kHz")
    gap = np.delete(np.arange(N + 1) / FS, 20_000)  # one sample missing
    path = write_csv(tmp_path / "gap.csv", {"t": gap, "acc": rec.acc})
    fails(
        spec_for(path, vibration="acc", speed_hz=25),
        "time 't' is not uniformly sampled",
        "between samples 19999 and 20000",
    )


def test_hdf5_rate_belongs_to_the_channel(rec, tmp_path):
    """An 'fs' applies to the datasets beside it and below it: other groups may run at other rates."""
    path = tmp_path / "r.h5"
    with h5py.File(path, "w") as f:
        f["slow/acc"], f["slow/fs"] = rec.acc[::2], FS / 2
        f["fast/acc"], f["fast/tacho"] = rec.acc, rec.tacho
        f["fast/acc"].attrs["fs"] = FS
        f.attrs["fs"] = FS  # the file's own rate agrees with the fast group
    assert read_channels(path, ["slow/acc"])[1] == FS / 2  # /slow/fs is nearer than the file's attribute
    ds = import_measured(spec_for(path, vibration="fast/acc", tacho="fast/tacho"))
    assert len(ds) == COMPLETE and ds.meta["fs_source"] == "attribute 'fs' of '/fast/acc'"
    with h5py.File(path, "a") as f:
        f["fast/tacho"].attrs["fs"] = 48000.0
    fails(
        spec_for(path, vibration="fast/acc", tacho="fast/tacho"),
        "sampling rates in the file disagree",
        "attribute 'fs' of '/fast/tacho' gives 48 kHz",
    )


def test_too_short_for_one_revolution(rec, tmp_path):
    path = write_npz(tmp_path / "r.npz", {"acc": rec.acc[:1500], "tacho": rec.tacho[:1500], "fs": FS})
    fails(
        spec_for(path, vibration="acc", speed_hz=25),
        "too short for one revolution: 1500 samples",
        "needs 2000 samples at 50 kHz",
    )
    fails(spec_for(path, vibration="acc", tacho="tacho"), "too short for one revolution", "needs 2000 samples")
    # Longer than a revolution, but 1.2 turns starting at 0.3 rad hold no complete one.
    path = write_npz(tmp_path / "s.npz", {"acc": rec.acc[:2400], "tacho": rec.tacho[:2400], "fs": FS})
    fails(spec_for(path, vibration="acc", tacho="tacho"), "no complete revolution")


def test_tacho_and_speed_options(files):
    path, _, _ = files["npz"]
    fails(spec_for(path, vibration="acc"), "give either a tacho channel", "got neither")
    fails(spec_for(path, vibration="acc", tacho="tacho", speed_hz=25), "got both")
    fails(spec_for(path, vibration="acc", tacho="tacho", tacho_kind="pulse"), "did you mean 'pulses'")
    fails(spec_for(path, vibration="acc", speed_hz=-3), "speed_hz (nominal shaft speed) must be positive")
    fails(spec_for(path, vibration="acc", speed_hz=25, transient="periodic"), "unknown transient detection")
    fails(spec_for(path, vibration="acc", speed_hz=25, class_names=("healthy", "healthy")), "class_names")


def test_tacho_that_never_completes_a_revolution(rec, tmp_path):
    one_pulse = np.where((rec.theta > 2 * TWO_PI) & (rec.theta < 2 * TWO_PI + 1), 5.0, 0.0)
    path = write_npz(
        tmp_path / "r.npz",
        {
            "acc": rec.acc,
            "one": one_pulse,
            "stuck": np.full(N, 0.7),
            "degrees": np.degrees(np.mod(rec.theta, TWO_PI)),
            "fs": FS,
        },
    )
    fails(spec_for(path, vibration="acc", tacho="one"), "tacho 'one' never completes a revolution", "1 rising edge")
    fails(spec_for(path, vibration="acc", tacho="stuck"), "tacho 'stuck' never completes a revolution")
    fails(spec_for(path, vibration="acc", tacho="degrees", tacho_kind="angle"), "more than one turn")


def test_label_errors(rec, tmp_path):
    names = rec.label.copy()
    names[30_000] = "craks"
    shifted = np.roll(rec.label, 500)  # changes 500 samples into a revolution
    path = write_npz(
        tmp_path / "r.npz",
        {
            "acc": rec.acc,
            "tacho": rec.tacho,
            "typo": names,
            "index": rec.index * 3,
            "faulty": np.array("fault"),
            "shifted": shifted,
            "fs": FS,
        },
    )
    base = dict(vibration="acc", tacho="tacho")
    fails(
        spec_for(path, labels="typo", class_names=("healthy", "fault", "crack"), **base),
        "unknown class 'craks' (did you mean 'crack'?) at sample 30000",
        "healthy, fault, crack",
    )
    fails(spec_for(path, labels="index", **base), "holds 3 at sample", "not a class index 0 … 1")
    fails(spec_for(path, labels="faulty", **base), "no healthy data to standardise against")
    fails(spec_for(path, labels="shifted", **base), "changes within revolution", "'healthy'", "'fault'")


def test_ragged_csv_and_pickled_npz(rec, tmp_path, files):
    text = files["csv"][0].read_text().splitlines()
    text[100] = text[100].rsplit(",", 2)[0]
    path = tmp_path / "ragged.csv"
    path.write_text("\n".join(text))
    fails(spec_for(path, vibration="acc", tacho="tacho"), "line 101 has 2 fields but the header has 4")
    path = tmp_path / "obj.npz"
    np.savez(path, acc=np.array([rec.acc, "x"], dtype=object), fs=FS)
    fails(spec_for(path, vibration="acc", speed_hz=25), "cannot read", "as NPZ", "allow_pickle")
    path = tmp_path / "single.npz"
    with open(path, "wb") as f:
        np.save(f, rec.acc)
    fails(spec_for(path, vibration="acc", speed_hz=25), "single array")


def test_a_record_that_never_settles_is_kept_whole_with_a_warning(rec, tmp_path):
    """Issue 39: a drifting (or a steady but spread) level is no failure: every revolution is kept
    and the drift is said once, in meta["warnings"]."""
    growing = rec.acc * np.linspace(1, 3, N)
    path = write_npz(tmp_path / "r.npz", {"acc": growing, "tacho": rec.tacho, "fs": FS})
    ds = import_measured(spec_for(path, vibration="acc", tacho="tacho"))
    assert len(ds) == COMPLETE and ds.meta["transient_revolutions"] == 0
    (warning,) = ds.meta["warnings"]
    assert "never settles" in warning and "every revolution is kept" in warning and "\n" not in warning
    kept = import_measured(spec_for(path, vibration="acc", tacho="tacho", transient="none"))
    assert len(kept) == COMPLETE and "warnings" not in kept.meta


@pytest.mark.parametrize("fmt", FORMATS)
def test_truncated_files_fail_cleanly(files, fmt, tmp_path):
    """Cut each file at a few points: one GearlabInputError line, never another exception and,
    for the binary formats, never a dataset from part of the file."""
    path, options, _ = files[fmt]
    data = path.read_bytes()
    size = len(data)
    for cut in sorted({0, 1, 16, 44, 130, 600, size // 10, size // 2, size * 9 // 10, size - 7, size - 1}):
        part = tmp_path / f"cut{cut}{path.suffix}"
        part.write_bytes(data[:cut])
        try:
            ds = import_measured(spec_for(part, **options))
        except GearlabInputError as exc:
            assert "\n" not in str(exc)
        else:
            # A CSV cut at a line end is a valid shorter record; nothing else may import.
            assert fmt == "csv", f"{fmt} cut at {cut} of {size} bytes imported {len(ds)} revolutions"
            assert 0 < len(ds) <= COMPLETE


# --- found by fuzzing (tests/test_fuzz.py) -------------------------------------------------


def hang_guard(seconds=60):
    """An import that loops forever inside a C library cannot be interrupted: end the test
    process with a stack dump rather than hang the run."""
    import faulthandler

    faulthandler.dump_traceback_later(seconds, exit=True)
    return faulthandler.cancel_dump_traceback_later


def test_matlab_element_of_a_type_scipy_does_not_know_is_refused_not_a_crash(files, tmp_path):
    """The complex flag set on a real variable: scipy's reader takes the next variable's tag for
    the imaginary part and indexes its dtype table with it (a segmentation fault). The file's
    layout is checked before scipy reads it."""
    path, options, _ = files["mat5"]
    data = bytearray(path.read_bytes())
    assert data[144] == 6  # the first variable's class: double
    data[145] |= 0x08  # its array flags: complex
    bad = tmp_path / "complex.mat"
    bad.write_bytes(bytes(data))
    fails(spec_for(bad, **options), f"cannot read {bad} as MATLAB", "runs past the end of the variable")


def test_matlab_variables_of_every_kind_pass_the_layout_check(rec, tmp_path):
    """What MATLAB files hold besides the channels (cells, structs, sparse and complex matrices,
    text, empty and integer arrays), compressed or not, and v4 files: the channels import."""
    import scipy.sparse

    extras = {
        "cells": np.array([np.arange(3), "text", np.array([[1, 2]])], dtype=object),
        "nested": {"a": np.arange(4), "b": "x", "c": {"d": np.eye(2)}},
        "sparse": scipy.sparse.csc_matrix(np.eye(5) * (1 + 2j)),
        "complex": np.arange(6) * (1 - 1j),
        "text": "hello",
        "texts": np.array(["ab", "cd"]),
        "empty": np.zeros((0, 3)),
        "nothing": "",
        "ints": np.arange(10, dtype=np.int64),
        "flags": np.array([True, False]),
        "single": np.float32(3.5),
        "fs": scipy.sparse.csc_matrix([[FS]]),  # a rate stored sparse is still one number
    }
    for compress in (False, True):
        path = tmp_path / f"r{compress}.mat"
        scipy.io.savemat(path, {"acc": rec.acc[None], "tacho": rec.tacho[None], **extras}, do_compression=compress)
        ds = import_measured(spec_for(path, vibration="acc", tacho="tacho"))
        assert len(ds) == COMPLETE and ds.meta["fs_hz"] == FS
        fails(spec_for(path, vibration="nested", speed_hz=25), "vibration channel 'nested' is not numeric")
    path = tmp_path / "v4.mat"
    scipy.io.savemat(path, {"acc": rec.acc[None], "tacho": rec.tacho[None], "fs": np.array([[FS]])}, format="4")
    assert len(import_measured(spec_for(path, vibration="acc", tacho="tacho"))) == COMPLETE


def test_damaged_hdf5_groups_do_not_hang_the_import(files, tmp_path):
    """72 bytes of the root group's header repeated: h5py's visititems loops forever on it.
    The importer walks the file itself, each object once."""
    path, options, _ = files["h5"]
    data = path.read_bytes()
    bad = tmp_path / "repeated.h5"
    bad.write_bytes(data[:71] + data[71:143] + data[71:])
    cancel = hang_guard()
    try:
        fails(spec_for(bad, **options), f"cannot read {bad} as HDF5")
    finally:
        cancel()


def test_rate_or_speed_giving_less_than_two_samples_per_revolution(rec, tmp_path):
    """A rate in kHz written as Hz: billions of revolutions in the record, which cutting would
    try to allocate."""
    path = write_npz(tmp_path / "r.npz", {"acc": rec.acc, "fs": 1e-3})
    fails(
        spec_for(path, vibration="acc", speed_hz=25),
        "one revolution spans 4e-05 samples",
        "expected at least 2 samples per revolution",
    )


def test_what_the_file_says_stays_on_one_line(rec, tmp_path):
    path = write_npz(
        tmp_path / "r.npz",
        {"acc": rec.acc, "tacho": rec.tacho, "fs": FS, "label": np.where(rec.index, "fa\nult", "healthy")},
    )
    message = fails(spec_for(path, vibration="acc", tacho="tacho", labels="label"), "unknown class 'fa\\nult'")
    assert "\n" not in message
    fails(spec_for(tmp_path / ("x" * 300 + ".npz"), vibration="acc", speed_hz=25), "File name too long")
    fails(spec_for(tmp_path / "a\0b.npz", vibration="acc", speed_hz=25), "'path' contains a NUL character")


# --- units: sensitivity and gain -----------------------------------------------------------------------


def test_integer_records_are_scaled_by_gain_and_sensitivity_and_keep_their_step(tmp_path, rec):
    """Counts (an int16 array) x gain (V per count) / sensitivity (V per m/s²) are m/s²; one count
    times that scale is the record's quantisation step; with neither given the units are unknown."""
    volts_per_count, sensitivity = 2e-4, 0.01 / 9.80665  # 10 mV/g
    counts = np.round(rec.acc * sensitivity / volts_per_count).astype(np.int16)
    path = write_npz(tmp_path / "counts.npz", {"acc": counts, "tacho": rec.tacho, "fs": FS})
    known = import_measured(
        spec_for(path, vibration="acc", tacho="tacho", sensitivity=sensitivity, gain=volts_per_count)
    )
    raw = import_measured(spec_for(path, vibration="acc", tacho="tacho"))
    scale = volts_per_count / sensitivity
    assert known.meta["quantum"] == pytest.approx(scale) and raw.meta["quantum"] == 1.0
    assert known.meta["units"].startswith("m/s²") and raw.meta["units"].startswith("unknown")
    # the same revolutions, in m/s² against counts
    np.testing.assert_allclose(known.reference[0], raw.reference[0] * scale, rtol=1e-9)
    np.testing.assert_allclose(known.reference[1], raw.reference[1] * scale, rtol=1e-9)
    assert np.abs(known.reference[1] - np.std(rec.acc)).max() < 0.05 * np.std(rec.acc)


def test_a_wav_int16_record_is_scaled_from_full_scale_by_its_gain(files, rec):
    path, options, _ = files["wav-int16"]
    full_scale_volts = 5.0
    ds = import_measured(spec_for(path, sensitivity=0.1, gain=full_scale_volts, **options))
    assert ds.meta["quantum"] == pytest.approx(full_scale_volts / 0.1 / 32768)
    plain = import_measured(spec_for(path, **options))
    assert plain.meta["quantum"] == pytest.approx(1 / 32768) and plain.meta["units"].startswith("unknown")
    np.testing.assert_allclose(ds.reference[1], plain.reference[1] * full_scale_volts / 0.1, rtol=1e-9)


def test_revolution_start_fractions_are_recorded(files):
    path, options, _ = files["npz"]
    fractions = import_measured(spec_for(path, **options)).meta["start_fractions"]
    assert len(fractions) == COMPLETE
    # 2000 samples per revolution: every revolution starts at the same point between two samples,
    # where θ = 2πk falls: sample (2πk - PHI0) / (2π SPEED / FS)
    expected = ((TWO_PI - PHI0) / (TWO_PI * SPEED / FS)) % 1.0
    assert fractions == pytest.approx([expected] * COMPLETE, abs=1e-4) and 0.1 < expected < 0.9


@pytest.mark.parametrize("key, value, fact", [("sensitivity", 0.0, "sensitivity"), ("gain", -1.0, "gain")])
def test_units_must_be_positive(files, key, value, fact):
    path, options, _ = files["npz"]
    fails(spec_for(path, **options, **{key: value}), fact)
