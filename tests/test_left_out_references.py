"""Issue 39: a classical indicator's reference from a history of few takes. NA4's denominator and
tooth_energy's, tooth_sync's and pinion_sync's per-window mean and spread are read off the history's
units; a history take scored against a reference holding its own units scores nearer it than a new take
does, and the threshold set on those scores lets a new healthy take through more often than asked. Of
two takes or more each is scored against the reference made without it (with two, the other take's:
test_detection_rig's two-record thresholds)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from test_threshold_few_takes import BLOCK, STRIDE, TEETH, take

from gearlab.kinds import record_effects
from gearlab.kinds.detection_classical import classical_record
from gearlab.kinds.detection_records import tsa_units
from gearlab.kinds.detection_units import Rule
from gearlab.signals.indicators import na4, na4_reference, tooth_energy, tooth_reference

CLASSICAL = SimpleNamespace(mesh_orders=(TEETH,), shaft_orders=2, sidebands=1, shafts=(), slow_shafts=())


def condition(takes: list[np.ndarray]) -> dict:
    """A detection condition's history of *takes* (record10 units, sliding) and one new healthy take."""
    files = [SimpleNamespace(path=f"h{i}") for i in range(len(takes))]
    units = [tsa_units(t, BLOCK, STRIDE) for t in takes]
    test = SimpleNamespace(path="t")
    return {
        "history": list(zip(files, takes)),
        "history_units": {"record10": np.concatenate(units)},
        "history_records": {
            "record10": [(len(u), record_effects.independent_units(len(u), BLOCK, STRIDE)) for u in units]
        },
        "test": [(test, takes[0])],
        "test_units": {"t": {"record10": tsa_units(takes[0], BLOCK)}},
    }


@pytest.mark.parametrize("takes", [2, 3, 4])
@pytest.mark.parametrize("name", ["na4", "tooth_energy"])
def test_a_history_take_is_scored_against_the_reference_of_the_other_takes(name, takes):
    rng = np.random.default_rng([takes, 39])
    history = [take(rng) for _ in range(takes)]
    cond = condition(history)
    rule = Rule("records", 0.01, cond["history_records"])
    record = classical_record(name, "c", cond, CLASSICAL, rule)
    units = [tsa_units(t, BLOCK, STRIDE) for t in history]
    dofs = [record_effects.overlap_dof(len(u), BLOCK, STRIDE) for u in units]

    def scored(X: np.ndarray, keep: list) -> np.ndarray:
        if name == "na4":
            return na4(X, (TEETH,), na4_reference(np.concatenate([units[j] for j in keep]), (TEETH,)))
        reference = tooth_reference([units[j] for j in keep], TEETH, (TEETH,), dofs=[dofs[j] for j in keep])
        return tooth_energy(X, (TEETH,), reference)

    got = rule.groups("record10", np.asarray(record["history_scores"]["record10"]))
    for k in range(takes):
        keep = [j for j in range(takes) if j != k]
        assert np.allclose(got[k], scored(units[k], keep), rtol=1e-9), k
    # a new take's units against the whole history's reference
    new = cond["test_units"]["t"]["record10"]
    assert np.allclose(record["test_scores"]["t"]["record10"], scored(new, list(range(takes))), rtol=1e-9)
