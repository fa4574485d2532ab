"""A tone's line taken out of what the other effects are scored on (gearlab/gap/lines.py, Rows.line).

A target like development trial 901/21 of the transfer benchmark: a stiffer bearing behind a 6.2 kHz 3-pole
low-pass, beside a 340 Hz tone and noise. Against the whole rows, a filter and a model effect scored beside
no tone (or a tone at another level) miss the line; with each row's sinusoid at the line's order taken out of
the target and of every set, the true pair scores near 0 and far below the low-pass alone."""

import numpy as np
import pytest

from gearlab.data.builder import build_dataset
from gearlab.data.spec import NoiseSpec, dataset_preset
from gearlab.effects import effect_spec
from gearlab.gap.diagnose import Settings, _prepared
from gearlab.gap.lines import TONE, tone_line
from gearlab.gap.scoring import Scorer, _by_level
from gearlab.gap.views import healthy_rows, without_line

pytestmark = pytest.mark.filterwarnings("ignore::UserWarning")  # the simulator's accuracy warnings on odd parameters

SPEED = 30.375
SOURCE = dataset_preset("B-6-ch5").with_(faults=(), healthy=40, speed_hz=SPEED)
MODEL = (
    effect_spec("bearing_stiffness", k_factor=2.78, c_factor=1.05),
    effect_spec("sensor_lowpass", f_c=6183.0, order=3),
)
LOAD = 11.8  # N m, the source's 20: each set scored at this scale of its rows (gearlab.gap.level)


def prepared(effects: tuple):
    target = SOURCE.with_(effects=effects, load_nm=LOAD, noise=NoiseSpec("gaussian", 2.9, 5), seed=21)
    return _prepared(SOURCE, healthy_rows(build_dataset(target)), Settings(healthy=40, seed=0), None)


def test_the_tones_line_is_found_and_taken_out_and_the_true_pair_then_scores_below_the_filter_alone():
    target, _, rows, settings, pair, search, fresh = prepared(MODEL + (effect_spec(TONE, frequency=340.1, ratio=0.44),))
    order = tone_line(target, rows(fresh), settings, (TONE, "sensor_noise"))
    assert order == pytest.approx(340.1 / SPEED, abs=0.01)
    assert tone_line(target, rows(fresh), settings, ("sensor_noise",)) == 0.0  # the tone no candidate: no line

    def best(effects: tuple, line: float) -> float:
        """The score of the source with *effects*, beside noise at its best level (the search's nuisance)."""
        here = rows.__class__(load=LOAD / SOURCE.load_nm, line=line)
        scorer = Scorer(without_line(target, line), pair, settings.max_order)
        return min(
            scorer.score(here(search.with_(effects=_by_level(search.effects + effects + (noise,)))))
            for noise in (effect_spec("sensor_noise", kind="gaussian", snr_db=s) for s in np.arange(-8.0, 6.0, 0.5))
        )

    assert best(MODEL, order) < 0.01 * best(MODEL[1:], order)  # the line out: the pair far below the low-pass alone
    assert best(MODEL, order) < 0.01 * best(MODEL, 0.0)  # ... and below itself scored against the whole rows


def test_a_target_without_a_tone_holds_no_line():
    target, _, rows, settings, *_, fresh = prepared(MODEL)
    assert tone_line(target, rows(fresh), settings, (TONE, "sensor_noise")) == 0.0
