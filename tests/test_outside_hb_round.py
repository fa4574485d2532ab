"""An outside user's look (issue 39): two gearboxes no other test uses, their recordings made here by plain numpy
(mesh lines with shaft sidebands, shaft harmonics, noise; no gearlab simulator). A: one stage 17/53 at 18 Hz, an
accelerometer in volts (10.2 mV/(m/s^2)) and a once-a-turn tacho, logged as a semicolon CSV with decimal commas.
B: two stages 19/67 + 23/71 at 40 Hz, no tacho, in m/s^2 as MATLAB v5 and .npz files whose unit is a text entry."""

from __future__ import annotations

import numpy as np
import scipy.io
from gearboxes import description, stage

FS_B, F_B = 10000.0, 40.0
BOX_B = description(
    stage(19, 67, module="2.5 mm", bores=("25 mm", "30 mm")),
    stage(23, 71, module="3 mm", width="25 mm", bores=("30 mm", "40 mm")),
    name="box2s",
    speed="40 Hz",
    load="60 N*m",
    near="input",
)


def _accel_b(seconds=1.0, seed=1):
    """Box B's acceleration (m/s^2): each stage's mesh (3 harmonics, both shafts' sidebands), run-out, noise."""
    rng = np.random.default_rng(seed)
    n = int(FS_B * seconds)
    th = 2 * np.pi * F_B * np.arange(n) / FS_B + rng.uniform(0, 2 * np.pi)
    shafts = [th, th * 19 / 67, th * 19 / 67 * 23 / 71]
    a = sum(0.5 * np.cos(s + k) for k, s in enumerate(shafts))
    for s, zp in enumerate((19, 23)):
        am = 1 + 0.08 * np.cos(shafts[s]) + 0.06 * np.cos(shafts[s + 1] + 1.1)
        a = a + sum(4 / (1 + s) * ah * am * np.cos(h * zp * shafts[s] + s) for h, ah in ((1, 1), (2, 0.4), (3, 0.2)))
    return a + rng.normal(0, 0.6, n)


def _scenario(tmp_path, history, test, extra=""):
    (tmp_path / "box2s.toml").write_text(BOX_B)
    path = tmp_path / "detect.toml"
    path.write_text(
        '[scenario]\nname = "b"\nkind = "detection"\n[source]\ngearbox = "box2s.toml"\nfaults = { chip = [16] }\n'
        f'[target]\nspeed = "40 Hz"\n{extra}files = [{{ file = "{history}", role = "history", label = "healthy" }}, '
        f'{{ file = "{test}", role = "test", label = "fault" }}]\n[[methods]]\nadapter = "matched_filter"\n'
    )
    return path


def test_a_mat_files_unit_text_is_no_channel_and_its_unit_is_checked_at_validate(cli, tmp_path):
    """A MATLAB v5 take of box B with `acc`, `fs` and the text `acc_unit` (as the guide's step 0 reads a unit):
    validate counted `acc_unit` a second signal channel and asked for 'vibration', which inspect and the run do not;
    and a velocity's `acc_unit = 'mm/s'` passed validate where the same .npz is refused. Both read as inspect reads."""
    a = _accel_b()
    scipy.io.savemat(tmp_path / "h.mat", {"acc": a[:, None], "fs": FS_B, "acc_unit": "m/s^2"}, format="5")
    scipy.io.savemat(tmp_path / "t.mat", {"acc": a[:, None], "fs": FS_B, "acc_unit": "m/s^2"}, format="5")
    code, out, err = cli("validate", _scenario(tmp_path, "h.mat", "t.mat"))
    assert code == 0, err
    scipy.io.savemat(tmp_path / "v.mat", {"acc": a[:, None], "fs": FS_B, "acc_unit": "mm/s"}, format="5")
    code, out, err = cli("validate", _scenario(tmp_path, "h.mat", "v.mat"))
    assert code == 2, out
    assert err.count("\n") == 1 and "key 'vibration'" in err and "v.mat" in err and "velocity in mm/s" in err, err
