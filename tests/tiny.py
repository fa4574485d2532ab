"""Tiny scenarios shared by the tests: Experiment B's domains cut down to one fault and a few
healthy samples, so that a transfer run trains in seconds."""

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


def domains(healthy: int = 9) -> str:
    """The [source] and [target] tables of the tiny scenarios."""
    return DOMAINS.format(healthy=healthy)
