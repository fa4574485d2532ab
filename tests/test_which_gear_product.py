"""Which gear in the product (simulate and compare, gearlab.data.which_templates): `gearlab inspect
--gearbox --history`, the detection kind's which-gear records and `gearlab score` name a two-gear
shaft's gear by the description's simulated events at the record's speed, as benchmarks/localisation.py
does, and say which rule named it. A 21/63 + 24/56 train's 24T stage-2 pinion chip (as in test_localise)."""

import json

import numpy as np
import pytest
from which_gear_takes import REDUCER as TWO
from which_gear_takes import reducer_take

from gearlab.data.which_gear import Take
from gearlab.kinds import detection_which_gear as D
from gearlab.parts.measured import TargetFile
from gearlab.runs import RunDir

SPEED, FS = 25.0, 20_000.0
PINION, WHEEL = "intermediate pinion 24T (stage 2)", "intermediate gear 63T (stage 1)"
CHIP = [{"name": "chip", "gear": "intermediate pinion", "tooth": 20, "step": 18}]


@pytest.fixture(scope="module")
def takes(tmp_path_factory):
    """{name: (file, revolutions, first revolution)}: two healthy takes and the chipped one."""
    where = tmp_path_factory.mktemp("which")
    out = {}
    for name, faults, seed in (("h1", [], 201), ("h2", [], 202), ("chip", CHIP, 203)):
        rec, revolutions, first = reducer_take(faults, seed, SPEED, FS)
        path = where / f"{name}.npz"
        np.savez(path, acc=rec.vibration, tacho=rec.tacho, fs=rec.fs)
        out[name] = (str(path), revolutions, first)
    return out


def test_inspect_with_history_names_the_pinion_by_the_simulated_events(takes, tmp_path):
    from typer.testing import CliRunner

    from gearlab.cli import app

    def localised(box):
        common = ["--gearbox", str(box), "--vibration", "acc", "--tacho", "tacho", "--pulses-per-rev", "1"]
        common += ["--history", takes["h1"][0], "--history", takes["h2"][0], "--json"]
        out = CliRunner().invoke(app, ["inspect", takes["chip"][0], *common])
        assert out.exit_code == 0, out.output
        return json.loads(out.stdout)["localisation"]

    loc = localised(TWO)
    ev = next(s for s in loc["shafts"] if s["shaft"] == "intermediate")
    assert loc["named"] == PINION and ev["which"] == PINION, loc["summary"]
    assert "named by the simulated events" in loc["summary"]
    assert ev["stage_evidence"]["simulated fit"][PINION] > ev["stage_evidence"]["simulated fit"][WHEEL]
    # a description without the load to simulate at: the width decides, and the line says why
    loadless = tmp_path / "loadless.toml"
    loadless.write_text(TWO.read_text().replace('load = "40 N*m"\n', ""))
    width = localised(loadless)
    # the width names the pinion too since the evidence is read in each order's null sds (z 13.0; before:
    # undecided, z under WIDTH_Z)
    assert width["named"] == PINION, width["summary"]
    assert "by the event's width" in width["summary"] and "not simulated:" in width["summary"], width["summary"]


def _source():
    from gearlab.data.spec import dataset_preset
    from gearlab.gearbox.simulation import reference

    # a [source] gearbox = "reducer_21_63_24_56.toml" (a stage-1 pinion chip watched)
    return dataset_preset("phm09-30").with_(preset=reference(str(TWO)))


def test_the_detection_kind_and_score_name_the_pinion_as_other_damage(takes, tmp_path):
    tf = {p: TargetFile(p, p, "history" if p != "chip" else "test", "", "25 Hz") for p in takes}
    cond = {
        "history": [(tf["h1"], None), (tf["h2"], None)],
        "test": [(tf["chip"], None)],
        "raw": {p: (revs, first) for p, (_, revs, first) in takes.items()},
        "max_order": int(0.9 * FS / 2 / SPEED),
        "speeds": dict.fromkeys(takes, SPEED),
        "fs": dict.fromkeys(takes, FS),
    }
    run = RunDir(tmp_path)
    D.store_localisation(run, _source(), {"25 Hz": cond})
    found = run.read_json("localisation.json")["records"]["chip"]
    assert found["named"] == PINION, found["summary"]
    assert found["call"] == f"other damage: {PINION}"  # the run watches the 21T input pinion
    assert "named by the simulated events" in found["summary"]
    _, revs, first = takes["chip"]
    scored = D.localise_scored(run, {"25 Hz": [("new", Take(revs, first, SPEED, FS))]})["new"]
    assert scored["named"] == PINION and scored["call"] == found["call"], scored["summary"]
    # a record whose speed or rate the condition does not give: the event's width, said
    cond.pop("fs")
    width = D.localise_target(_source(), {"25 Hz": cond})["records"]["chip"]
    # (it names the pinion too since the evidence is read in each order's null sds: z 13.0, before under WIDTH_Z)
    assert width["named"] == PINION and "by the event's width" in width["summary"], width["summary"]
