"""An outside user's short take (issue 39, "Bad input ... at validate time wherever the file header suffices";
helper O): a 1 s test take of a two-stage 26/63 + 24/77 box at 45 Hz passed `gearlab validate`, then stopped the
detection run ('gives 18 intermediate-shaft revolutions, fewer than record30's 30'). A WAV's and an HDF5 file's
header give the take's length (samples and rate), so validate can refuse it before any run; a CSV's does not
(validate reads no data), so nothing new is said of one. The takes are made here, seconds long, by plain numpy."""

from __future__ import annotations

import h5py
import numpy as np
import pytest
import scipy.io.wavfile
from gearboxes import reducer_26_63_24_77

FS = 25600
# the watched gear, the intermediate pinion, turns 26/63 x 45 = 18.6 times a second: a record30 unit needs 1.6 s
BOX = reducer_26_63_24_77(name="boxT", load="400 N*m")


def _signal(seconds: float) -> tuple[np.ndarray, np.ndarray]:
    """Both meshes (in g) and a once-a-turn input tacho of a take of *seconds* at 45 Hz."""
    t = np.arange(int(FS * seconds)) / FS
    th = 2 * np.pi * 45.0 * t
    x = np.cos(26 * th) + 0.6 * np.cos(24 * th * 26 / 63) + np.random.default_rng(1).normal(0, 0.02, t.size)
    return x, 5.0 * (np.cos(th) > 0.99)


def _wav(path, seconds):
    x, tacho = _signal(seconds)
    scipy.io.wavfile.write(path, FS, np.column_stack([x, tacho]).astype(np.float32))
    return path.name, "0", "1"


def _h5(path, seconds):
    x, tacho = _signal(seconds)
    with h5py.File(path, "w") as f:
        f.attrs["fs"] = float(FS)
        f["acc"], f["tacho"] = x, tacho
    return path.name, "acc", "tacho"


def _stored(path, seconds):
    """The take with its rate stored as data, a one-number 'fs' beside the channels: npz, MAT v5 / v4, HDF5."""
    x, tacho = _signal(seconds)
    arrays = {"acc": x, "tacho": tacho, "fs": np.array(float(FS))}
    if path.suffix == ".npz":
        np.savez(path, **arrays)
    elif path.suffix == ".h5":
        with h5py.File(path, "w") as f:
            for k, v in arrays.items():
                f[k] = v
    else:
        scipy.io.savemat(path, arrays, format="4" if path.stem.endswith("v4") else "5")
    return path.name, "acc", "tacho"


def _csv(path, seconds):
    x, tacho = _signal(seconds)
    t = np.arange(x.size) / FS
    np.savetxt(path, np.column_stack([t, x, tacho]), fmt="%.6f", delimiter=",", header="time_s,acc,tacho", comments="")
    return path.name, "acc", "tacho"


def _validate(cli, tmp_path, test_take: tuple, declared: bool = True):
    """validate a detection scenario watching the intermediate pinion: two long WAV history takes and *test_take*
    (its file, vibration and tacho channels), *declared*: read at its declared 45 Hz without its tacho, else by its
    tacho (its speed then read in the run)."""
    (tmp_path / "box.toml").write_text(BOX)
    takes = [(_wav(tmp_path / f"h{i}.wav", 3.0), "history") for i in (1, 2)] + [(test_take, "test")]
    listed = ",\n".join(
        f'{{ file = "{f}", vibration = "{v}", '
        + ('speed = "45 Hz"' if declared and role == "test" else f'tacho = "{t}"')
        + f', role = "{role}", label = "healthy" }}'
        for (f, v, t), role in takes
    )
    (tmp_path / "d.toml").write_text(
        '[scenario]\nname = "t"\nkind = "detection"\n[source]\ngearbox = "box.toml"\n'
        'faults = { "chip@intermediate pinion" = [18] }\nhealthy = 8\n'
        f'[target]\nunit = "g"\nfiles = [\n{listed},\n]\n'
        '[[methods]]\nadapter = "matched_filter"\n[protocol]\nbatch = 4\n'
    )
    return cli("validate", tmp_path / "d.toml")


