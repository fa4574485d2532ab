"""The transfer benchmark's correction rule (gearlab.kinds.transfer_benchmark.read_off_history): of what
a diagnosis fitted, the corrected source keeps the model and excitation effects and leaves out what the
recipe reads off the target history itself -- noise, and the rest of the signal level (a sensor's
resonance or low-pass, an offset), which its path and residual take from the same rows."""

from __future__ import annotations

from pathlib import Path

import pytest

from gearlab.engine import load_scenario
from gearlab.kinds import transfer_benchmark as tb
from gearlab.registry import get_registry

NOISE = ["sensor_noise", [["kind", "gaussian"], ["snr_db", 1.0]]]
LOWPASS = ["sensor_lowpass", [["f_c", 2031.0], ["order", 1]]]  # a stand-in: the target's was 7.1 kHz, order 3
RESONANCE = ["sensor_bandwidth", [["f_n", 2083.0], ["zeta", 0.41]]]
BEARINGS = ["bearing_stiffness", [["c_factor", 0.45], ["k_factor", 0.5]]]
INERTIAS = ["drive_inertias", [["I11", 1.4e-3], ["I22", 5.5e-5], ["c_c", 88.0], ["k_c", 7775.0]]]


@pytest.fixture(scope="module")
def source():
    spec = load_scenario(Path(__file__).parents[1] / "scenarios" / "transfer_benchmark.toml").spec
    return tb.trials(spec)[0][1]


def kept(source, *fitted, verdict="explained", **record) -> list[str] | None:
    """The effects the corrected source of a record with *fitted* adds (None: the plain source itself)."""
    fixed = tb.corrected_spec(
        source, {"trial": "trial004", "verdict": verdict, "corrected_effects": list(fitted), **record}
    )
    return None if fixed is source else sorted(name for name, _ in fixed.effects if (name, _) not in source.effects)


def test_model_effects_kept_sensor_filters_and_noise_left_to_the_recipe(source):
    # seed 1325, trial 4: a 2 kHz low-pass standing in for the target's, bearings for its drive
    assert kept(source, LOWPASS, NOISE, BEARINGS) == ["bearing_stiffness"]
    assert kept(source, RESONANCE, NOISE, INERTIAS, BEARINGS) == ["bearing_stiffness", "drive_inertias"]
    # partly explained above the share that applies it: the same rule
    assert kept(source, RESONANCE, NOISE, INERTIAS, verdict="partly explained", explained_share=0.9999) == [
        "drive_inertias"
    ]


def test_a_sensor_alone_leaves_the_plain_source(source):
    assert kept(source, RESONANCE, NOISE) is None
    assert kept(source, LOWPASS) is None
    assert kept(source, NOISE) is None


def test_what_the_recipe_reads_off_the_history_is_the_signal_level():
    registry = get_registry()
    for name in registry.names("effect"):
        effect = registry.get("effect", name)
        why = tb.read_off_history(name)
        if effect.noise:
            assert why == "noise"
        else:
            assert (why == tb.SIGNAL_WHY) == (effect.level == "signal"), name
    assert tb.read_off_history("drive_inertias") == tb.read_off_history("mesh_damping") == ""
    assert tb.read_off_history("sensor_lowpass") == tb.read_off_history("sensor_bandwidth") == tb.SIGNAL_WHY


def test_the_table_says_why_each_was_left_out():
    record = {
        "effects": [{"name": n, "params": {}} for n, _ in (LOWPASS, NOISE, BEARINGS)],
        "left_out": [{"name": "sensor_lowpass", "why": tb.SIGNAL_WHY}, {"name": "sensor_noise", "why": "noise"}],
    }
    assert tb.fitted_text(record).endswith(f"left out: sensor_lowpass ({tb.SIGNAL_WHY}), sensor_noise (noise)")
