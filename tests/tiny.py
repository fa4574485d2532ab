"""Tiny scenarios shared by the tests: Experiment B's domains cut down to one fault and a few
healthy samples, so that a transfer run trains in seconds."""

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from gearlab.data.spec import Dataset

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
effects = [{{ name = "sensor_noise", kind = "laplace", snr_db = 0.0, seed = 1 }}]
"""
# the target's line of DOMAINS (as domains() writes it) that makes its records noisy
TARGET_NOISE = 'effects = [{ name = "sensor_noise", kind = "laplace", snr_db = 0.0, seed = 1 }]\n'

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


# The two baselines and one calibrated method: [[methods]] of a tiny transfer scenario.
BASELINES_AND_MMD = """\
[[methods]]
adapter = "source_only"

[[methods]]
adapter = "target_only"
supervised = true

[[methods]]
adapter = "mmd"
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


def stiffness(points: int, faults: list[str], steps: tuple[int, int], tooth: int | None = None, cases: str = "") -> str:
    """A stiffness scenario ("stiff") of the luo2019 pair: *faults* swept over *steps* (on *tooth*), then
    the [[cases]] tables *cases*."""
    text = (
        f'[scenario]\nname = "stiff"\nkind = "stiffness"\n\n[stiffness]\npair = "luo2019"\npoints = {points}\n\n'
        f"[sweep]\nfaults = {json.dumps(faults)}\n"
    )
    if tooth is not None:
        text += f"tooth = {tooth}\n"
    text += f"steps = [{steps[0]}, {steps[1]}]\n"
    return f"{text}\n{cases}" if cases else text


def protocol(methods, **changes):
    """A protocol that trains in a second or two: two epochs of priming, a patience of 2, batches of 4
    (gearlab.learn.protocol.Protocol); *changes* replace any field."""
    from gearlab.learn.protocol import Protocol

    base = dict(target_train=12, batch=4, prime_epochs=2, patience=2, min_epochs=2, device="cpu")
    return Protocol(methods=tuple(methods), **{**base, **changes})


def bare_dataset(X: np.ndarray, fault: np.ndarray, spec=None, **more) -> Dataset:
    """The samples *X*, labelled healthy (0) or faulty (1) by *fault*, and nothing else: no intensity, tooth,
    fault area or revolution, one domain."""
    zeros = np.zeros(len(X), dtype=np.int8)
    return Dataset(
        spec=spec,
        X=X,
        label=fault.copy(),
        fault=fault,
        intensity=zeros,
        tooth=zeros,
        rfa=np.zeros(len(X), np.float32),
        revolution=zeros.astype(np.int16),
        domain=zeros,
        **more,
    )


def run_once(folder: Path, name: str, text: str, cache: Path | None = None, modules: dict | None = None) -> Path:
    """The run directory of one uninterrupted run of the scenario *text* (written to folder/name, run into
    folder/runs) on the dataset cache *cache* (default: folder/cache), *modules* standing in for those of
    sys.modules while it runs."""
    from gearlab.engine import run_scenario

    path = folder / name
    path.write_text(text)
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("GEARLAB_CACHE", str(cache or folder / "cache"))
        for module, stand_in in (modules or {}).items():
            mp.setitem(sys.modules, module, stand_in)
        return run_scenario(path, out=folder / "runs").path


def records(run: Path) -> dict[str, dict]:
    """A run's records by unit, without the fields that measure time (they differ run to run)."""
    out = {}
    for line in (Path(run) / "results.jsonl").read_text().splitlines():
        r = json.loads(line)
        out[r["unit"]] = {k: v for k, v in r.items() if "seconds" not in k and "time" not in k}
    return out


RIG_DOMAIN = """gearbox = "rig.toml"
teeth = [1]
faults = { chip = [20] }
healthy = 12
fs = 40000"""  # 40 kHz: a cheap target, source and target alike


def rig_gap_run(folder: Path, cache: Path, rig: Path, target: str, candidate: str, corrected: list) -> Path:
    """The run directory of a gap run "rig_gap" of the description *rig* (copied to folder/rig.toml): its
    [target] the [source] plus the line *target*, diagnosing sensor_noise and *candidate* by a stand-in
    diagnosis (test_gap_kind.fake_module) that reports the *corrected* effects."""
    import shutil

    from test_gap_kind import fake_module

    module = fake_module([])
    plain = module.diagnose

    def diagnose(source, target_X, settings, **kw):
        return {**plain(source, target_X, settings, **kw), "corrected_effects": corrected}

    module.diagnose = diagnose
    shutil.copy(rig, folder / "rig.toml")
    text = (
        f'[scenario]\nname = "rig_gap"\nkind = "gap"\n\n[source]\n{RIG_DOMAIN}\n\n[target]\n{RIG_DOMAIN}\n{target}\n\n'
        f'[diagnosis]\ncandidates = ["sensor_noise", "{candidate}"]\nbudget = 2\nhealthy = 10\nbootstrap = 10\n'
        f"permutations = 20\n\n[accuracy]\nenabled = false\n\n{EXECUTION}"
    )
    return run_once(folder, "gap.toml", text, cache, {"gearlab.gap.diagnose": module})
