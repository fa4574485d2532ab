"""A detector built on a [corrected] source with sensor noise takes its fault shapes from the source's
noise-free twin (gearlab.kinds.detection_units.noise_free_twin), not from the noisy samples.

A simulated chip's shape is small against the sensor noise the corrected simulator adds: on a
20/30 + 20/50 reducer's output gear (chip step 12, 25 dB, TSAs of 10 output revolutions, 16 draws)
the mean of a sample's 16 draws was as much noise as shape (cosine 0.71 to its noise-free shape),
and the corrected likelihood_ratio and matched_filter detected 26 and 28 % of the chipped record10
units against the plain detectors' 43 and 44 % (dev seeds 101-109); with the noise-free shapes 43
and 44 %."""

import numpy as np
from detection_scenario import run, scenario


def _corrected_run(cli, folder, snr_db: float) -> None:
    corrected = (
        '[corrected]\nlabel = "noisy"\ntsa = 3\ndraws = 3\n'
        f'effects = [{{ name = "sensor_noise", kind = "gaussian", snr_db = {snr_db} }}]\n'
    )
    folder.mkdir()
    run(cli, scenario(folder, methods=("matched_filter",), extra=corrected), folder / "runs")


def test_the_corrected_detectors_shapes_hold_no_sensor_noise(cli, tmp_path, module_cache, monkeypatch, no_figures):
    """The same corrected source at 20 and at 30 dB: its detector's shapes are the same rows (the
    noise-free twin's); before, each sample's mean over its noise draws, which differ with the noise."""
    import gearlab.api as api

    shapes = []
    statistic = api.template_statistic

    def spy(Xs, ys, *args, **kwargs):
        shapes.append(np.array(Xs, copy=True))
        return statistic(Xs, ys, *args, **kwargs)

    monkeypatch.setattr(api, "template_statistic", spy)
    _corrected_run(cli, tmp_path / "a", 20.0)
    low = shapes[:]  # the plain source's detector's shapes, then the corrected one's
    _corrected_run(cli, tmp_path / "b", 30.0)
    high = shapes[len(low) :]
    assert len(low) == len(high) == 2
    assert np.array_equal(low[0], high[0])  # the plain source's: no noise in either
    assert low[1].ndim == 2 and np.array_equal(low[1], high[1])
