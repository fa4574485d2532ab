"""Outside-user check of issue 39 (helper CP): recordings made outside gearlab, read as docs/your_gearbox.md says
(small files written here, not simulated by gearlab)."""

from __future__ import annotations

import pytest

from gearlab.data.textzip import calibration, gain_quantity, parse_sensitivity

G = 9.80665


@pytest.mark.parametrize(
    "written, si, unit",
    [
        ("5g", 5 * G, "m/s^2"),  # a float WAV's full scale as a data sheet writes it
        ("2.5g", 2.5 * G, "m/s^2"),
        ("10g/V", 10 * G, "m/s^2/V"),
        ("1 mg", 1e-3 * G, "m/s^2"),  # integer counts of a milli-g each
        ("1mg", 1e-3 * G, "m/s^2"),
    ],
)
def test_a_gain_in_g_without_a_space_or_in_milli_g_is_read_as_gravity(written, si, unit):
    # '--gain 5g' was refused ('cannot read '5g' as a gain') while '--sensitivity 1V/g' was read: the 'g' after a
    # digit was taken as the gram; '1 mg' (milligram) too, though the gain's own help names counts of '1 mg'
    number, kind = gain_quantity(written, "--gain")
    assert kind == unit and number == pytest.approx(si)
    assert calibration({"gain": written}, lambda k: f"--{k}")["sensitivity"] > 0


def test_a_sensitivity_in_g_without_a_space_is_read_and_kilograms_stay_refused():
    assert parse_sensitivity("100mV/g", "--sensitivity") == pytest.approx(0.1 / G)
    assert parse_sensitivity("0.1V/g", "--sensitivity") == pytest.approx(0.1 / G)
    from gearlab.errors import GearlabInputError

    with pytest.raises(GearlabInputError, match="--gain"):
        gain_quantity("5 kg", "--gain")
