"""gearlab.units reads common quantities from a table of pint's factors (issue 42: no registry at
start-up); each must give the float pint gives, bit for bit, and anything else still goes to pint."""

import random

import pytest

from gearlab import units
from gearlab.errors import GearlabInputError


def by_pint(text: str, unit: str, read=units._parse) -> float:
    """What *read* returns without the table."""
    saved = units._from_table
    units._from_table = lambda text, unit: None
    try:
        return read(text, unit, "here")
    finally:
        units._from_table = saved


def numbers(seed: int, n: int) -> list[str]:
    """Numbers as people write them: integers, decimals, exponents, with and without a space."""
    rng = random.Random(seed)
    texts = ["0", "1", "7", "0.5", ".25", "3.175", "1.", "2e8", "1E-3", "206e9", "12345678901234567890"]
    for _ in range(n):
        x = 10 ** rng.uniform(-6, 9)
        texts += [f"{x:.6g}", f"{x:.17g}", repr(x), f"{x:e}", str(rng.randint(1, 10**6))]
    return texts


@pytest.mark.parametrize("to", list(units.FACTORS))
def test_the_table_gives_what_pint_gives(to):
    for written, factor in units.FACTORS[to].items():
        assert units._ureg().Quantity(1, written).to(to).magnitude == factor, (written, to)
        for number in numbers(len(to) + len(written), 6):
            for text in (f"{number} {written}", f"{number}{written}", f"  {number}   {written} "):
                fast = units._from_table(text.strip(), to)
                assert fast is not None, text
                slow = by_pint(text, to)
                assert fast == slow and type(fast) is type(slow), (text, to, fast, slow)
        for text in (written, f"  {written} "):  # a bare unit: one of it, as pint reads it
            fast, slow = units._from_table(text.strip(), to), by_pint(text, to)
            assert fast == slow == factor and type(fast) is type(slow), (text, to, fast, slow)


@pytest.mark.parametrize(
    "text, unit",
    [("5", "m"), ("0.5", ""), ("1e3", "Hz"), (".5", "")],
)
def test_a_bare_number_is_read_as_pint_reads_it(text, unit):
    assert units._from_table(text, unit) == by_pint(text, unit) == float(text)


@pytest.mark.parametrize(
    "text, unit",
    [
        ("-3 mm", "m"),  # signed: pint's "-0" is an unsigned integer zero
        ("-0 mm", "m"),
        ("3 mm", ""),  # the wrong dimension: pint's message
        ("5 ft", "m"),  # a unit the table does not hold
        ("1e400 mm", "m"),  # an overflow: pint's words
        ("0x10 mm", "m"),
        ("05 mm", "m"),
        ("3 N m", "N*m"),
        ("20 degC", "K"),
    ],
)
def test_what_the_table_does_not_hold_goes_to_pint(text, unit):
    assert units._from_table(text, unit) is None
    try:
        expected = by_pint(text, unit, units.to_si)
    except GearlabInputError as exc:
        with pytest.raises(GearlabInputError) as got:
            units.to_si(text, unit, "here")
        assert str(got.value) == str(exc)
    else:
        assert units.to_si(text, unit, "here") == expected


def test_display_by_the_table_matches_pint():
    for to, row in units.FACTORS.items():
        for written in row:
            for value in (0.005, 1.0, 3.3e-7, 123456.0):
                fast = units.display(value, written, to)
                shown = units._ureg().Quantity(value, written).to(to).magnitude
                assert fast == f"{shown:.6g} {to}" or written == to


def test_a_scenario_quantity_builds_no_registry():
    """What validate reads: the table alone, no pint registry built (0.2-0.3 s)."""
    units._ureg.cache_clear()
    for text, unit in (("3.175 mm", "m"), ("20 deg", "rad"), ("25 Hz", "Hz"), ("10 mV/g_n", "V*s^2/m")):
        units.to_si(text, unit, "here")
    units.display(0.005, "m", "mm")
    assert units._ureg.cache_info().currsize == 0


def test_a_channel_named_for_its_unit_builds_no_registry():
    """A column named 'acc_gear_V' or 'acc [mV]' (channel_units.name_unit reads its unit bare): the table, as for a
    scenario's quantities; each process that read such a file built pint's registry (0.5-0.7 s of CPU with its
    import). A bare unit the table does not hold, or nothing, still goes to pint."""
    from gearlab.data.channel_units import name_unit

    units._ureg.cache_clear()
    assert name_unit("acc_gear_V") == ("voltage", "V", 1.0)
    assert name_unit("acc [mV]") == ("voltage", "mV", 0.001)
    assert units.to_si("Hz", "Hz", "here") == 1.0
    assert units._ureg.cache_info().currsize == 0
    assert units._from_table("", "V") is None and units._from_table("ft", "m") is None
