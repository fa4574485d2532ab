"""An outside user's look (issue 39): two gearboxes no other test uses, their takes made here by plain numpy (mesh
lines with both shafts' sidebands, shaft harmonics, noise; no gearlab simulator). A: one stage 13/41 (a 13-tooth
pinion, profile-shifted) at 60 Hz, 100 mV/g through a x10 amplifier (1 V/g), a headerless tab-separated text at
25.6 kHz with a tacho of 2 marks a turn. B: three stages 21/63 + 18/54 + 15/45 at 30 Hz, no tacho, an int16 WAV at a
full scale of 20 g. Beside them: a one-take history's level, and MATLAB's two-byte characters in a unit text."""

from __future__ import annotations

import json
from types import SimpleNamespace

import numpy as np
import pytest
import scipy.io
from gearboxes import description, inspected, read_as_described, stage

G = 9.80665
FS_A, F_A = 25600.0, 60.0
BOX_A = description(name="boxA", speed="60 Hz", load="30 N*m", tacho="input", marks=2) + (
    '[[stages]]\nmodule = "2 mm"\nface_width = "20 mm"\npinion = { z = 13, bore = "15 mm", x = 0.25 }\n'
    'wheel = { z = 41, bore = "25 mm" }\n'
)
A_KEYS = ("--vibration", "0", "--tacho", "1", "--fs", "25600", "--sensitivity", "1 V/g")


def _accel(z, speed, fs, seconds, seed, level=1.0):
    """A box's acceleration (m/s^2) and input-shaft angle: each stage's mesh (3 harmonics, its two shafts'
    sidebands) times *level* (a load), each shaft's run-out and harmonics, noise."""
    rng = np.random.default_rng(seed)
    n = int(fs * seconds)
    th = 2 * np.pi * speed * np.arange(n) / fs + rng.uniform(0, 2 * np.pi)
    shafts = [th * np.prod([zp / zw for zp, zw in z[:k]]) for k in range(len(z) + 1)]
    a = sum(0.3 / h * np.cos(h * s + k + h) for k, s in enumerate(shafts) for h in (1, 2, 3))
    for s, (zp, _) in enumerate(z):
        am = 1 + 0.1 * np.cos(shafts[s] + 0.3) + 0.07 * np.cos(shafts[s + 1] + 1.9)
        mesh = sum(ah * np.cos(h * zp * shafts[s] + s + h) for h, ah in ((1, 1), (2, 0.45), (3, 0.2)))
        a = a + level * 3.0 / (1 + s) * am * mesh
    return a + rng.normal(0, 0.4, n), th


def _text_a(path, seed=1, seconds=1.5):
    """Box A's take as its logger writes it: no header, tab-separated, volts at 1 V/g, a 2-mark tacho."""
    a, th = _accel(((13, 41),), F_A, FS_A, seconds, seed)
    tacho = np.where(np.mod(2 * th, 2 * np.pi) < 0.3, 4.9, 0.02)
    np.savetxt(path, np.column_stack([a / G, tacho]), fmt="%.5f", delimiter="\t")
    return path


@pytest.fixture(scope="module")
def box_a(tmp_path_factory):
    where = tmp_path_factory.mktemp("hg_a")
    (where / "boxA.toml").write_text(BOX_A)
    (where / "boxA14.toml").write_text(BOX_A.replace("z = 13", "z = 14"))
    take = _text_a(where / "take.txt")
    (where / "test.txt").write_bytes(take.read_bytes())  # a second take for a scenario's test role
    return where, take


def test_a_headerless_tab_text_reads_its_mesh_speed_and_two_marks(cli, box_a):
    where, take = box_a
    read_as_described(inspected(cli, take, "--gearbox", where / "boxA.toml", *A_KEYS), F_A, [13])


