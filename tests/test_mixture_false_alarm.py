"""The size-and-sign mixture of `likelihood_ratio` (mixture = 1, gearlab.learn.detectors.SIZES):
its fit and threshold see no target test row or label."""

import pytest
from test_protocol import method
from test_protocol import test_target_test_samples_cannot_reach_training_stopping_or_selection as leak_check

from gearlab.learn.calibration import RECIPE


@pytest.mark.parametrize("supervised", [False, True], ids=["unsupervised", "supervised"])
def test_no_target_test_row_reaches_the_size_mixture(supervised, monkeypatch):
    """The leak check of every method (tests/test_protocol) for mixture = 1, which its METHODS
    leave out: its reference, noise law and threshold come from the target training rows alone."""
    leak_check(method("likelihood_ratio", supervised, mixture=1), RECIPE, "shapes", monkeypatch)
