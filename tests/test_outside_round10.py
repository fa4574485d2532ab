"""Outside-user check of issue 39, round 10 (gearboxes and recordings made outside the project by an
independent generator, described as a user would from docs/your_gearbox.md)."""

from __future__ import annotations

import gzip

import numpy as np
import pytest

from gearlab.data.recordings import read_contents


def test_gzipped_text_is_read_as_zipped_text_is(tmp_path, cli):
    # A logger's day file, tab-separated without a header and gzipped (B_next_week.txt.gz, a 31/77 + 23/58
    # reducer): "unknown file type '.gz'", where the same text in a .zip was read.
    rows = np.column_stack([np.sin(np.arange(4000) * 0.37), (np.arange(4000) % 40 < 8) * 4.8])
    body = "".join(f"{a:.6f}\t{b:.3f}\n" for a, b in rows)
    for day in ("day", "next"):
        with gzip.open(tmp_path / f"{day}.txt.gz", "wt") as f:
            f.write(body)
    contents, fmt = read_contents(tmp_path / "day.txt.gz", ["0", "1"])
    assert fmt == "zipped text"
    assert np.allclose(np.asarray(contents.found["0"], float), rows[:, 0], atol=1e-6)
    # validate reads its header (the columns) without the data; a column it lacks is one line, exit 2
    box = '[gearbox]\nname = "b"\n[operation]\nspeed = "20 Hz"\nload = "50 N*m"\n'
    box += '[[stages]]\nmodule = "2 mm"\nface_width = "20 mm"\n'
    box += 'pinion = { z = 31, bore = "20 mm" }\nwheel = { z = 77, bore = "30 mm" }\n'
    (tmp_path / "b.toml").write_text(box)
    for column, code in (("0", 0), ("2", 2)):
        (tmp_path / "d.toml").write_text(
            '[scenario]\nname = "d"\nkind = "detection"\n[source]\ngearbox = "b.toml"\nfaults = { chip = [20] }\n'
            f'[target]\nvibration = "{column}"\ntacho = "1"\nfs = "12 kHz"\nunit = "g"\nfiles = [{{ file = '
            '"day.txt.gz", role = "history", label = "healthy" }, { file = "next.txt.gz", role = "test", label = '
            '"fault" }]\n'
        )
        got, out, err = cli("validate", tmp_path / "d.toml")
        assert got == code, (out, err)
        if code:
            assert len(err.strip().splitlines()) == 1 and "day.txt.gz" in err and "'2'" in err, err


def test_validate_names_a_given_rate_a_csv_time_column_contradicts(tmp_path, cli):
    # A ';' CSV with decimal commas and a time column 'Zeit [ms]' at 25.6 kHz (times printed to 1e-4 ms),
    # and fs = "20 kHz" in [target]: validate said OK (the header named the time column, its rate was not
    # read), the run stopped at reading the data. The same for a '# fs = ...' line.
    fs, n = 25600.0, 3000
    t_ms = np.arange(n) / fs * 1e3
    x = np.sin(np.arange(n) * 0.21)
    rows = "".join(f"{a:.4f};{b:.5f}\n".replace(".", ",") for a, b in zip(t_ms, x))
    (tmp_path / "a.csv").write_text("Zeit [ms];Beschleunigung [m/s^2]\n" + rows)
    (tmp_path / "b.csv").write_text("Zeit [ms];Beschleunigung [m/s^2]\n" + rows)
    (tmp_path / "c.csv").write_text("# fs = 25600\nacc_ms2\n" + "".join(f"{b:.5f}\n" for b in x))
    (tmp_path / "d.csv").write_text("# fs = 25600\nacc_ms2\n" + "".join(f"{b:.5f}\n" for b in x))
    box = '[gearbox]\nname = "a"\n[operation]\nspeed = "48 Hz"\nload = "40 N*m"\n'
    box += '[[stages]]\nmodule = "2 mm"\nface_width = "20 mm"\n'
    box += 'pinion = { z = 27, bore = "25 mm" }\nwheel = { z = 73, bore = "40 mm" }\n'
    (tmp_path / "box.toml").write_text(box)
    for first, second, vib in (("a.csv", "b.csv", "Beschleunigung [m/s^2]"), ("c.csv", "d.csv", "acc_ms2")):
        for rate, code in (("25.6 kHz", 0), ("20 kHz", 2), (None, 0)):
            given = f'fs = "{rate}"\n' if rate else ""
            (tmp_path / "s.toml").write_text(
                '[scenario]\nname = "s"\nkind = "detection"\n[source]\ngearbox = "box.toml"\nfaults = { chip = [20] }\n'
                f'[target]\nvibration = "{vib}"\nspeed = "48 Hz"\n{given}files = [{{ file = "{first}", role = '
                f'"history", label = "healthy" }}, {{ file = "{second}", role = "test", label = "fault" }}]\n'
            )
            got, out, err = cli("validate", tmp_path / "s.toml")
            assert got == code, (first, rate, out, err)
            if code:
                line = err.strip()
                assert len(line.splitlines()) == 1 and "[target] key 'fs'" in line and first in line, line
                assert "25.6 kHz" in line, line


