"""One noise declaration: a dataset's `noise = {kind, snr_db, seed}` and the `sensor_noise` effect
are one noise (gearlab.signals.add_noise) at two places, declared with the same kinds and the
same SNR bounds; a value outside them is one line naming the file, the table and the key."""

import dataclasses

import pytest
from conftest import ROOT

from gearlab.data.spec import NoiseSpec
from gearlab.registry import get_registry
from gearlab.signals import NOISE_KINDS, SNR_DB_RANGE


def test_the_noise_table_and_the_effect_declare_the_same_kinds_and_bounds():
    fields = {f.name: f.metadata["setting"] for f in dataclasses.fields(NoiseSpec)}
    effect = get_registry().get("effect", "sensor_noise")
    (snr,) = [p for p in effect.params if p.name == "snr_db"]
    assert (fields["snr_db"].low, fields["snr_db"].high) == (snr.low, snr.high) == SNR_DB_RANGE
    assert tuple(fields["kind"].choices) == tuple(effect.options["kind"]) == NOISE_KINDS


@pytest.mark.parametrize("snr", [500, -40])
def test_a_noise_table_outside_the_bounds_is_one_line_exit_2(cli, write_scenario, snr):
    text = (ROOT / "scenarios" / "quick.toml").read_text()
    old = 'noise = { kind = "laplace", snr_db = 0.0, seed = 1 }'
    assert old in text
    bad = write_scenario(text.replace(old, f'noise = {{ kind = "laplace", snr_db = {snr}, seed = 1 }}'))
    code, _, err = cli("validate", bad)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1, err
    assert str(bad) in lines[0] and "[target] key 'noise': snr_db" in lines[0] and "[-20.0, 80.0]" in lines[0]


def test_the_bounds_themselves_are_accepted(cli, write_scenario):
    text = (ROOT / "scenarios" / "quick.toml").read_text()
    for snr in SNR_DB_RANGE:
        good = write_scenario(text.replace("snr_db = 0.0", f"snr_db = {snr}"))
        code, out, err = cli("validate", good)
        assert code == 0 and "OK" in out, err
