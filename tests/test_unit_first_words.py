"""Issue 41: a detection or noise-study training unit says what it does from its start. It loaded
torch (seconds in a fresh worker) and its data before its first line: tests' tiny detection
scenario in a 100-column pty stood 5.7 s on '3 trainings 0/3 ETA after the first step' with no
line under it until '16 Hz/mmd-unsup: priming, epoch 1 of 2'."""

from types import SimpleNamespace

import numpy as np
import pytest

from gearlab.kinds import detection_units, noise_study


class Stop(Exception):
    """Raised where the unit would train: what it said before is what is checked."""


def recorder(said: list):
    class Recorder:
        def __init__(self, root, unit):
            said.append(f"open {unit}")

        def __enter__(self):
            return said.append

        def __exit__(self, *exc):
            return False

    return Recorder


def stop(*args, **kwargs):
    raise Stop


def test_a_detection_unit_says_it_is_starting_before_torch_and_its_training(monkeypatch, tmp_path):
    said = []
    monkeypatch.setattr(detection_units, "UnitProgress", recorder(said))
    monkeypatch.setattr(detection_units, "aligned_to_a_point", lambda *args: False)
    monkeypatch.setattr(detection_units.chapter5, "train_method", stop)
    method = SimpleNamespace(key="mmd-unsup", adapter="mmd", is_detector=False)
    rows = np.zeros((2, 8))
    task = (SimpleNamespace(device="cpu"), method, "", "16 Hz", None, None, (rows, None, rows, None), rows, {}, {})
    with pytest.raises(Stop):
        detection_units.train_unit((*task, SimpleNamespace(root=tmp_path), None, False, None))  # no left_out
    assert said[:2] == ["open 16 Hz/mmd-unsup", "starting: importing torch"]


def test_a_noise_study_unit_says_it_is_starting_before_torch_and_its_data(monkeypatch, tmp_path):
    said = []
    monkeypatch.setattr(noise_study, "UnitProgress", recorder(said))
    monkeypatch.setattr(noise_study.cache, "load", stop)
    with pytest.raises(Stop):
        noise_study.train_unit((None, None, None, None, None, "gaussian", 0, "noisy", tmp_path))
    assert said[0].startswith("open ") and said[1] == "starting: importing torch"
    assert said[2].startswith("starting: reading")