def test_a_wrong_later_stage_does_not_make_inspect_follow_the_record_s_noise(tmp_path):
    # A 19/44 + 29/67 + 25/62 reducer without a tacho (speed swinging 0.12 %), a localised change on the 67T
    # wheel, described with a 66T wheel: the described third mesh's 4th harmonic (4 x 4.74) sat 0.03 orders
    # from M1, so M1 and its next four harmonics were 'not clear of their neighbours' and the 8th (1e-5 of
    # M1's power: noise) was followed. The angle wobbled, every line split in three (M1 read at 19.014), and
    # the verdict blamed the input pinion (19.97 teeth), the first wheel (49.4) and the second pinion (32.5)
    # beside the 67T wheel.
    from gearlab.gearbox import load_gearbox
    from gearlab.inspect import InspectOptions, inspect_record

    fs, f, stages = 16000.0, 58.8, ((19, 44), (29, 67), (25, 62))
    t = np.arange(int(4 * fs)) / fs
    rng = np.random.default_rng(3)
    swing = 1 + 0.0012 * np.sin(2 * np.pi * 0.4 * t + 1) + 0.0004 * np.sin(2 * np.pi * 1.3 * t)
    theta = 2 * np.pi * np.cumsum(f * swing) / fs
    x, o = np.zeros_like(t), 1.0
    for s, (z1, z2) in enumerate(stages):
        wheel = o * z1 / z2
        mod = 1 + 0.12 * np.cos(o * theta + s) + 0.08 * np.cos(wheel * theta - s)
        if s == 1:  # a tooth of the 67T wheel: a dip once per turn of its shaft
            mod *= 1 - 0.5 * np.exp(-0.5 * ((np.angle(np.exp(1j * wheel * theta)) - 1.0) / 0.06) ** 2)
        x += sum(w * mod * np.cos(h * z1 * o * theta + h + s) for h, w in ((1, 1.0), (2, 0.5), (3, 0.25))) / (1 + s)
        o = wheel
    np.savez(tmp_path / "c.npz", acc_ms2=x + rng.normal(0, 0.05, t.size), fs=fs)
    described = ((19, 44), (29, 66), (25, 62))  # the 67T wheel described as 66
    stage = '[[stages]]\nmodule = "2 mm"\nface_width = "20 mm"\npinion = {{ z = {}, bore = "20 mm" }}\n'
    box = [stage.format(a) + f'wheel = {{ z = {w}, bore = "30 mm" }}\n' for a, w in described]
    (tmp_path / "c66.toml").write_text(
        '[gearbox]\nname = "c66"\n[operation]\nspeed = "60 Hz"\nload = "30 N*m"\n' + "".join(box)
    )
    report = inspect_record(str(tmp_path / "c.npz"), load_gearbox(tmp_path / "c66.toml"), InspectOptions("acc_ms2"))
    stage1 = report["check"]["stages"][0]
    assert abs(stage1["measured_order"] - 19) < 0.002, stage1
    assert report["matches"] is False
    assert "67.0" in report["verdict"] and "66 described" in report["verdict"], report["verdict"]
    assert "stage 1" not in report["verdict"], report["verdict"]


