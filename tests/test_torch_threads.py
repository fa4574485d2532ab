"""An in-process run (the TUI's, a notebook's, gearlab.api's) leaves torch on the caller's thread count: each
training unit runs on one torch thread (a result does not depend on how many run side by side), and every kind's
train_unit set it with torch.set_num_threads(1) and left it there, the caller's later torch work on one core."""

from __future__ import annotations

from types import SimpleNamespace

import pytest
import torch

from gearlab.kinds import detection_units, noise_study
from gearlab.learn.protocol import Method
from gearlab.parts import training

CALLER = 3  # the caller's count: not torch's default, not the one thread of a unit


@pytest.fixture
def caller_threads():
    before = torch.get_num_threads()
    torch.set_num_threads(CALLER)
    yield
    torch.set_num_threads(before)


def test_a_detection_unit_trains_on_one_thread_and_leaves_the_caller_s(caller_threads, tmp_path, monkeypatch):
    # the matched filter's unit of test_threshold_few_takes, trained and scored in this thread (an in-process
    # executor's: gearlab.run_scenario's units run on a thread of their own, whose count is that thread's)
    from test_threshold_few_takes import called

    inside = []
    train_method = detection_units.chapter5.train_method

    def counted(*args, **kwargs):
        inside.append(torch.get_num_threads())
        return train_method(*args, **kwargs)

    monkeypatch.setattr(detection_units.chapter5, "train_method", counted)
    healthy, chipped = called(0, tmp_path, left_out=False)
    assert inside == [1] and chipped > 0.5, (inside, chipped)  # it trained, on one thread, and found the chips
    assert torch.get_num_threads() == CALLER


def _units(monkeypatch, module, *steps: str) -> list:
    """The thread counts *module*'s unit trains on: its *steps* (module attributes) record it and return {}."""
    inside = []

    def step(*args, **kwargs):
        inside.append(torch.get_num_threads())
        return {}

    for name in steps:
        monkeypatch.setattr(module, name, step)
    return inside


def test_a_transfer_unit_leaves_the_caller_s_thread_count(caller_threads, monkeypatch, tmp_path):
    inside = _units(monkeypatch, training, "loaded", "run_unit")
    method = Method("source_only", False)
    training.train_unit((None, (None, None), (None, None), 0, 0, method, SimpleNamespace(root=tmp_path)))
    assert inside == [1, 1, 1]  # both datasets read and the training, on one thread
    assert torch.get_num_threads() == CALLER


def test_a_noise_study_unit_leaves_the_caller_s_thread_count(caller_threads, monkeypatch, tmp_path):
    inside = _units(monkeypatch, noise_study, "run_unit")
    monkeypatch.setattr(noise_study.cache, "load", lambda *args: None)
    noise_study.train_unit((None, None, None, None, None, "gaussian", 0, "noisy", tmp_path))
    assert inside == [1]
    assert torch.get_num_threads() == CALLER
