"""A gear's name written among a fault's steps is answered with the key that names the gear.

docs/your_gearbox.md names a fault's gear in its key ("chip@intermediate pinion" = [18, 20]); a user who wrote
broken_tip = ["intermediate gear", 12, 16, 20] was told only "'broken_tip' must map to a list of ladder steps".
"""

import pytest

from gearlab.data.placement import canonical_faults
from gearlab.errors import GearlabInputError

SHAFTS = ("input", "intermediate", "output")


def test_a_gear_among_the_steps_is_answered_with_the_gear_key():
    with pytest.raises(GearlabInputError) as got:
        canonical_faults({"broken_tip": ["intermediate gear", 12, 16, 20]}, SHAFTS, "d.toml: [source]")
    assert str(got.value) == (
        "d.toml: [source] key 'faults': 'broken_tip' must map to a list of ladder steps, got "
        "['intermediate gear', 12, 16, 20] (on a gear: \"broken_tip@intermediate gear\" = [12, 16, 20])"
    )


def test_steps_that_are_no_list_say_so_alone():
    with pytest.raises(GearlabInputError) as got:
        canonical_faults({"chip": 20}, SHAFTS, "d.toml: [source]")
    assert str(got.value).endswith("must map to a list of ladder steps, got 20")
