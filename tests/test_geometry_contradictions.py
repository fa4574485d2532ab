"""The geometry contradictions of issue 39 item 1 -- contact ratio below 1, undercut, interference, a tooth
count that the module and centre distance contradict -- each end `gearlab validate` of a scenario that uses
the description with one line naming the description's file, table and key (exit 2). A contact ratio below 1
from a gear's own tip diameter or addendum names that gear's key (it named the stage alone)."""

from __future__ import annotations

import pytest
import tomli_w


def stage(z1, z2, **extra):
    pinion = {"z": z1, "bore": "10 mm", **extra.pop("pinion", {})}
    wheel = {"z": z2, "bore": "10 mm", **extra.pop("wheel", {})}
    return {"module": "2 mm", "face_width": "20 mm", **extra, "pinion": pinion, "wheel": wheel}


CASES = [
    ([stage(12, 40)], "[[stages]] #1.pinion key 'z'", "undercut"),
    ([stage(14, 200)], "[[stages]] #1.pinion key 'z'", "interference"),
    ([stage(20, 57), stage(18, 50, centre_distance="70 mm")], "[[stages]] #2 key 'centre_distance'", "z1 + z2 = 70"),
    ([stage(20, 57, addendum=0.5, dedendum=0.8)], "[[stages]] #1: contact ratio", "below 1"),
    (
        [stage(20, 57, pinion={"tip_diameter": "41 mm"}, wheel={"tip_diameter": "115 mm"})],
        "[[stages]] #1.pinion key 'tip_diameter'",
        "contact ratio ε_α = 0.",
    ),
    (
        [stage(20, 57, pinion={"addendum": 0.5}, wheel={"addendum": 0.5})],
        "[[stages]] #1.pinion key 'addendum'",
        "contact ratio",
    ),
]
IDS = ["undercut", "interference", "centre distance", "contact ratio (stage)", "(pinion tip)", "(gears' addenda)"]


@pytest.mark.parametrize(("stages", "key", "said"), CASES, ids=IDS)
def test_a_contradiction_is_one_line_at_validate(tmp_path, cli, stages, key, said):
    box = {"stages": stages, "operation": {"speed": "25 Hz", "load": "10 N*m"}}
    (tmp_path / "box.toml").write_bytes(tomli_w.dumps(box).encode())
    scenario = tmp_path / "s.toml"
    scenario.write_text(
        '[scenario]\nname = "g"\nkind = "dataset"\n[[datasets]]\ngearbox = "box.toml"\npreset = "B-6-ch5"\n'
        "healthy = 4\n"
    )
    code, _, err = cli("validate", scenario)
    line = err.strip()
    assert code == 2 and len(line.splitlines()) == 1, err
    assert f"box.toml: {key}" in line and said in line, line
