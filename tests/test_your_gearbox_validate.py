"""`gearlab validate` on a gearbox description alone (issue 39 outside check): a user who wrote step 1's file
and checked it with validate was told 'missing table [scenario]'; now OK with its stages, or the one line
naming the key that is wrong, exit 2."""

from __future__ import annotations

BOX = """[gearbox]
name = "reducer"

[[stages]]
module = "2 mm"
face_width = "20 mm"
pinion = { z = 24, bore = "20 mm" }
wheel = { z = 83, bore = "35 mm" }
"""


def test_validate_checks_a_gearbox_description(cli, tmp_path):
    good = tmp_path / "box.toml"
    good.write_text(BOX)
    code, out, err = cli("validate", good)
    assert code == 0, err
    assert "gearbox description 'reducer', stages 24/83" in out
    undercut = tmp_path / "undercut.toml"
    undercut.write_text(BOX.replace("z = 24,", "z = 11,"))
    code, out, err = cli("validate", undercut)
    assert code == 2 and "pinion key 'z'" in err and len(err.strip().splitlines()) == 1, err
    typo = tmp_path / "typo.toml"
    typo.write_text(BOX.replace("[[stages]]", "[[stage]]"))
    code, out, err = cli("validate", typo)
    assert code == 2 and "unknown table [stage] (did you mean 'stages'?)" in err, err


def test_history_files_whose_channels_differ_are_told_each_files_own_key(cli, tmp_path):
    # an outside user's logger CSV beside a TSV with another column name: the error named the channels only,
    # and the user, told 'expected the vibration channel's name', gave one that the other file lacks
    (tmp_path / "box.toml").write_text(
        BOX.replace("[[stages]]", '[operation]\nspeed = "25 Hz"\nload = "7 N*m"\n\n[[stages]]')
    )
    t = [i / 5000 for i in range(64)]
    (tmp_path / "a.csv").write_text("time_s,accel_ms2\n" + "".join(f"{x},{(i % 7) - 3}\n" for i, x in enumerate(t)))
    (tmp_path / "b.tsv").write_text("t [s]\tacc [m/s^2]\n" + "".join(f"{x}\t{(i % 5) - 2}\n" for i, x in enumerate(t)))
    (tmp_path / "gap.toml").write_text(
        '[scenario]\nname = "g"\nkind = "gap"\n\n[source]\ngearbox = "box.toml"\n\n[target]\nfiles = [\n'
        '  { file = "a.csv", role = "history", label = "healthy" },\n'
        '  { file = "b.tsv", role = "history", label = "healthy" },\n]\n'
    )
    code, out, err = cli("validate", tmp_path / "gap.toml")
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "a.csv: 'accel_ms2'" in err and "b.tsv: 'acc [m/s^2]'" in err, err
    assert "or each file's own ({ file = 'a.csv', vibration = 'accel_ms2' })" in err, err
