"""An ambiguous speed raised in a worker process reaches the user as its one line.

A detection run reads its records in a process pool; AmbiguousSpeed (two speeds explain a record's mesh
lines, or its tooth counts are not the description's) crossed back by pickle, whose default rebuilds an
exception from its message alone: its unpickling failed ("missing 1 required positional argument:
'speeds'") and the run ended in BrokenProcessPool with a traceback, exit 1, where the line says what to do.
"""

import pickle
from concurrent.futures import ProcessPoolExecutor

import pytest

from gearlab.errors import GearlabInputError
from gearlab.gearbox.speed import AmbiguousSpeed


def _raise_ambiguous():
    raise AmbiguousSpeed("rec.csv: the speed is ambiguous (or a tooth count differs)", [8.4, 12.6], "rec.csv: head")


def test_ambiguous_speed_survives_pickle_with_its_speeds_and_head():
    exc = AmbiguousSpeed("a: the speed is ambiguous; hint", [8.425, 12.64], "a: the speed is ambiguous")
    back = pickle.loads(pickle.dumps(exc))
    assert isinstance(back, AmbiguousSpeed) and isinstance(back, GearlabInputError)
    assert str(back) == str(exc)
    assert back.speeds == [8.425, 12.64]
    assert back.head == "a: the speed is ambiguous"


def test_ambiguous_speed_from_a_worker_is_the_input_error_not_a_broken_pool():
    with ProcessPoolExecutor(max_workers=1) as pool:
        future = pool.submit(_raise_ambiguous)
        with pytest.raises(AmbiguousSpeed, match="tooth count differs") as got:
            future.result()
    assert got.value.speeds == [8.4, 12.6]


def test_inspects_ambiguous_speed_says_a_tooth_count_may_differ(monkeypatch):
    # inspect's own record (no file of a run): a 29/73 box described 28/73, no speed given, read '8.425 Hz (708 Hz
    # as 3xM1) or 12.64 Hz (2xM1) ... expected a declared speed', the count that differs unsaid; at its nominal
    # speed inspect names it ('its sidebands show a 29-tooth pinion ... described 28')
    import numpy as np
    from test_inspect import described

    from gearlab.gearbox import speed as S

    def ambiguous(*args, **kwargs):
        raise AmbiguousSpeed("r: the speed is ambiguous; expected a declared speed", [8.425, 12.64])

    monkeypatch.setattr(S, "speed_from_mesh", ambiguous)
    monkeypatch.setattr(S, "_followed", lambda *args: (None, 0.0, "", None))
    signal = np.random.default_rng(0).normal(size=8192)
    with pytest.raises(AmbiguousSpeed) as got:
        S.follow_speed(signal, 8192.0, described((28, 73)), None, "r")
    assert str(got.value) == (
        "r: the speed is ambiguous; expected a declared speed (or a tooth count differs from box's: at its nominal "
        "speed, --speed, inspect names it)"
    )
    assert got.value.speeds == [8.425, 12.64]
