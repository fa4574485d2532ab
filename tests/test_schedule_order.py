"""A phase's units go to the pool longest first (issue 42): the short ones fill in behind the
long ones, ties keep their order."""

from gearlab.learn.schedule import longest_first


def test_long_units_first_ties_in_order():
    units = ["a1", "b9", "c1", "d9", "e0", "f1"]
    assert longest_first(units, lambda u: int(u[1])) == ["b9", "d9", "a1", "c1", "f1", "e0"]
