"""Small items of issue 39's outside-user check (one line naming file, table and key; exit 2)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from gearlab.errors import GearlabInputError
from gearlab.gearbox import speed_hz
from gearlab.notebook import inspect_options
from gearlab.parts.measured import speed_of

BARE = "(a bare number is in Hz; expected a speed with its unit, e.g. '35 Hz' or '2100 rpm')"


def test_a_bare_speed_meant_in_rpm_is_refused_alike_by_inspect_and_the_scenario_keys(tmp_path, cli):
    # inspect's --speed is the [target] key 'speed' (an input-shaft speed up to 1 kHz; a number in Hz)
    for check in (lambda v: inspect_options(speed=v).speed_hz, lambda v: speed_of(v, "t.toml: [target] key 'speed'")):
        for bare in ("2100", 2100):
            with pytest.raises(GearlabInputError, match=r"up to 1 kHz.*2100'? " + re.escape(BARE)):
                check(bare)
        assert check("2100 rpm") == pytest.approx(35.0)
        assert check("35") == check(35) == 35.0  # a bare number in range is Hz, as before
        with pytest.raises(GearlabInputError) as said:
            check("2 kHz")
        assert "bare number" not in str(said.value)  # a speed with its unit is not told about bare numbers
    with pytest.raises(GearlabInputError, match=r"got 200000 \(a bare number is in Hz"):
        speed_hz(200000, "g.toml: [operation] key 'speed'")
    path = tmp_path / "rec.csv"
    np.savetxt(path, np.c_[np.sin(np.arange(2000) * 0.3)], header="acc", comments="# fs = 5000\n")
    code, _, err = cli("inspect", path, "--speed", "2100")
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert err.startswith("error: --speed: ") and "'2100 rpm'" in err


def test_the_gaps_stop_for_an_unconfirmed_speed_names_the_scenario_file(tmp_path):
    """A declared speed that no history record's mesh lines confirm stops the gap with a line naming
    the scenario file, table and key, as the gap's other refusals do (the records read by stand-ins:
    the line is the test's subject, not the mesh lines)."""
    from dataclasses import replace
    from types import SimpleNamespace

    from gearlab.data.recordings import UNCONFIRMED
    from gearlab.engine import load_scenario
    from gearlab.kinds.gap_inputs import read_history

    t = np.arange(4000) / 4000.0
    np.savetxt(tmp_path / "h.csv", np.c_[np.sin(2 * np.pi * 400 * t)], header="acc", comments="# fs = 4000\n")
    path = tmp_path / "gap.toml"
    path.write_text(
        '[scenario]\nname = "g"\nkind = "gap"\n\n[source]\npreset = "phm09-30"\n\n'
        '[target]\nvibration = "acc"\nspeed = "35 Hz"\n'
        'files = [{ path = "h.csv", role = "history", label = "healthy" }]\n'
    )
    records = load_scenario(path).spec.target
    assert records.where == f"{path}: [target]"
    file = SimpleNamespace(path="h.csv", role="history")
    read = SimpleNamespace(
        revolutions=np.zeros((3, 8)), speed_hz=35.0, angle_source=f"declared, {UNCONFIRMED}: x", warnings=()
    )
    stub = SimpleNamespace(files=(file,), tacho=None, marks=1, read=lambda f: read)
    with pytest.raises(GearlabInputError) as said:
        read_history(replace(records, target=stub), lambda event: None)
    assert str(said.value).startswith(f"{path}: [target] key 'speed': 35 Hz declared, but no history record")


def test_inspect_with_a_gearbox_names_its_gears_as_a_faults_key_takes_them(tmp_path, cli):
    """docs/your_gearbox.md: faults go on a gear 'as inspect names it'; inspect --gearbox says those names."""
    import json

    from gearlab.data.placement import resolve_gear
    from gearlab.gearbox import resolve_gearbox

    fs, speed = 20000.0, 30.0
    t = np.arange(int(2 * fs)) / fs
    theta = 2 * np.pi * speed * t
    acc = np.sin(32 * theta) + 0.3 * np.sin(32 * 48 / 80 * theta) + 0.01 * np.sin(7 * t)
    tacho = (np.mod(theta, 2 * np.pi) < 0.5).astype(float)
    path = tmp_path / "rec.csv"
    np.savetxt(path, np.c_[acc, tacho], delimiter=",", header="acc_ms2,tacho", comments=f"# fs = {fs:g}\n")
    args = ("inspect", path, "--gearbox", "phm09", "--vibration", "acc_ms2", "--tacho", "tacho")
    code, out, err = cli(*args, "--json")
    assert code == 0, err
    gears = json.loads(out)["gears"]
    names = ["input pinion", "idler gear", "idler pinion", "output gear"]
    assert [(g["name"], g["teeth"]) for g in gears] == list(zip(names, (32, 96, 48, 80)))
    shafts = resolve_gearbox("phm09").shafts
    assert [resolve_gear(g["name"], None, shafts, "w") for g in gears] == [(g["stage"], g["gear"]) for g in gears]
    code, out, err = cli(*args)
    assert code == 0, err
    said = " ".join(out.split())
    assert 'faults key names them (e.g. "chip@input pinion"): input pinion 32T (stage 1), idler gear 96T' in said
    assert "output gear 80T (stage 2)" in said
