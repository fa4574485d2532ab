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
