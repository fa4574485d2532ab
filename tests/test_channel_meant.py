"""A vibration channel misnamed is offered among the columns that look like a vibration's (issue 39, an outside user's
triaxial sensor): 'acc_x' was answered 'did you mean 'tacho_V'?' (the closest spelling of all the columns) where
'ax_g' was meant."""

from __future__ import annotations

import numpy as np

HEADER = "time_s,ax_g,ay_g,az_g,tacho_V"


def _csv(path):
    t = np.arange(4000) / 2000.0
    x = np.sin(2 * np.pi * 300 * t)
    rows = np.column_stack([t, x, 0.5 * x, 0.1 * x, 5.0 * (25 * t % 1 < 0.1)])
    path.write_text(HEADER + "\n" + "\n".join(",".join(f"{v:.6f}" for v in r) for r in rows) + "\n")
    return path


def test_a_misnamed_vibration_is_offered_the_vibration_like_columns_first(tmp_path, cli):
    rec = _csv(tmp_path / "tri.csv")
    code, _, err = cli("inspect", rec, "--vibration", "acc_x", "--tacho", "tacho_V")
    line = err.strip()
    assert code == 2 and "\n" not in line and "no vibration channel 'acc_x'" in line, err
    assert "(a vibration channel: ax_g, ay_g, az_g?)" in line and "did you mean" not in line, line
    # one spelt close among them: that one
    code, _, err = cli("inspect", rec, "--vibration", "ax_G", "--tacho", "tacho_V")
    assert code == 2 and "did you mean 'ax_g'" in err, err
    # a tacho misnamed is still offered by spelling across every column
    code, _, err = cli("inspect", rec, "--vibration", "ax_g", "--tacho", "tacho_v")
    assert code == 2 and "did you mean 'tacho_V'" in err, err


def test_validate_offers_the_same(tmp_path, cli):
    from detection_scenario import scenario

    path = scenario(tmp_path)
    for name in ("h1", "h2", "h3", "f1", "f2"):  # each record a triaxial sensor's CSV
        _csv(tmp_path / "data" / f"{name}.csv")
    text = path.read_text().replace('vibration = 0\ntacho = "2"', 'vibration = "acc_x"\ntacho = "tacho_V"')
    path.write_text(text.replace(".zip", ".csv").replace("pulses_per_rev = 10", "").replace("fs = ", "# fs = "))
    code, _, err = cli("validate", path)
    line = err.strip()
    assert code == 2 and "key 'vibration'" in line and "(a vibration channel: ax_g, ay_g, az_g?)" in line, err
