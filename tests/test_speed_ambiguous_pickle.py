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
