"""Tiny scenarios shared by the tests: Experiment B's domains cut down to one fault and a few
healthy samples, so that a transfer run trains in seconds."""

import json
from pathlib import Path

DOMAINS = """\
[source]
preset = "B-6-ch5"
teeth = [1, 2, 3]
faults = {{ crack = [13] }}
healthy = {healthy}

[target]
preset = "B-8-ch5"
teeth = [1, 2, 3]
faults = {{ crack = [13] }}
healthy = {healthy}
noise = {{ kind = "laplace", snr_db = 0.0, seed = 1 }}
"""

# The training keys of a tiny protocol ([protocol] of a transfer scenario, [accuracy] of a gap one).
SCHEDULE = """\
target_train = 8
batch = 4
prime_epochs = 2
baseline_epochs = 2
patience = 2
min_epochs = 2
max_epochs = {max_epochs}
"""

EXECUTION = """\
[execution]
workers = 1
device = "cpu"
"""


def domains(healthy: int = 9) -> str:
    """The [source] and [target] tables of the tiny scenarios."""
    return DOMAINS.format(healthy=healthy)


def schedule(max_epochs: int = 3) -> str:
    return SCHEDULE.format(max_epochs=max_epochs)


def transfer(methods: str, repetitions: int = 1, max_epochs: int = 3) -> str:
    """A tiny transfer scenario (k in {0, 2}, one worker, CPU); *methods* are its [[methods]] tables."""
    return (
        f'[scenario]\nname = "tiny"\nkind = "transfer"\n\n{domains()}\n[network]\nname = "fast"\n\n{methods}\n'
        f"[protocol]\nks = [0, 2]\nrepetitions = {repetitions}\n{schedule(max_epochs)}\n{EXECUTION}"
    )


def records(run: Path) -> dict[str, dict]:
    """A run's records by unit, without the fields that measure time (they differ run to run)."""
    out = {}
    for line in (Path(run) / "results.jsonl").read_text().splitlines():
        r = json.loads(line)
        out[r["unit"]] = {k: v for k, v in r.items() if "seconds" not in k and "time" not in k}
    return out
