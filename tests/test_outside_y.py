"""An outside user's leftovers (issue 39 item 4 and "How it will be checked"): every share a gap run prints
says which fit it comes from, the ranking's header says the noise fitted beside each candidate, and
`gearlab score` without a tacho on a record of another gearbox says that the tooth counts may differ. The
records here are small stand-ins written by hand, not simulated by gearlab."""

from __future__ import annotations

import numpy as np
import pytest

from gearlab.errors import GearlabInputError


def test_the_round_s_progress_line_says_which_fit_its_share_is_of():
    # an outside lab's 24/83 box: 'gap: round 1: sensor_noise removes 97.8 % of the gap left (accepted)' beside
    # the verdict's 98.2 % (round 1's search) and the summary's 98.8 % (final fit): three shares, one unnamed
    from gearlab.gap.diagnose import round_line

    line = round_line(1, "sensor_noise", 0.978, True)
    assert (
        line
        == "gap: round 1: sensor_noise removes 97.8 % of the gap left, at round 1's fit on fresh revolutions (accepted)"
    )
    assert round_line(2, "sensor_bandwidth", 0.081, False).endswith(
        "at round 2's fit on fresh revolutions (not accepted)"
    )


def test_the_ranking_s_header_says_the_noise_fitted_beside_each_candidate():
    # '(round-1 fit, alone)' read as 'without sensor noise', where every other candidate had it beside it
    from gearlab.kinds.gap_tables import ranking_md

    ranking = [
        {"name": "sensor_bandwidth", "share_removed": 0.984, "params": {"f_c": 3100.0}},
        {"name": "sensor_noise", "share_removed": 0.981, "params": {"snr_db": 9.9}},
    ]
    head = ranking_md(ranking, []).splitlines()[0]
    assert "alone" not in head, head
    assert "| parameters (round-1 fit, sensor noise fitted beside each other effect) |" in head, head
    # sensor noise no candidate (a user's list without it): nothing beside them
    assert "| parameters (round-1 fit) |" in ranking_md(ranking[:1], []).splitlines()[0]


def _tone(tmp_path):
    # one strong line and noise: 500 Hz fits 23 teeth at 21.7 Hz or 19 at 26.3 Hz about equally
    n, fs = 40000, 5000.0
    x = np.cos(2 * np.pi * 500 * np.arange(n) / fs) + np.random.default_rng(1).normal(0, 0.1, n)
    path = tmp_path / "tone.npz"
    np.savez(path, acc=x, fs=fs)
    return path


def test_an_ambiguous_speed_of_a_record_read_against_a_description_points_to_inspect(tmp_path):
    # `gearlab score` without a tacho stopped at 'the speed is ambiguous ...; expected a declared speed ... or a
    # tacho channel' on a record of another gearbox: the tooth counts, the likelier cause there, went unsaid
    from test_inspect import described

    from gearlab.data.recordings import cut_recording
    from gearlab.inspect import InspectOptions, inspect_record

    path = _tone(tmp_path)
    box = described((23, 41), (19, 67))
    with pytest.raises(GearlabInputError) as err:
        cut_recording(str(path), vibration="acc", gearbox=box)
    said = str(err.value)
    assert "the speed is ambiguous without a tacho" in said and "\n" not in said, said
    hint = (
        f"(or the record's tooth counts differ from {box.name}'s, another gearbox's: gearlab inspect {path} --gearbox"
    )
    assert said.endswith(f"{hint} box.toml names them)"), said
    # inspect itself does not point to itself
    with pytest.raises(GearlabInputError) as own:
        inspect_record(str(path), box, InspectOptions())
    assert "--gearbox" not in str(own.value) and "the speed is ambiguous" in str(own.value)