def test_a_wrong_pinion_count_is_called_out(cli, box_a):
    where, take = box_a
    code, out, err = cli("inspect", take, "--gearbox", where / "boxA14.toml", *A_KEYS)
    assert code == 0, err
    assert "a 13-tooth pinion on the input shaft? described 14" in out, out[-2000:]


def validated_a(chain: str) -> str:
    """A detection scenario on box A's two takes with the [target] *chain* keys (sensitivity, gain)."""
    return (
        '[scenario]\nname = "a"\nkind = "detection"\n[source]\ngearbox = "boxA.toml"\nfaults = { chip = [20] }\n'
        f'[target]\nvibration = "0"\ntacho = "1"\nfs = 25600\n{chain}\n'
        'files = [{ file = "take.txt", role = "history", label = "healthy" }, '
        '{ file = "test.txt", role = "test", label = "fault" }]\n'
    )


@pytest.mark.parametrize(
    "change, said",
    [
        (('vibration = "0"', 'vibration = "2"'), ("take.txt has no channel '2'", "key 'vibration'")),
        (('"test.txt"', '"gone.txt"'), ("gone.txt: no such file", "key 'file'")),
        (('sensitivity = "1 V/g"', 'unit = "mm/s"'), ("'mm/s' is a velocity", "key 'unit'")),
    ],
)
def test_a_bad_input_is_one_line_at_validate(cli, box_a, change, said):
    where, _ = box_a
    scenario = validated_a('sensitivity = "1 V/g"')
    (where / "ok.toml").write_text(scenario)
    code, out, err = cli("validate", where / "ok.toml")
    assert code == 0, err
    (where / "bad.toml").write_text(scenario.replace(*change))
    code, out, err = cli("validate", where / "bad.toml")
    assert code == 2 and err.count("\n") == 1 and "bad.toml" in err, (out, err)
    assert all(s in err for s in said), err


def test_an_amplifier_s_gain_given_as_gain_is_refused_on_decimal_values(cli, box_a):
    # the guide: 100 mV/g through x10 is sensitivity '1 V/g', not --gain 10 (refused on volts); on a headerless
    # text, no unit said, '--sensitivity "100 mV/g" --gain 10' read each volt as 10 V: 100 g a file unit, the level
    # 100 x too high, unsaid, and a scenario's gain = 10 passed validate
    where, take = box_a
    keys = A_KEYS[:-1] + ("100 mV/g",)
    code, out, err = cli("inspect", take, *keys, "--gain", "10", "--speed", "60 Hz")
    assert "not m/s² (expected no gain (an amplifier's gain goes in the sensitivity" in out, (out[:800], err)
    scenario = validated_a('sensitivity = "100 mV/g"\ngain = 10')
    (where / "gain.toml").write_text(scenario)
    code, out, err = cli("validate", where / "gain.toml")
    assert code == 2 and err.count("\n") == 1 and "key 'gain'" in err and "take.txt" in err, (out, err)
    (where / "volts.toml").write_text(scenario.replace("gain = 10", 'gain = "10 V"'))  # a unit said: as before
    code, out, err = cli("validate", where / "volts.toml")
    assert code == 0, err