def test_a_short_wav_take_is_refused_at_validate(cli, tmp_path):
    # before: 'OK', then the run stopped after reading every take
    code, out, err = _validate(cli, tmp_path, _wav(tmp_path / "short.wav", 1.0))
    assert code == 2, out + err
    (line,) = err.strip().splitlines()
    assert "d.toml" in line and "[target] key 'files'" in line and "short.wav: 1 s at 45 Hz holds ~18 turns" in line
    assert "of the intermediate shaft; record30 needs 30 (a take of >= 1.7 s)" in line, line


def test_a_short_hdf5_take_is_refused_at_validate(cli, tmp_path):
    code, out, err = _validate(cli, tmp_path, _h5(tmp_path / "short.h5", 1.0))
    assert code == 2, out + err
    (line,) = err.strip().splitlines()
    assert "short.h5: 1 s at 45 Hz holds ~18 turns of the intermediate shaft; record30 needs 30" in line, line


def test_a_short_take_read_by_its_tacho_is_warned_of(cli, tmp_path):
    # its speed is its tacho's, read in the run: at the description's 45 Hz it is short, a faster take might not be
    for take in (_wav(tmp_path / "short.wav", 1.0), _h5(tmp_path / "short.h5", 1.0)):
        code, out, err = _validate(cli, tmp_path, take, declared=False)
        assert code == 0 and out.startswith("OK"), out + err
        assert f"{take[0]}: 1 s at 45 Hz holds ~18 turns of the intermediate shaft; record30 needs 30" in err, err
        assert "unless it runs faster than the description's speed" in err, err


def test_a_long_enough_take_passes(cli, tmp_path):
    for take in (_wav(tmp_path / "long.wav", 2.0), _h5(tmp_path / "long.h5", 2.0)):  # 37 turns
        code, out, err = _validate(cli, tmp_path, take)
        assert code == 0 and out.startswith("OK"), out + err


def test_a_csv_take_s_length_is_not_read_at_validate(cli, tmp_path):
    # a text file's header gives no length: validate reads no data, and says what it said before
    code, out, err = _validate(cli, tmp_path, _csv(tmp_path / "short.csv", 1.0))
    assert code == 0 and out.startswith("OK"), out + err


def test_a_short_take_with_its_rate_stored_as_data_is_refused_at_validate(cli, tmp_path):
    # before: OK for each (the header gave the array's shape but no rate: the one-number 'fs' was data, not read)
    for name in ("short.npz", "short.mat", "short_v4.mat", "short.h5"):
        code, out, err = _validate(cli, tmp_path, _stored(tmp_path / name, 1.0))
        assert code == 2, name + out + err
        (line,) = err.strip().splitlines()
        assert f"{name}: 1 s at 45 Hz holds ~18 turns of the intermediate shaft; record30 needs 30" in line, line
    for name in ("long.npz", "long.mat", "long_v4.mat", "long.h5"):
        code, out, err = _validate(cli, tmp_path, _stored(tmp_path / name, 2.0))
        assert code == 0 and out.startswith("OK"), name + out + err


def test_a_given_rate_against_one_stored_as_data_is_refused_as_the_run_refuses_it(tmp_path):
    from gearlab.data.recordings import read_header
    from gearlab.errors import GearlabInputError

    for name in ("t.npz", "t.mat", "t_v4.mat", "t.h5"):
        path = tmp_path / name
        _stored(path, 0.5)
        header = read_header(path)
        assert header.stated[0] == FS, name
        header.check_rate(float(FS), "d.toml: [target]", path)  # the same rate given: fine
        with pytest.raises(GearlabInputError, match=r"d.toml: \[target\] key 'fs': 20 kHz given, but .* says 25.6 kHz"):
            header.check_rate(20000.0, "d.toml: [target]", path)
