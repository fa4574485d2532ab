"""Issue 41: a noise study's Bayes bound is a stage with counts and an ETA. It was one log line
('the Bayes bound of ...: its noise-free twin and the class likelihoods') and then nothing: 6.8 s
of a tiny study at load 8 (tests/tui_scenarios/tnoise.toml), minutes for chapter 4's Student-t
sets, which class_bound sums elementwise."""

import numpy as np
import pytest
from test_noise_study import small_spec, synthetic

from gearlab.kinds import noise_study as kind
from gearlab.learn.bounds import class_bound, class_bound_steps
from gearlab.learn.noise_study import NoiseProtocol


@pytest.mark.parametrize("law", ["gaussian", "student_t"])
def test_class_bound_says_each_block_of_rows_and_class_and_predicts_the_same(law):
    data = synthetic(small_spec())
    clean = synthetic(small_spec(noise=None))
    label = np.asarray(data.label)
    steps = []
    pred = class_bound(data.X, clean.X, label, law, chunk=40, on_step=steps.append)
    assert class_bound_steps(label, chunk=40) == 5 * 5  # 5 classes x 192 rows in blocks of 40
    assert steps == list(range(1, 26))
    assert np.array_equal(pred, class_bound(data.X, clean.X, label, law, chunk=40))


def test_the_noise_studys_bound_is_a_stage_that_counts_to_its_end(monkeypatch):
    monkeypatch.setattr(kind, "load_or_build", lambda spec, executor=None, on_event=None: (synthetic(spec), False))
    spec = small_spec()
    data, events = synthetic(spec), []
    bound = kind.bayes_bound(data, spec, NoiseProtocol(runs=2), None, events.append)
    (stage,) = [e for e in events if e.kind == "stage"]
    assert stage.total == 2 + class_bound_steps(data.label) and spec.name in stage.message
    done = [e.done for e in events if e.kind == "advance" and e.stage == stage.stage]
    assert done == list(range(1, stage.total + 1))
    assert bound == kind.bayes_bound(data, spec, NoiseProtocol(runs=2))  # the same numbers as before
