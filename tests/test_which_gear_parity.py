"""Which gear is one decision (gearlab.data.which_gear): `gearlab inspect --history`, the detection
kind's which-gear records (detection_which_gear.localise_target) and `gearlab score`
(localise_scored, each new record read as score reads it) name the same gear with the same evidence
(each shaft's z and threshold, the tooth) on the same records. The records are written here, not
simulated by gearlab: a two-stage box's mesh harmonics, amplitude-modulated at their shafts' orders,
one gear with a tooth whose passing lifts its mesh for about a pitch, white noise, a speed that
wobbles, and a tacho on the output shaft (a slower shaft's mark: the input angle's zero is the
output's first mark, whole input turns away from where the first complete input turn starts)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from gearboxes import description, mesh_train, shaft_orders, stage

from gearlab.gearbox import order_table, resolve_gearbox

TEETH = ((19, 47), (23, 41))  # tooth counts no other test uses
FS, SPEED, SECONDS = 12_000.0, 20.0, 4.0
TOOTH = 30  # the damaged tooth of the output gear (41T), counted from the output's tacho mark


def take(path, fault, seed, slip):
    """Write a record (npz: acc in m/s², tacho pulses, fs) of the box at *slip* below SPEED with a
    *fault* (stage index, "pinion" | "wheel", tooth counted from the shafts' common zero) or None."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(SECONDS * FS)) / FS
    f = SPEED * (1 - slip) * (1 + 0.002 * np.sin(2 * np.pi * 0.4 * t + seed))
    orders = shaft_orders(TEETH)
    # every shaft at its zero at theta = 0, a third of an output turn after the record starts
    theta = 2 * np.pi * np.cumsum(f) / FS - 2 * np.pi * (1 / 3) / orders[-1]
    x = mesh_train(
        theta, TEETH, rng, fault, noise=0.3, level=3.0, bump=0.8, width=0.5, second=0.5, third=0.25, phase=0.5
    )
    tacho = np.where((orders[-1] * theta) % (2 * np.pi) < 0.3, 5.0, 0.0)
    np.savez(path, acc=x, tacho=tacho, fs=FS)
    return str(path)


@pytest.fixture(scope="module")
def box(tmp_path_factory):
    """{"box": the description's path, name: record path}: three healthy takes, a take with the
    stage-2 pinion (the intermediate shaft's 23T) damaged, one with the output gear's tooth TOOTH."""
    where = tmp_path_factory.mktemp("parity")
    text = description(*(stage(*z) for z in TEETH), name="parity", speed="20 Hz", near="input", tacho="output")
    path = where / "parity.toml"
    path.write_text(text)
    out = {"box": str(path)}
    for name, fault, seed, slip in (
        ("h1", None, 1, 0.012),
        ("h2", None, 2, 0.016),
        ("h3", None, 3, 0.010),
        ("pinion", (1, "pinion", 7), 5, 0.015),
        ("output", (1, "wheel", TOOTH), 6, 0.013),
    ):
        out[name] = take(where / f"{name}.npz", fault, seed, slip)
    return out


HISTORY = ("h1", "h2", "h3")


def inspected(box, name, tacho=True) -> dict:
    """`gearlab inspect --json` of the record *name* against the history: its localisation (read-only),
    inspected once a module (two tests read the output take's with the tacho)."""
    from typer.testing import CliRunner

    from gearlab.cli import app

    key = (box[name], tacho)
    if key not in INSPECTED:
        args = ["inspect", box[name], "--gearbox", box["box"], "--vibration", "acc", "--json"]
        args += ["--tacho", "tacho"] if tacho else []
        for h in HISTORY:
            args += ["--history", box[h]]
        out = CliRunner().invoke(app, args)
        assert out.exit_code == 0, out.output
        INSPECTED[key] = json.loads(out.stdout)["localisation"]
    return INSPECTED[key]


INSPECTED: dict = {}  # (record path, tacho) -> inspected's localisation


def _target(box, tacho=True):
    """The detection kind's [target] of the box's records: with the output's tacho, or none (the speed
    followed on the description's mesh lines)."""
    from gearlab.parts.measured import Target, TargetFile, tacho_shaft_of

    files = tuple(TargetFile(box[n], box[n], "history" if n in HISTORY else "test", "x", "") for n in box if n != "box")
    if not tacho:
        return Target("acc", None, 1, None, None, "none", "fault", files, gearbox=box["box"])
    shaft = tacho_shaft_of("", "tacho", resolve_gearbox(box["box"]), "[target]", "[source] gearbox")
    return Target("acc", "tacho", 1, None, None, "none", "fault", files, tacho_shaft=shaft)


def _source(box):
    from gearlab.data.spec import dataset_preset
    from gearlab.gearbox.simulation import reference

    return dataset_preset("phm09-30").with_(preset=reference(box["box"]))


def _detected(box, where, tacho=True):
    """(the detection kind's which-gear records, `gearlab score`'s of the same files against the run's
    stored histories), each file read as each reads it (score: cut_recording with the run's keys)."""
    from gearlab.data.recordings import cut_recording
    from gearlab.data.which_gear import Take
    from gearlab.kinds import detection_which_gear as D
    from gearlab.kinds.detection_records import read_target
    from gearlab.runs import RunDir

    target = _target(box, tacho)
    conditions = read_target(target, (10,), lambda e: None)
    assert len(conditions) == 1
    run = RunDir(where)
    D.store_localisation(run, _source(box), conditions)
    loc = run.read_json("localisation.json")
    keys = {"vibration": "acc", "tacho": "tacho", "tacho_shaft": target.tacho_shaft}
    if not tacho:
        keys = {"vibration": "acc", "gearbox": resolve_gearbox(box["box"])}
    news = [(box[n], Take.of(cut_recording(box[n], **keys))) for n in ("pinion", "output")]
    return loc, D.localise_scored(run, {next(iter(conditions)): news})


@pytest.fixture(scope="module")
def detected(box, tmp_path_factory):
    return _detected(box, tmp_path_factory.mktemp("run"))


def _shafts(found: dict) -> dict:
    return {s["shaft"]: (s["z"], s["threshold"], s["flagged"]) for s in found["shafts"]}


def _teeth(found: dict) -> dict:
    """{(shaft, gear): (tooth, pitches to 6 places)} of the flagged shafts."""
    return {
        (s["shaft"], g): (t["tooth"], round(t["pitches"], 6))
        for s in found["shafts"]
        for g, t in s["tooth"].items()
        if g != "angle_deg"
    }


@pytest.mark.parametrize("name", ["pinion", "output"])
def test_inspect_detection_and_score_name_the_same_gear_with_the_same_evidence(box, detected, name):
    shown = inspected(box, name)
    run, scored = detected
    found = run["records"][box[name]]
    assert found["named"] == shown["named"] and found["named"] is not None, (found["summary"], shown["summary"])
    assert found["summary"] == shown["summary"]
    for shaft, (z, thr, flagged) in _shafts(shown).items():
        assert _shafts(found)[shaft] == pytest.approx((z, thr, flagged), rel=1e-9), shaft
    assert _teeth(found) == _teeth(shown) and _teeth(found)
    assert scored[box[name]]["named"] == shown["named"] and scored[box[name]]["summary"] == shown["summary"]


def test_without_a_tacho_inspect_detection_and_score_read_and_decide_alike(box, tmp_path):
    # the speed followed on a mesh harmonic's phase: inspect's revolutions were cut from the followed
    # phase's own zero, a detection's and score's from the record's first sample (outside round 9's P,
    # 13/81 without a tacho: the 81T named by both, z 316 against 246)
    run, scored = _detected(box, tmp_path, tacho=False)
    shown = inspected(box, "output", tacho=False)
    found = run["records"][box["output"]]
    assert found["named"] == shown["named"] == "output gear 41T (stage 2)", (found["summary"], shown["summary"])
    for shaft, (z, thr, flagged) in _shafts(shown).items():
        assert _shafts(found)[shaft] == pytest.approx((z, thr, flagged), rel=1e-9), shaft
    assert _teeth(found) == _teeth(shown)
    assert scored[box["output"]]["summary"] == shown["summary"]


def test_a_tooth_of_the_tacho_shaft_is_counted_from_its_own_mark(box, detected):
    # the input angle's zero is the output's first mark, some whole input turns after the first complete
    # input turn begins: counted from that turn, the output gear's tooth came out 1.5 output turns' worth
    # of teeth away in the detection kind and in score (their first revolution was the transient's count)
    gear = "output gear 41T (stage 2)"
    run, scored = detected
    for found in (inspected(box, "output"), run["records"][box["output"]]):
        assert found["named"] == gear, found["summary"]
        ev = next(s for s in found["shafts"] if s["shaft"] == "output")
        off = (ev["tooth"][gear]["pitches"] - (TOOTH - 0.5) + 41 / 2) % 41 - 41 / 2
        assert abs(off) < 1.0, (off, found["summary"])
    assert (
        f"tooth {TOOTH} of 41" in scored[box["output"]]["evidence"]
        or abs(int(scored[box["output"]]["evidence"].split("tooth ")[1].split(" of")[0]) - TOOTH) <= 1
    ), scored[box["output"]]["evidence"]


def test_a_take_counts_its_first_revolution_from_the_tacho_shafts_mark(box):
    # recordings.cut_recording (the detection kind's and score's reader) and inspect count alike
    from gearlab.data.recordings import cut_recording
    from gearlab.inspect import InspectOptions
    from gearlab.inspect_history import input_revolutions

    target = _target(box)
    box_ = resolve_gearbox(box["box"])
    period = order_table(box_).train_period
    for name in ("h1", "output"):
        rec = cut_recording(box[name], vibration="acc", tacho="tacho", tacho_shaft=target.tacho_shaft)
        revs, first, *_ = input_revolutions(box[name], box_, InspectOptions(vibration="acc", tacho="tacho"))
        assert rec.first_revolution % period == first % period
        assert rec.first_revolution < 0  # the first whole input turn starts before the output's first mark
        assert np.allclose(rec.revolutions, revs, rtol=1e-9, atol=1e-9)
