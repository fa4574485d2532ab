"""The which-gear check's history and simulated events kept between calls (gearlab.data.which_gear_cache): a second
`gearlab inspect --history` of another take against the same history reads neither the history files nor simulates
the events again, says exactly what an uncached call says, and a changed history file or tooth count is read again."""

from __future__ import annotations

import json
import warnings

import pytest
from gearboxes import description, stage
from test_which_gear_parity import TEETH, take

HISTORY = ("h1", "h2", "h3")
# a load to simulate the events at: the intermediate shaft's two gears are told by them
KEYS = {"name": "kept", "speed": "20 Hz", "load": "30 N*m", "near": "input", "tacho": "output"}


@pytest.fixture(scope="module")
def box(tmp_path_factory):
    """{"box": the two-stage description, name: record}: three healthy takes, the intermediate pinion's (a two-gear
    shaft: its gear is told by the simulated events) and the output gear's damaged takes."""
    where = tmp_path_factory.mktemp("kept")
    path = where / "kept.toml"
    path.write_text(description(*(stage(*z) for z in TEETH), **KEYS))
    out = {"box": str(path), "where": where}
    for name, fault, seed, slip in (
        ("h1", None, 1, 0.012),
        ("h2", None, 2, 0.016),
        ("h3", None, 3, 0.010),
        ("pinion", (1, "pinion", 7), 5, 0.015),
        ("output", (1, "wheel", 30), 6, 0.013),
        ("calm", None, 7, 0.014),
    ):
        out[name] = take(where / f"{name}.npz", fault, seed, slip)
    return out


@pytest.fixture(autouse=True)
def two_kinds(monkeypatch):
    """The events of two fault kinds, not all five (which_templates.KINDS): the file's one uncached simulation of
    them is of the healthy run and each kind on each gear of the two-gear shaft, 5 runs, not 11 (the file's CPU 40
    -> 26 s, the means of three runs each on 2 busy cores). Two, so that an entry still holds several kinds per
    gear (events_arrays, events_of); the pinion is named by its own mesh's sidebands, the same with five kinds or two
    (z = 147, threshold 2.71)."""
    from gearlab.data import which_templates

    monkeypatch.setattr(which_templates, "KINDS", ("chip", "crack"))


@pytest.fixture
def counted(monkeypatch):
    """{"read": files read as revolutions, "simulated": events simulated} while the test runs."""
    from gearlab import inspect_history
    from gearlab.data import which_templates

    seen = {"read": [], "simulated": 0}
    read, simulate = inspect_history.input_revolutions, which_templates._revolutions

    def reading(path, *args, **kwargs):
        seen["read"].append(path)
        return read(path, *args, **kwargs)

    def simulating(*args):
        seen["simulated"] += 1
        return simulate.__wrapped__(*args)  # the process's own memo left out: each call simulates

    monkeypatch.setattr(inspect_history, "input_revolutions", reading)
    monkeypatch.setattr(which_templates, "_revolutions", simulating)
    return seen


def inspected(box, name, history=HISTORY, gearbox=None) -> dict:
    from typer.testing import CliRunner

    from gearlab.cli import app

    args = ["inspect", box[name], "--gearbox", gearbox or box["box"], "--vibration", "acc", "--tacho", "tacho"]
    for h in history:
        args += ["--history", box[h]]
    out = CliRunner().invoke(app, [*args, "--json"])
    assert out.exit_code == 0, out.output
    return json.loads(out.stdout)


