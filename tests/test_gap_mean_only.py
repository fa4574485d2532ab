"""An effect that adds only a constant (sensor_offset, Effect.mean_only) is invisible to the gap
diagnosis, which compares each record without its mean: the source's rows with a 30 m/s² offset are
the rows without it. So no diagnosis takes it as a candidate (it was tried on the PHM 2009 records,
where it could remove nothing): one line at validate time; a simulated dataset may still carry it."""

import numpy as np
import pytest

from gearlab.data.spec import dataset_preset
from gearlab.effects import default_candidates, effect_spec
from gearlab.errors import GearlabInputError
from gearlab.gap import scoring
from gearlab.registry import get_registry

SOURCE = dataset_preset("B-6-ch5").with_(healthy=12)


def test_a_constant_leaves_the_compared_rows_as_they_are():
    offset = SOURCE.with_(effects=(effect_spec("sensor_offset", offset=30.0),))
    np.testing.assert_allclose(scoring.Rows()(offset), scoring.Rows()(SOURCE), atol=1e-9)


def test_no_diagnosis_takes_it():
    registry = get_registry()
    assert "sensor_offset" not in default_candidates(registry)
    with pytest.raises(GearlabInputError, match=r"candidate #2: 'sensor_offset' adds only a constant"):
        scoring.check_settings(scoring.Settings(candidates=("sensor_noise", "sensor_offset")))


def test_validate_refuses_it_as_a_candidate(cli, tmp_path):
    scenario = tmp_path / "g.toml"
    scenario.write_text(
        '[scenario]\nname = "g"\nkind = "gap"\n[source]\npreset = "B-6-ch5"\n'
        '[target]\npreset = "B-6-ch5"\n'
        '[diagnosis]\ncandidates = ["sensor_offset", "sensor_noise"]\n'
    )
    got, out, err = cli("validate", scenario)
    lines = [line for line in err.splitlines() if line.strip()]
    assert got == 2 and len(lines) == 1, (out, err)
    assert "[diagnosis] key 'candidates'" in lines[0] and "'sensor_offset'" in lines[0] and "g.toml" in lines[0], err
    scenario.write_text(scenario.read_text().replace('"sensor_offset", ', ""))
    assert cli("validate", scenario)[0] == 0  # the same scenario without it
