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