def test_a_second_take_against_the_same_history_reads_it_from_the_cache_and_says_the_same(
    box, counted, tmp_path, monkeypatch
):
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    first = inspected(box, "pinion")
    assert len(counted["read"]) == 1 + len(HISTORY) and counted["simulated"] > 0, counted
    assert first["localisation"]["named"] == "intermediate pinion 23T (stage 2)", first["localisation"]["summary"]
    kept = sorted(p.name.split("-")[1] for p in (tmp_path / "cache").glob("which-*.npz"))
    assert "history" in kept and "events" in kept, kept
    counted["read"].clear()
    counted["simulated"] = 0
    again = inspected(box, "pinion")  # the history and the events from the cache: the take alone read
    assert counted["read"] == [box["pinion"]] and counted["simulated"] == 0, counted
    assert again == first  # every field, the history's thresholds, the envelope's and the residual's among them
    other, calm = inspected(box, "output"), inspected(box, "calm")  # calm: nothing synchronous, its envelope read
    assert counted["read"][:2] == [box["pinion"], box["output"]], counted
    # the same takes without the cache: equal, field by field
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "fresh"))
    assert inspected(box, "output") == other
    assert inspected(box, "calm") == calm


def test_a_history_file_written_again_or_another_tooth_count_is_read_again(box, counted, tmp_path, monkeypatch):
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    history = ("h1", "h2", "extra")
    box = dict(box) | {"extra": take(tmp_path / "extra.npz", None, 4, 0.011)}
    before = inspected(box, "output", history)
    counted["read"].clear()
    take(tmp_path / "extra.npz", None, 9, 0.014)  # another healthy take under the same name
    after = inspected(box, "output", history)
    assert len(counted["read"]) == 1 + len(history), counted  # read again, not the first content's
    assert after["localisation"]["shafts"] != before["localisation"]["shafts"]
    counted["read"].clear()
    other = tmp_path / "other.toml"  # the output gear one tooth more: another gearbox, another history
    stages = (stage(*TEETH[0]), stage(23, 42))
    other.write_text(description(*stages, **KEYS))
    inspected(box, "output", history, str(other))
    assert len(counted["read"]) == 1 + len(history), counted


def test_an_entry_that_cannot_be_read_is_computed_again(box, counted, tmp_path, monkeypatch):
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    first = inspected(box, "output")
    for entry in (tmp_path / "cache").glob("which-history-*.npz"):
        entry.write_bytes(b"not an npz")
    counted["read"].clear()
    assert inspected(box, "output") == first
    assert len(counted["read"]) == 1 + len(HISTORY), counted


def test_a_cached_history_says_again_what_its_files_first_reading_warned_of(box, tmp_path, monkeypatch):
    """A reader's note on a history file (a logger's footer left out, say) is printed by every call, not by the one
    that read the file alone."""
    from typer.testing import CliRunner

    from gearlab import inspect_history
    from gearlab.cli import app

    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    read = inspect_history.input_revolutions

    def noted(path, *args, **kwargs):
        if kwargs.get("history") and path == box["h2"]:
            warnings.warn(f"{path}: 3 footer lines left out", stacklevel=2)
        return read(path, *args, **kwargs)

    monkeypatch.setattr(inspect_history, "input_revolutions", noted)
    args = ["inspect", box["output"], "--gearbox", box["box"], "--vibration", "acc", "--tacho", "tacho"]
    args += [a for h in HISTORY for a in ("--history", box[h])]
    for _ in range(2):
        with pytest.warns(UserWarning, match="3 footer lines left out"):
            assert CliRunner().invoke(app, args).exit_code == 0
    assert list((tmp_path / "cache").glob("which-history-*.npz")), "the second call did not read the cache"


def test_simulated_events_read_back_are_the_events_kept_gear_by_gear_and_kind_by_kind():
    """events_of(events_arrays(made)) is made: each gear's events in their kinds' order (the cached events are
    compared by no test above, whose pinion its own mesh's sidebands name)."""
    import numpy as np

    from gearlab.data.which_gear_cache import events_arrays, events_of

    rng = np.random.default_rng(0)
    made = {"healthy": rng.normal(size=8), "gears": {g: [rng.normal(size=8) for _ in range(3)] for g in ("b", "a")}}
    back = events_of(events_arrays(made), 3)
    assert list(back["gears"]) == ["b", "a"]
    np.testing.assert_array_equal(back["healthy"], made["healthy"])
    for gear, kinds in made["gears"].items():
        assert len(back["gears"][gear]) == 3
        for kept, was in zip(back["gears"][gear], kinds, strict=True):
            np.testing.assert_array_equal(kept, was)