def test_a_one_take_history_says_a_called_take_off_its_level_is_load_uncertain():
    # a healthy take at 1.2 x a one-take history's level (one load), called by NA4 and the template methods with no
    # gear named: its spread unknown (None), nothing was said of its level under the 1.25 x of a level change, and
    # the run's verdict read 'the watched gear's fault by the run's rule; look at the watched gear.'
    from gearlab.kinds.detection_level import called_level, run_levels
    from gearlab.kinds.detection_summary import take_lines

    def revs(seed, level=1.0):  # 256 samples a turn, whole turns: the revolutions a run reads
        a, _ = _accel(((13, 41),), 100.0, 25600.0, 0.82, seed, level)
        return a[: 82 * 256].reshape(82, 256)

    take = lambda name, r: (SimpleNamespace(path=name), r)  # noqa: E731
    test = [take("loaded", revs(2, 1.2)), take("same", revs(3))]
    ratios, spread, _ = run_levels({"history": [take("h", revs(1))], "test": test})
    said = called_level(True, [], ratios["loaded"], spread, 1)
    assert said.startswith("level 1.2 x its history's, its one take's turns within "), (ratios, spread, said)
    assert "load-uncertain" in said, said
    assert called_level(True, [], ratios["same"], spread, 1) == "", (ratios, spread)  # its own load: nothing
    assert called_level(True, ["input pinion 13T (stage 1)"], ratios["loaded"], spread, 1) == ""  # a gear named
    # the run's verdict says so of the take, as gearlab score's rows do
    level = {"history": ["h"], "level_ratio": ratios, "level_spread": spread, "warnings": []}
    loc = {"condition": "60 Hz", "named": [], "call": "watched-gear fault (not localised)",
           "summary": "nothing localised (largest: input z = 0.80, threshold 2.58)"}  # fmt: skip
    summary = {"which_gear": {"records": {"loaded": loc}}, "conditions": {"60 Hz": level}}
    records = [{"condition": "60 Hz", "method": "na4", "thresholds": {"record30": 1.0},
                "test_scores": {"loaded": {"record30": [2.0, 3.0]}}}]  # fmt: skip
    (line,) = take_lines(summary, records, "record30")
    assert "its level 1.2 x its history's, its one take's turns within" in line and "load-uncertain" in line, line
    assert line.endswith("or record a history at this take's load (or gain)."), line


def _two_byte_chars(monkeypatch, mdtype):
    """scipy's MAT v5 writer writing text as MATLAB does in some files: two bytes a character (miUINT16, or
    miUTF16), where scipy writes UTF-8."""
    from scipy.io.matlab import _mio5
    from scipy.io.matlab._miobase import arr_to_chars

    def write_char(self, arr, codec="ascii"):
        arr = arr_to_chars(arr)
        self.write_header(arr.shape, _mio5.mxCHAR_CLASS)
        self.write_element(np.array([ord(c) for c in arr.T.ravel()], dtype="<u2"), mdtype=mdtype)

    monkeypatch.setattr(_mio5.VarWriter5, "write_char", write_char)


def _v73(path, acc, unit):
    """A MATLAB v7.3 file (HDF5 with MATLAB's 512-byte header) of struct rec: acc, fs and units, the text as MATLAB
    keeps it, one uint16 a character."""
    import h5py

    with h5py.File(path, "w", userblock_size=512) as f:
        rec = f.create_group("rec")
        rec.attrs["MATLAB_class"] = np.bytes_("struct")
        for name, data, kind in (("acc", acc[None, :], "double"), ("fs", np.array([[5000.0]]), "double"),
                                 ("units", np.array([[ord(c)] for c in unit], dtype="<u2"), "char")):  # fmt: skip
            rec.create_dataset(name, data=data).attrs["MATLAB_class"] = np.bytes_(kind)
    with open(path, "r+b") as f:
        f.write(b"MATLAB 7.3 MAT-file, written by h5py".ljust(116) + bytes(8) + b"\x00\x02IM")
    return path


