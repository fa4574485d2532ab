"""A worker's warning reads as the command line's: one line 'warning: MESSAGE', not Python's
'FILE:LINE: UserWarning: MESSAGE' followed by the echoed source line (the simulator's step warning
at a record's rate, printed so in each process-pool worker)."""

import warnings

from gearlab.executors import LocalExecutor

MESSAGE = "fs = 200368 Hz gives fewer than 10 steps per period; results will be inaccurate"


def _warns(i: int) -> int:
    warnings.warn(MESSAGE, stacklevel=1)
    return i


def test_a_workers_warning_is_one_line(capfd):
    with LocalExecutor(2) as pool:
        assert pool.map(_warns, [1, 2]) == [1, 2]
    err = capfd.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert lines and all(line == f"warning: {MESSAGE}" for line in lines), err
    assert "UserWarning" not in err and "warnings.warn" not in err
