"""Outside user FH (issue 39, round 26): a 39/61 single-stage drive recorded by two accelerometers (one on the
gear's bearing, one on the motor's) beside a once-per-turn tacho, takes named by their date; its takes made here
with numpy (both shafts' lines, the mesh's harmonics modulated in amplitude and phase, noise). A user with an idler
between pinion and wheel writes it as a third gear of the stage."""

from __future__ import annotations

BOX = (
    '[gearbox]\nname = "mill39"\n[operation]\nspeed = "30 Hz"\nload = "20 N*m"\n'
    '[[stages]]\nmodule = "2 mm"\nface_width = "20 mm"\n'
    'pinion = { z = 39, bore = "25 mm" }\nwheel = { z = 61, bore = "30 mm" }\n'
    '[sensor]\nnear = "input"\ntacho = "input"\n'
)


def test_an_idler_written_in_a_stage_is_refused_with_the_two_stages_to_write(tmp_path, cli):
    # 'idler = { z = 45 }' beside pinion and wheel was 'unknown key (did you mean 'module'?)': no word of how an idler
    # is described (two stages sharing its tooth count, as the guide's last section says)
    idler = BOX.replace("wheel = {", 'idler = { z = 45, bore = "25 mm" }\nwheel = {')
    (tmp_path / "box.toml").write_text(idler)
    code, out, err = cli("validate", tmp_path / "box.toml")
    line = err.strip()
    assert code == 2 and "\n" not in line and "box.toml: [[stages]] #1 key 'idler'" in line, err
    assert "did you mean" not in line and "two [[stages]]" in line, line
    assert "39/45" in line and "45/61" in line, line