@pytest.mark.parametrize("writer", ["miUINT16", "miUTF16", "v7.3"])
def test_a_mat_unit_text_in_two_byte_characters_is_read_by_validate_and_inspect(cli, tmp_path, monkeypatch, writer):
    from scipy.io.matlab import _mio5_params

    acc = _accel(((16, 48),), 25.0, 5000.0, 2.0, seed=4)[0] / G
    if writer == "v7.3":
        good, bad = _v73(tmp_path / "g.mat", acc, "g"), _v73(tmp_path / "v.mat", acc, "mm/s")
    else:
        _two_byte_chars(monkeypatch, getattr(_mio5_params, writer))
        good, bad = tmp_path / "g.mat", tmp_path / "v.mat"
        scipy.io.savemat(good, {"rec": {"acc": acc, "fs": 5000.0, "units": "g"}}, do_compression=writer == "miUTF16")
        scipy.io.savemat(bad, {"rec": {"acc": acc, "fs": 5000.0, "units": "mm/s"}})
    code, out, err = cli("inspect", good, "--vibration", "rec/acc", "--speed", "25 Hz")
    assert code == 0 and "values: m/s² = value x 9.80665 (channel 'rec/acc' in g)" in out, (out[:600], err)
    (tmp_path / "box.toml").write_text(description(stage(16, 48), name="b", speed="25 Hz", load="7 N*m"))
    for take, code_expected in ((good, 0), (bad, 2)):
        (tmp_path / "gap.toml").write_text(
            '[scenario]\nname = "m"\nkind = "gap"\n[source]\ngearbox = "box.toml"\n[target]\nvibration = "rec/acc"\n'
            f'files = [{{ file = "{take.name}", role = "history", label = "healthy" }}]\n[accuracy]\nenabled = false\n'
        )
        code, out, err = cli("validate", tmp_path / "gap.toml")
        assert code == code_expected, (out, err)
    assert err.count("\n") == 1 and "v.mat" in err and "key 'vibration'" in err and "velocity in mm/s" in err, err


FS_B, F_B, STAGES_B = 10000.0, 30.0, ((21, 63), (18, 54), (15, 45))
B_KEYS = ("--vibration", "0", "--gain", "20 g")  # an int16 WAV's unit is its full scale
BOX_B = description(
    stage(21, 63, bores=("20 mm", "30 mm")),
    stage(18, 54, module="3 mm", width="30 mm", bores=("30 mm", "40 mm")),
    stage(15, 45, module="4 mm", width="40 mm", bores=("40 mm", "60 mm")),
    name="boxB",
    speed="30 Hz",
    load="50 N*m",
    near="input",
)


@pytest.fixture(scope="module")
def box_b(tmp_path_factory):
    """Box B's take as its recorder writes it: an int16 WAV whose full scale is 20 g, no tacho, 4 s."""
    from scipy.io import wavfile

    where = tmp_path_factory.mktemp("hg_b")
    (where / "boxB.toml").write_text(BOX_B)
    (where / "boxB19.toml").write_text(BOX_B.replace("z = 18", "z = 19"))
    a = _accel(STAGES_B, F_B, FS_B, 4.0, seed=21)[0]
    wavfile.write(where / "take.wav", int(FS_B), np.round(a / G / 20.0 * 32767).astype(np.int16))
    return where, where / "take.wav"


def test_b_three_stage_wav_reads_its_meshes_and_speed_and_says_why_the_input_count_is_open(cli, box_b):
    # stage 1's wheel turns once in 3 input turns (21/63): the input's sidebands, 1 order off the first mesh, are the
    # intermediate 1 shaft's 3rd and are left out, so the pinion's count stays open; inspect said only 'a tacho or
    # the measured speed (--speed) would decide', though the lines stood clear in the spectrum
    where, take = box_b
    code, out, err = cli("inspect", take, "--gearbox", where / "boxB.toml", *B_KEYS, "--json")
    assert code == 0, err
    report = json.loads(out)
    assert abs(report["speed"]["mean_hz"] - F_B) < 0.005 * F_B, report["speed"]
    measured = [s["measured_order"] for s in report["check"]["stages"]]
    assert np.allclose(measured, [21, 6, 5 / 3], atol=0.05), measured
    verdict = report["verdict"]
    assert "the input turns 3 times a turn of the intermediate 1 shaft" in verdict, verdict


def test_b_wrong_count_on_the_intermediate_shaft_is_called_out(cli, box_b):
    where, take = box_b
    code, out, err = cli("inspect", take, "--gearbox", where / "boxB19.toml", *B_KEYS)
    assert code == 0, err
    assert "stage 2: mesh order 6 measured, 6.333 expected" in out and "described 19" in out, out[-2000:]
