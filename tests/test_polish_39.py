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
