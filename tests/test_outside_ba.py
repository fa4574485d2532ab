"""A true description must match where a shaft's comb of two or three lines reads its spacing from a line off the
described comb (issue 39, gearbox.sideband_combs.on_described). On the PHM 2009 rig's spur3 at 40 Hz, high load,
channel 1, the output shaft's first sideband of the 2nd mesh lies on the described spacing (0.2 = 32/96 x 48/80)
and a line 2.3 bins off its 3rd (another line's sideband of the idler) pulled the fitted spacing to 0.1957: 'the
wheel on the output shaft shows 81.8 ± 0.5 teeth, 80 described' of the rig's own description."""

from __future__ import annotations

from pathlib import Path

import pytest

PHM = Path(__file__).resolve().parents[2] / "shared" / "data" / "phm09"


@pytest.mark.skipif(not PHM.is_dir(), reason="the PHM 2009 records are not in ../shared")
@pytest.mark.parametrize("record", ["spur3_40hz_High_1", "spur3_40hz_High_2"])
def test_phm_output_wheel_read_on_its_described_comb(record):
    from gearlab.gearbox import resolve_gearbox
    from gearlab.inspect import InspectOptions, inspect_record

    options = InspectOptions(vibration="1", tacho="2", pulses_per_rev=10, fs=66666.67)
    report = inspect_record(str(PHM / f"{record}.zip"), resolve_gearbox("phm09"), options)
    assert report["matches"] is True, report["verdict"]
    assert "output shaft shows" not in report["verdict"], report["verdict"]
