"""The keys of a measured recording (file, files, vibration, tacho, pulses_per_rev, speed, fs, gearbox,
sensitivity, gain, transient) are declared once (gearlab.kinds.common.MEASURED, issue 38 item 3):
every kind's table that takes one has its type, wording, unit and bounds, and refuses a bad value
with the same one-line error when the file is read (`gearlab validate`)."""

import pytest

from gearlab.errors import GearlabInputError
from gearlab.kinds import SCENARIO_KINDS
from gearlab.kinds.common import MEASURED
from gearlab.scenario import validate_table

# Tables whose key of a measured key's name means something else: detection's [corrected] gearbox is
# the corrected simulator's description (a gap run's gearbox_corrected.toml), read no recording.
NOT_MEASURED = {("detection", "corrected")}


def measured_tables():
    """(kind, table name, Table) of every table with a measured-data key."""
    return [
        (kind, name, table)
        for kind, module in SCENARIO_KINDS.items()
        for name, table in module.TABLES.items()
        if set(table.keys) & set(MEASURED) and (kind, name) not in NOT_MEASURED
    ]


def test_the_tables_left_out_hold_no_other_measured_key():
    for kind, name in NOT_MEASURED:
        assert set(SCENARIO_KINDS[kind].TABLES[name].keys) & set(MEASURED) == {"gearbox"}, (kind, name)


def test_every_table_declares_a_measured_key_alike():
    seen: dict = {}
    for kind, name, table in measured_tables():
        for key in set(table.keys) & set(MEASURED):
            k = table.keys[key]
            shape = (k.types, k.doc, k.unit, getattr(k.check, "setting", None))
            assert seen.setdefault(key, shape) == shape, (kind, name, key)
    # the dataset, transfer, gap and detection kinds read recordings through them
    tables = {(kind, name) for kind, name, _ in measured_tables()}
    assert {("dataset", "datasets"), ("transfer", "target"), ("gap", "target"), ("detection", "target")} <= tables
    assert set(seen) == set(MEASURED)


BAD = [
    ("fs", "20 MHz", "'20 MHz' is outside (0 Hz, 10 MHz]"),
    ("fs", -1, "expected a positive value, got -1"),
    ("speed", "2 kHz", "expected an input-shaft speed up to 1 kHz"),
    ("gain", "0 V", "expected a positive voltage per file unit such as '0.3 mV', got '0 V'"),
    ("sensitivity", "100", "is no accelerometer's sensitivity"),
    ("transient", "stat", "'stat' is not one of stats, none"),
    ("vibration", -1, "a column index is 0 or more, got -1"),
    ("tacho", -2, "a column index is 0 or more, got -2"),
    ("pulses_per_rev", 0, "0 is outside [1, 10000]"),
]


@pytest.mark.parametrize(("key", "value", "said"), BAD, ids=[f"{k}={v}" for k, v, _ in BAD])
def test_a_bad_measured_key_is_one_error_in_every_table(key, value, said):
    errors = {}
    for kind, name, table in measured_tables():
        if key not in table.keys:
            continue
        given = {"vibration": "acc", "files": [], key: value}
        with pytest.raises(GearlabInputError) as caught:
            validate_table("s.toml", name, table, {k: v for k, v in given.items() if k in table.keys})
        text = str(caught.value)
        assert f"key '{key}': " in text and "\n" not in text, (kind, name, text)
        errors[(kind, name)] = text.split(f"key '{key}': ", 1)[1]
    assert len(errors) >= 3 and len(set(errors.values())) == 1, errors
    assert said in next(iter(errors.values()))


def test_a_benchmark_source_takes_no_measured_file_key():
    # a simulated [source] given 'takes' or 'pulses_per_rev' would ignore it silently: not its keys
    from gearlab.kinds.common import MEASURED_ONLY, SOURCE_KEYS

    assert {"takes", "pulses_per_rev"} <= set(MEASURED_ONLY)
    assert not set(MEASURED_ONLY) & set(SOURCE_KEYS)
