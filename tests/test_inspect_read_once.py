"""`gearlab inspect TAKE --history H...` reads the take once and, without a tacho, searches its speed once: the
localisation cuts its revolutions from the record and speed inspect's rows were read from (issue 42: both were
done twice, the search a take's dearest step), and says what it said when it read them itself. A take whose drift
inspect took out has its speed followed again on the record as read, as the localisation always followed it."""

from __future__ import annotations

import numpy as np
import pytest
from gearboxes import description, mesh_train, stage

from gearlab import inspect as I
from gearlab import inspect_history as IH
from gearlab.gearbox import load_gearbox
from gearlab.inspect import InspectOptions
from gearlab.notebook import inspect_recording

TEETH = ((19, 47),)  # one stage: each shaft one gear, no events simulated
FS, SPEED, SECONDS = 5000.0, 20.0, 6.0


def _take(path, seed: int, fault=None, drift: float = 0.0) -> str:
    """A take without a tacho at about SPEED; *drift*: a baseline rising by that many m/s² over the take."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(SECONDS * FS)) / FS
    theta = 2 * np.pi * SPEED * (1 - 0.01 * seed) * t
    x = mesh_train(theta, TEETH, rng, fault, noise=0.3, level=3.0, bump=0.8, width=0.5, second=0.5, third=0.25, phase=0)
    np.savez(path, acc=x + drift * t / SECONDS, fs=FS)
    return str(path)


@pytest.fixture(scope="module")
def box(tmp_path_factory):
    where = tmp_path_factory.mktemp("once")
    path = where / "once.toml"
    path.write_text(description(*(stage(*z) for z in TEETH), name="once", speed=f"{SPEED} Hz", near="input"))
    out = {"box": str(path), "history": [_take(where / f"h{k}.npz", k) for k in (1, 2, 3)]}
    out["take"] = _take(where / "take.npz", 4, fault=(0, "pinion", 5))
    out["drifting"] = _take(where / "drifting.npz", 4, fault=(0, "pinion", 5), drift=40.0)
    return out


@pytest.fixture
def counted(monkeypatch):
    """{"read": the take's read_record calls, "speed": its measured_speed calls} while the test runs."""
    seen = {"read": 0, "speed": 0}
    read, measured = I.read_record, I.measured_speed

    def reading(path, *args, **kwargs):
        seen["read"] += "take" in str(path) or "drifting" in str(path)
        return read(path, *args, **kwargs)

    def measuring(rec, *args, **kwargs):
        seen["speed"] += "take" in rec.path or "drifting" in rec.path
        return measured(rec, *args, **kwargs)

    for module in (I, IH):
        monkeypatch.setattr(module, "read_record", reading)
        monkeypatch.setattr(module, "measured_speed", measuring)
    return seen


@pytest.mark.parametrize("name, speeds", [("take", 1), ("drifting", 2)])
def test_inspect_with_a_history_reads_the_take_once_and_says_what_a_second_reading_says(
    box, counted, name, speeds, tmp_path, monkeypatch
):
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    report = inspect_recording(box[name], gearbox=box["box"], history=box["history"], vibration="acc")
    assert counted == {"read": 1, "speed": speeds}, counted
    assert report["speed"]["source"] != "declared", report["speed"]  # found from the mesh lines: searched
    assert ("baseline" in " ".join(report["flaws"])) == (name == "drifting"), report["flaws"]
    options, described = InspectOptions(vibration="acc"), load_gearbox(box["box"])
    again = IH.localisation(box[name], box["history"], described, options)  # the take read and followed again
    assert counted == {"read": 2, "speed": speeds + 1}, counted
    assert again == report["localisation"]
