"""An outside user's three-stage gearbox (13/43, 31/67, 41/97, described from its tooth counts only):
the integration-rate warning a gap or detection run prints must name the key that changes the rate."""

import re
import warnings

from gearlab.dynamics.newmark import Simulator
from gearlab.gearbox.simulation import model_name, reference, referenced
from gearlab.registry import get_registry

BOX = """
[gearbox]
name = "boxd"

[operation]
speed = "28 Hz"
load = "40 N*m"

[[stages]]
module = "2 mm"
face_width = "20 mm"
pinion = { z = 13, bore = "20 mm", x = 0.3 }
wheel = { z = 43, bore = "25 mm" }

[[stages]]
module = "2.5 mm"
face_width = "25 mm"
pinion = { z = 31, bore = "25 mm" }
wheel = { z = 67, bore = "35 mm" }

[[stages]]
module = "3 mm"
face_width = "30 mm"
pinion = { z = 41, bore = "35 mm" }
wheel = { z = 97, bore = "50 mm" }

[sensor]
near = "intermediate 1"
tacho = "input"
"""


def test_three_stage_rate_warning_names_the_scenario_key(tmp_path):
    # gap and detection runs of this box printed "model 'three_stage', preset 'gearbox:...#fd04...': fs = 200200 Hz
    # gives fewer than 10 steps ...; expected fs >= 284337 Hz": no key a scenario's user could change
    path = tmp_path / "boxd.toml"
    path.write_text(BOX)
    ref = reference(str(path))
    model = get_registry().get("model", model_name(referenced(ref)))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sim = Simulator(model, ref, 200e3)
    said = [str(w.message) for w in caught if "fewer than 10 steps" in str(w.message)]
    assert len(said) == 1, said
    floor_khz = -(-sim.fs_floor // 1e3)
    assert 250e3 < sim.fs_floor < 350e3  # the stiffest mode near 28 kHz, over the default 200 kHz / 10
    assert re.search(r"\[source\] fs = \"(\d+) kHz\"", said[0]).group(1) == f"{floor_khz:.0f}", said[0]
    assert "--fs" in said[0]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # at the rate it names, no warning
        Simulator(model, ref, floor_khz * 1e3)


BOX_F = """
[gearbox]
name = "boxf"

[operation]
speed = "1440 rpm"
load = "60 N*m"

[[stages]]
module = "2 mm"
face_width = "20 mm"
pinion = { z = 21, bore = "20 mm" }
wheel = { z = 55, bore = "30 mm" }

[[stages]]
module = "3 mm"
face_width = "30 mm"
pinion = { z = 34, bore = "30 mm" }
wheel = { z = 77, bore = "45 mm" }

[sensor]
near = "output"
tacho = "output"
pulses_per_rev = 2
"""

DETECT_F = """
[scenario]
name = "boxf_chip"
kind = "detection"

[source]
gearbox = "boxf.toml"
faults = {{ "chip@output gear" = [16, 18, 20] }}
healthy = 48
{teeth}
[target]
vibration = "acc"
speed = "24 Hz"
files = [
  {{ file = "h.csv", role = "history", label = "healthy" }},
  {{ file = "t.csv", role = "test", label = "fault" }},
]
"""


def _watched_wheel(tmp_path, teeth: str):
    from gearlab.engine import load_scenario

    (tmp_path / "boxf.toml").write_text(BOX_F)
    for name in ("h.csv", "t.csv"):
        (tmp_path / name).write_text("time_s,acc\n0,0\n")
    (tmp_path / "d.toml").write_text(DETECT_F.format(teeth=teeth))
    (fault,) = load_scenario(tmp_path / "d.toml").spec.source.fault_classes("test").values()
    return fault


def test_the_guide_s_cost_of_a_watched_output_wheel_and_its_way_out(tmp_path):
    # the guide promised seconds with --quick; box F's run made 232 simulations, ETA 2 h 30 at load 7, and the
    # guide named no way out: what docs/your_gearbox.md now says of it stands
    from pathlib import Path

    guide = " ".join((Path(__file__).parents[1] / "docs" / "your_gearbox.md").read_text().split())
    every = _watched_wheel(tmp_path, "")
    assert (every.period, len(every.teeth)) == (605, 77)  # 77 x 3 sizes + the healthy case: 232 simulations
    assert "77T output gear: 232 simulations of 605 input turns" in guide
    chosen = _watched_wheel(tmp_path, "teeth = [1, 27, 53]\n")
    assert chosen.teeth == (1, 27, 53)  # 3 x 3 + 1: 10 simulations
    assert "`teeth = [1, 27, 53]` in `[source]` simulates those alone (10 simulations" in guide