def test_an_output_tacho_and_a_later_pinion_one_tooth_off_names_the_pinion_first(tmp_path):
    # A 31/77 + 23/58 reducer, its tacho on the output (2 marks a turn), described with a 24T second pinion:
    # the input's speed, the tacho's times the described ratio, read 4.2 % slow; inspect said 'stage 1: no
    # line at mesh order 31 (a 31-tooth pinion); stage 2: the pinion ... shows 23.0 teeth, 24 described':
    # stage 1 blamed first, as if a second difference. Read outward from the tacho, as the gap reads it.
    from gearlab.gearbox import load_gearbox
    from gearlab.inspect import InspectOptions, inspect_record

    fs, f, stages = 12000.0, 20.2, ((31, 77), (23, 58))
    t = np.arange(int(6 * fs)) / fs
    theta = 2 * np.pi * f * t
    x, o = np.zeros_like(t), 1.0
    for s, (z1, z2) in enumerate(stages):
        mod = 1 + 0.15 * np.cos(o * theta + s) + 0.1 * np.cos(o * z1 / z2 * theta + 2 * s)
        x += sum(w * mod * np.cos(h * z1 * o * theta + h) for h, w in ((1, 1.0), (2, 0.4), (3, 0.2)))
        o *= z1 / z2
    tach = np.where((2 * o * theta) % (2 * np.pi) < 2.0, 4.8, 0.1)
    x = x + np.random.default_rng(5).normal(0, 0.05, t.size)
    np.savez(tmp_path / "b.npz", acc_ms2=x, tach=tach, fs=fs)
    box = '[gearbox]\nname = "b24"\n[operation]\nspeed = "1200 rpm"\nload = "150 N*m"\n'
    for (z1, z2), m in zip(((31, 77), (24, 58)), ("1.5 mm", "2.5 mm")):
        box += f'[[stages]]\nmodule = "{m}"\nface_width = "20 mm"\npinion = {{ z = {z1}, bore = "20 mm" }}\n'
        box += f'wheel = {{ z = {z2}, bore = "30 mm" }}\n'
    (tmp_path / "b24.toml").write_text(box + '[sensor]\ntacho = "output"\npulses_per_rev = 2\n')
    report = inspect_record(
        str(tmp_path / "b.npz"), load_gearbox(tmp_path / "b24.toml"), InspectOptions("acc_ms2", "tach")
    )
    verdict = report["verdict"]
    assert report["matches"] is False
    first = verdict.split(": ", 1)[1]
    assert first.startswith("stage 2: the pinion on the intermediate shaft shows 23.0"), verdict
    assert "24 described" in first.split(";")[0], verdict
    assert "stage 1: no line at mesh order 31 (a 31-tooth pinion), as follows from stage 2's difference" in verdict
    outward = {"stage": 2, "gear": "pinion", "seen": pytest.approx(23, abs=0.3), "described": 24}
    assert report["check"]["outward"] == outward


def test_validate_names_the_table_of_a_file_whose_header_cannot_be_read(tmp_path, cli):
    # A zip of two text files among a scenario's records: validate's line named the archive alone
    # ("two.zip: expected a zip archive of exactly one text file, found 2"), not the table or key.
    import zipfile

    with zipfile.ZipFile(tmp_path / "two.zip", "w") as z:
        z.writestr("a.txt", "1\t2\n3\t4\n")
        z.writestr("b.txt", "1\t2\n")
    (tmp_path / "one.txt").write_text("".join(f"{np.sin(i):.4f}\t0\n" for i in range(3000)))
    box = '[gearbox]\nname = "b"\n[operation]\nspeed = "20 Hz"\nload = "50 N*m"\n'
    box += '[[stages]]\nmodule = "2 mm"\nface_width = "20 mm"\n'
    box += 'pinion = { z = 31, bore = "20 mm" }\nwheel = { z = 77, bore = "30 mm" }\n'
    (tmp_path / "b.toml").write_text(box)
    (tmp_path / "d.toml").write_text(
        '[scenario]\nname = "d"\nkind = "detection"\n[source]\ngearbox = "b.toml"\nfaults = { chip = [20] }\n'
        '[target]\nvibration = "0"\ntacho = "1"\nfs = "12 kHz"\nunit = "g"\nfiles = [{ file = "one.txt", role = '
        '"history", label = "healthy" }, { file = "two.zip", role = "test", label = "fault" }]\n'
    )
    code, out, err = cli("validate", tmp_path / "d.toml")
    line = err.strip()
    assert code == 2 and len(line.splitlines()) == 1, (out, err)
    assert "d.toml: [target]" in line and "two.zip" in line and "exactly one text file, found 2" in line, line
