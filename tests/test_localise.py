"""gearlab.signals.localise: which gear carries a localised change, on signal-level synthetic trains.

The records are built here in the input angle: every stage's mesh harmonics, each modulated a
little by both of its shafts (their amplitudes drawn per record, as one rig's records differ),
white noise, and for a fault a one-tooth dip of the faulty gear's mesh (its stage's component
only, once per turn of its shaft, centred on the tooth) with the ring of the strike as the tooth
comes into mesh. Tooth counts
are not the PHM rig's; one- and two-stage trains; grand periods of 5, 15 and 35 input turns, and
a coprime pair that needs the per-shaft fallback.
"""

import math
from fractions import Fraction
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from which_gear_takes import gearbox_take

from gearlab.errors import GearlabInputError
from gearlab.signals import localise as L

POINTS = 256


def train(*teeth):
    """A duck-typed order table (gearlab.gearbox.orders.OrderTable's fields) of a series train."""
    shafts = {1: ["input", "output"], 2: ["input", "intermediate", "output"]}[len(teeth)]
    orders, stages = [Fraction(1)], []
    for k, (z1, z2) in enumerate(teeth):
        o = orders[-1]
        stages.append(
            SimpleNamespace(
                index=k + 1,
                pinion_teeth=z1,
                wheel_teeth=z2,
                pinion_shaft=shafts[k],
                wheel_shaft=shafts[k + 1],
                mesh=o * z1,
                pinion_shaft_order=o,
                wheel_shaft_order=o * Fraction(z1, z2),
            )
        )
        orders.append(o * Fraction(z1, z2))
    period = math.lcm(*(o.denominator for o in orders))
    return SimpleNamespace(shafts=tuple(shafts), shaft_orders=tuple(orders), stages=tuple(stages), train_period=period)


def record(table, revolutions, rng, fault=None, depth=0.25, noise=0.3):
    """(revolutions, POINTS) in the input angle from its zero; *fault* = (shaft, stage, tooth 1-based)."""
    theta = 2 * np.pi * np.arange(revolutions * POINTS) / POINTS
    y = noise * rng.standard_normal(theta.size)
    for st in table.stages:
        mesh = float(st.mesh)
        carrier = sum(
            a * (1 + 0.05 * rng.standard_normal()) * np.cos(h * mesh * theta + 0.7 * h * st.index)
            for h, a in ((1, 1.0), (2, 0.5), (3, 0.25))
        )
        mod = 1.0
        for o, phase in ((st.pinion_shaft_order, 0.3), (st.wheel_shaft_order, 1.1)):
            mod = mod + 0.05 * (1 + 0.05 * rng.standard_normal()) * np.cos(float(o) * theta + phase)
        if fault is not None and fault[1] == st.index:
            name = table.shafts[fault[0]]
            z = st.pinion_teeth if st.pinion_shaft == name else st.wheel_teeth
            o = float(table.shaft_orders[fault[0]])
            at = 2 * np.pi * (fault[2] - 0.5) / z  # the middle of the tooth, in its shaft's angle
            d = (o * theta - at + np.pi) % (2 * np.pi) - np.pi
            mod = mod * (1 - depth * np.exp(-0.5 * (d / (0.6 * 2 * np.pi / z)) ** 2))
            # the strike as the tooth comes into mesh, early in its pitch
            since = ((o * theta - at + 0.3 * 2 * np.pi / z) % (2 * np.pi)) / o  # input angle since it
            ring = 0.27 * POINTS  # a resonance at 0.27 of the record's orders
            y += depth * np.exp(-since * ring / 40) * np.sin(ring * since)
        y += carrier * mod
    return y.reshape(revolutions, POINTS)


def history(table, revolutions, rng, count=3):
    return L.history([record(table, revolutions, rng) for _ in range(count)], table)


def near_tooth(found, tooth):
    """The tooth found, its peak within half a pitch of the tooth's middle."""
    z = found["of"]
    gap = (found["pitches"] - (tooth - 0.5) + z / 2) % z - z / 2
    return abs(gap) < 0.5 and found["tooth"] == tooth


def gear_name(table, shaft, stage):
    return next(g.name for g in L.gears_of(table)[table.shafts[shaft]] if g.stage == stage)


@pytest.mark.parametrize(
    ("teeth", "revolutions", "shaft", "stage", "tooth"),
    [
        (((18, 45),), 100, 0, 1, 7),  # grand period 5: input 5 turns, output 2
        (((18, 45),), 100, 1, 1, 31),
        (((20, 50), (25, 35)), 280, 0, 1, 4),  # grand period 35: 35, 14, 10 turns
        (((20, 50), (25, 35)), 280, 1, 1, 44),  # the intermediate shaft's wheel (stage 1) ...
        (((20, 50), (25, 35)), 280, 1, 2, 12),  # ... and its pinion (stage 2)
        (((20, 50), (25, 35)), 280, 2, 2, 30),
    ],
)
def test_the_damaged_gear_is_named_first_with_its_tooth(teeth, revolutions, shaft, stage, tooth):
    table = train(*teeth)
    rng = np.random.default_rng(7 + 10 * shaft + stage)
    hist = history(table, revolutions, rng)
    assert hist.layout.mode == "grand"
    res = L.localise(record(table, revolutions, rng, fault=(shaft, stage, tooth)), hist, table)
    name = gear_name(table, shaft, stage)
    on = L.gears_of(table)[table.shafts[shaft]]
    assert res.named_shaft == table.shafts[shaft]
    named = res.ranking[0]
    assert named.shaft == table.shafts[shaft]
    assert named.z > named.threshold
    assert near_tooth(named.tooth[name], tooth)
    assert f"{named.tooth[name]['tooth']} of {named.tooth[name]['of']}" in res.summary()
    assert ("step" in named.tooth[name]) == (shaft > 0)  # the slower shafts' teeth: up to a step
    if len(on) == 1:
        assert res.named == name and named.which is None
    else:
        # the intermediate shaft's 50T wheel and 25T pinion, told apart by the event's length
        assert res.named == name and named.which == name, named.stage_evidence
        assert "event width" in res.summary()


def test_a_pinion_fault_is_not_read_on_the_slower_shafts_it_is_also_periodic_with():
    # 20/60 then 30/50: the intermediate shaft turns once in 3 input turns, the output once in 5
    # (the rig's ratios, other teeth): a pinion tooth strikes 3 times per intermediate turn, every
    # 3rd intermediate order, and 5 times per output turn -- input content, not theirs.
    table = train((20, 60), (30, 50))
    assert table.train_period == 15
    rng = np.random.default_rng(3)
    hist = history(table, 120, rng)
    res = L.localise(record(table, 120, rng, fault=(0, 1, 9), depth=0.1), hist, table)
    assert res.named == "input pinion 20T (stage 1)"
    z = {e.shaft: e.z for e in res.ranking}
    assert z["input"] > 3 * max(z["intermediate"], z["output"], 1.0), z


def test_a_healthy_record_is_nothing_localised():
    for teeth, revolutions in (((18, 45),), 100), (((20, 60), (30, 50)), 120):
        table = train(*teeth)
        rng = np.random.default_rng(11)
        hist = history(table, revolutions, rng)
        res = L.localise(record(table, revolutions, rng), hist, table)
        assert res.named is None, res.describe()
        assert res.summary().startswith("nothing localised")
        assert all(not e.flagged and e.tooth == {} for e in res.ranking)
        # the thresholds come from the history alone: its records left out in turn, and a floor
        assert hist.left_out_z.shape == (3, len(table.shafts))
        floor = L.threshold_floor(len(table.shafts))
        assert np.all(hist.thresholds >= floor)
        assert np.all(hist.thresholds >= np.max(hist.left_out_z, axis=0))


def test_coprime_teeth_fall_back_to_each_shafts_own_average_and_say_so():
    table = train((17, 43))  # the output turns 17 times in 43 input turns: 3 grand periods in 150
    rng = np.random.default_rng(5)
    hist = history(table, 150, rng)
    assert hist.layout.mode == "shafts"
    for shaft, tooth in ((0, 5), (1, 20)):
        res = L.localise(record(table, 150, rng, fault=(shaft, 1, tooth)), hist, table)
        assert res.named == gear_name(table, shaft, 1), res.describe()
        assert near_tooth(res.ranking[0].tooth[res.named], tooth)
        assert res.method.startswith("per-shaft TSAs: the grand period (43 input revolutions) fits 3 time(s)")


def test_the_tooth_is_counted_from_the_input_angles_zero_whatever_revolution_the_record_starts_at():
    # A record cut from input revolution 2 on: the output shaft (2 turns in 5 input turns) is then
    # 4/5 of a turn on, so its teeth are found only if first_revolution is given.
    table = train((18, 45))
    rng = np.random.default_rng(9)
    hist = history(table, 100, rng)
    full = record(table, 102, rng, fault=(1, 1, 31))
    res = L.localise(full[2:], hist, table, first_revolution=2)
    assert near_tooth(res.ranking[0].tooth[res.named], 31)
    shifted = L.localise(full[2:], hist, table, first_revolution=0)
    assert near_tooth(shifted.ranking[0].tooth[res.named], (31 - 1 - 36) % 45 + 1)  # 0.8 turn = 36 pitches early


def test_describe_is_plain_data_for_json():
    import json

    table = train((18, 45))
    rng = np.random.default_rng(2)
    hist = history(table, 60, rng)
    res = L.localise(record(table, 60, rng, fault=(0, 1, 3)), hist, table)
    out = json.loads(json.dumps(res.describe()))
    assert out["named"] == res.named
    assert [s["shaft"] for s in out["shafts"]] == [e.shaft for e in res.ranking]
    assert out["method"].startswith("grand period of 5 input revolutions (input 5, output 2 turns)")


def test_bad_input_is_one_line():
    table = train((18, 45))
    rng = np.random.default_rng(1)
    hist = history(table, 40, rng, count=2)
    with pytest.raises(GearlabInputError, match=r"expected \(revolutions, 256\)"):
        L.localise(np.zeros((40, 128)), hist, table)
    with pytest.raises(GearlabInputError, match="no history record"):
        L.history([], table)
    with pytest.raises(GearlabInputError, match="localisation band"):
        L.layout(table, POINTS, 40, max_order=500)


def test_inspect_with_history_names_the_damaged_gear_of_simulated_rig_records(tmp_path, cli):
    """`gearlab inspect FILE --gearbox phm09 --history H1 --history H2`: the rig simulator's records
    (gearlab.data.simulated), healthy takes as the history, a cracked 80T output-gear tooth named
    (the input pinion that phm09_chip watches is not), a healthy take nothing localised."""
    import json

    from typer.testing import CliRunner

    from gearlab.cli import app
    from gearlab.data.simulated import simulated_record

    def save(name, faults, seed):
        rec = simulated_record(faults, speed_hz=40.0, revolutions=80, snr_db=30.0, seed=seed)
        path = tmp_path / f"{name}.npz"
        np.savez(path, acc=rec.vibration, tacho=rec.tacho, fs=rec.fs)
        return str(path)

    history = [save("healthy1", [], 1), save("healthy2", [], 2)]
    cracked = save("cracked", [{"name": "crack", "gear": "output gear", "tooth": 30, "step": 20}], 3)
    healthy = save("healthy3", [], 4)
    common = ["--gearbox", "phm09", "--vibration", "acc", "--tacho", "tacho", "--pulses-per-rev", "1"]
    common += [x for h in history for x in ("--history", h)]
    runner = CliRunner()
    out = runner.invoke(app, ["inspect", cracked, *common, "--json"])
    assert out.exit_code == 0, out.output
    loc = json.loads(out.stdout)["localisation"]
    assert loc["named"] == "output gear 80T (stage 2)", loc["summary"]
    assert loc["shafts"][0]["shaft"] == "output" and loc["shafts"][0]["flagged"]
    assert loc["history"] == history
    quiet = json.loads(runner.invoke(app, ["inspect", healthy, *common, "--json"]).stdout)["localisation"]
    assert quiet["named"] is None, quiet["summary"]
    shown = runner.invoke(app, ["inspect", cracked, *common])
    assert "which gear: localised change per shaft" in shown.output
    assert "output gear 80T (stage 2): z =" in shown.output
    # the command's one-line refusal, in this process (cli: the `gearlab` entry point), as the others
    code, _, err = cli("inspect", cracked, "--history", history[0], "--vibration", "acc")
    assert code == 2 and "give --gearbox too" in err and err.count("\n") == 1


def test_a_saved_history_localises_as_the_one_read_from_records(tmp_path):
    """History.state() holds plain arrays (np.savez, no pickle) from which History.restored remakes
    it for the same gearbox, records unread (what `gearlab score` uses); another gearbox is refused."""
    table = train((18, 45))
    rng = np.random.default_rng(4)
    hist = history(table, 60, rng)
    np.savez(tmp_path / "h.npz", **hist.state())
    with np.load(tmp_path / "h.npz", allow_pickle=False) as f:
        back = L.History.restored({k: f[k] for k in f.files}, table)
    rec = record(table, 60, rng, fault=(0, 1, 5))
    a, b = L.localise(rec, hist, table).describe(), L.localise(rec, back, table).describe()
    assert a == b and a["named"] == "input pinion 18T (stage 1)"
    with pytest.raises(GearlabInputError, match="saved for another gearbox description"):
        L.History.restored(hist.state(), train((19, 45)))


def test_takes_starting_at_different_tacho_marks_name_the_same_tooth(tmp_path):
    """Gearbox D's case (one stage 23/61, a tacho of 2 marks per turn, a chipped pinion tooth): two
    takes of one chip, one starting at each mark, localised with `gearlab inspect --history`
    against healthy takes, name the same tooth (before aligning each take to the first history
    take by its synchronous average, their tooth counts started half a turn apart)."""
    import json

    from gearboxes import description, stage
    from typer.testing import CliRunner

    from gearlab.cli import app
    from gearlab.data.simulated import simulated_record, tacho_pulses

    box = tmp_path / "pump.toml"
    one = stage(23, 61, width="30 mm", bores=("30 mm", "45 mm"))
    box.write_text(description(one, name="pump", speed="24.5 Hz", load="60 N*m", near="input", direction="x"))

    def save(name, faults, seed, start=0.0):
        """A take of the record from *start* input turns on, its tacho marking θ = πk (2 per turn)."""
        rec = simulated_record(faults, gearbox=str(box), revolutions=64, snr_db=30.0, seed=seed, fs=10_000.0)
        keep = rec.angle >= 2 * np.pi * start
        tacho = tacho_pulses(2 * rec.angle, 2 * 2 * np.pi * rec.speed_hz / rec.fs)  # 2θ: marks at θ = πk
        path = tmp_path / f"{name}.npz"
        np.savez(path, acc=rec.vibration[keep], tacho=tacho[keep], fs=rec.fs)
        return str(path)

    chip = [{"name": "chip", "gear": "input pinion", "tooth": 6, "step": 20}]
    history = [save("healthy1", [], 1), save("healthy2", [], 2, start=0.25)]
    takes = [save("chip_a", chip, 3, start=0.25), save("chip_b", chip, 3, start=0.75)]
    common = ["--gearbox", str(box), "--vibration", "acc", "--tacho", "tacho", "--pulses-per-rev", "2"]
    common += [x for h in history for x in ("--history", h)]
    runner = CliRunner()
    teeth = []
    for take in takes:
        out = runner.invoke(app, ["inspect", take, *common, "--json"])
        assert out.exit_code == 0, out.output
        loc = json.loads(out.stdout)["localisation"]
        assert loc["named_shaft"] == "input", loc["summary"]
        ev = next(s for s in loc["shafts"] if s["shaft"] == "input")
        teeth.append(next(t["tooth"] for k, t in ev["tooth"].items() if k != "angle_deg"))
    assert teeth[0] == teeth[1], teeth


def test_a_saved_history_of_two_marks_per_turn_turns_each_take_to_its_first_records_mark(tmp_path):
    """What `gearlab score` localises with (History.state / restored) keeps the tacho's marks and the
    first history record's mean revolution: a take cut half a turn later (at the other of 2 marks)
    names the same tooth as one cut at the first record's mark; one mark per turn turns nothing."""
    table = train((19, 38))
    rng = np.random.default_rng(11)
    hist = L.history([record(table, 60, rng) for _ in range(3)], table, marks=2)
    np.savez(tmp_path / "h.npz", **hist.state())
    with np.load(tmp_path / "h.npz", allow_pickle=False) as f:
        back = L.History.restored({k: f[k] for k in f.files}, table)
    full = record(table, 62, rng, fault=(0, 1, 5)).reshape(-1)
    at_first = full[: 60 * POINTS].reshape(60, POINTS)
    at_second = full[POINTS // 2 : POINTS // 2 + 60 * POINTS].reshape(60, POINTS)
    name = gear_name(table, 0, 1)
    teeth = [L.localise(take, back, table).describe() for take in (at_first, at_second)]
    found = [next(s for s in t["shafts"] if s["shaft"] == "input")["tooth"][name] for t in teeth]
    assert [near_tooth(f, 5) for f in found] == [True, True], found
    said = "(the mark falls at any of 2 points of an input turn: this record's input revolutions "
    assert said + "were cut 1/2 of a turn later to line up with that record's)" in teeth[1]["method"]
    assert said + "already line up with that record's)" in teeth[0]["method"]
    m, same = L.turned(at_second, hist.reference, 1)
    assert m == 0 and same is at_second


def test_two_gears_of_alike_tooth_counts_on_one_shaft_are_named_together_with_the_reason():
    # 40T wheel and 36T pinion on the intermediate shaft: their tooth periods differ by 10 %, too
    # little for the event's length to tell them apart, so the shaft is named with both
    table = train((20, 40), (36, 48))
    rng = np.random.default_rng(8)
    hist = history(table, 120, rng)
    res = L.localise(record(table, 120, rng, fault=(1, 1, 17)), hist, table)
    assert res.named == "intermediate shaft: 40T gear (stage 1) or 36T pinion (stage 2)", res.describe()
    ev = res.ranking[0]
    assert ev.which is None and "too alike" in ev.stage_evidence["undecided"]
    assert "which of the two: undecided" in res.summary()


def rig_takes(gear, seed, kind="crack", tooth=30, step=20, speed=40.0):
    """(history, damaged take) of the rig simulator (PHM 2009 gearbox): 2 healthy takes, one damaged."""
    from gearlab.data.simulated import simulated_record
    from gearlab.signals import cut_revolutions

    def take(faults, s):
        rec = simulated_record(faults, speed_hz=speed, revolutions=4 * speed, snr_db=25.0, seed=s)
        cut = cut_revolutions(rec.vibration, rec.fs, pulses=rec.tacho, transient="none")
        return cut.revolutions, (math.floor(rec.start) + 1) % rec.period if rec.period > 1 else 0

    hist = [take([], seed + 1), take([], seed + 2)]
    return hist, take([{"name": kind, "gear": gear, "tooth": tooth, "step": step}], seed + 3)


@pytest.mark.parametrize(
    ("gear", "named"), [("idler gear", "idler gear 96T (stage 1)"), ("idler pinion", "idler pinion 48T (stage 2)")]
)
def test_the_rig_simulators_idler_gears_are_told_apart(gear, named):
    """On the rig simulator a 96T-gear and a 48T-pinion crack on the idler are named apart (before:
    both as 'idler shaft: 96T gear (stage 1) or 48T pinion (stage 2)'), with the evidence; a flag
    is then other damage for a scenario watching the other gear of the same shaft."""
    from gearlab.gearbox import order_table, resolve_gearbox
    from gearlab.kinds.detection_which_gear import call_of

    table = order_table(resolve_gearbox("phm09"))
    hist, (revs, first) = rig_takes(gear, 100)
    h = L.history([r for r, _ in hist], table, first_revolutions=[f for _, f in hist], max_order=700)
    found = L.localise(revs, h, table, first_revolution=first).describe()
    assert found["named"] == named, found["summary"]
    ev = next(s for s in found["shafts"] if s["shaft"] == "idler")
    assert ev["which"] == named and "event width" in found["summary"]
    other = next(g for g in ev["gears"] if g != named)
    assert call_of(found, [other]).startswith("other damage: " + named)
    assert call_of(found, [named]).startswith("watched-gear fault: " + named)
    # the idler turns 1/3 per input turn: a take's first mark finds it at any of 3 angles, so its
    # gears' teeth are counted up to steps of z / 3, and the summary says so
    step = {"idler gear 96T (stage 1)": 32, "idler pinion 48T (stage 2)": 16}[named]
    assert ev["tooth"][named]["step"] == step and f"up to {step}-tooth steps between takes" in found["summary"]


def test_a_narrow_event_names_the_finer_gear_under_the_width_z():
    """Noise widens a fault's event and never narrows it: under z = WIDTH_Z an event that reads as
    narrow as the finer gear's tooth names that gear (before: any event under z = 10 named both),
    a wide one stays undecided. The synthetic 50T wheel at a shallow dip, six takes."""
    table = train((20, 50), (25, 35))
    named = []
    for seed in range(100, 106):
        rng = np.random.default_rng(seed)
        hist = history(table, 280, rng)
        res = L.localise(record(table, 280, rng, fault=(1, 1, 44), depth=0.12), hist, table)
        ev = next(e for e in res.ranking if e.shaft == "intermediate")
        assert ev.flagged and ev.z < L.WIDTH_Z, ev.describe()
        if ev.which is None:
            assert "too noisy" in ev.stage_evidence["undecided"] and ev.stage_evidence["u"] > L.U_FINE
        named.append(ev.which)
    assert "intermediate pinion 25T (stage 2)" not in named, named
    assert named.count("intermediate gear 50T (stage 1)") >= 3, named


TWO = Path(__file__).resolve().parents[1] / "examples" / "gearboxes" / "reducer_21_63_24_56.toml"


@pytest.mark.parametrize(("kind", "speed"), [("spall", 25.0), ("crack", 30.0)])
def test_a_stage_2_pinion_fault_on_a_21_63_24_56_train_is_named_the_24t_pinion(tmp_path, kind, speed):
    """The simulated 24T pinion (stage 2) on the intermediate shaft of a 21/63 + 24/56 train, whose
    event reads wider than the 63T wheel's (0.1 < u <= 0.35), is named alone (before: 'intermediate
    shaft: 63T gear (stage 1) or 24T pinion (stage 2)', a fault of the 63T for a scenario watching
    it); a scenario watching the 63T calls it other damage."""
    from gearlab.gearbox import order_table, resolve_gearbox
    from gearlab.kinds.detection_which_gear import call_of

    table = order_table(resolve_gearbox(str(TWO)))

    def take(faults, s):
        return two_stage_take(faults, s, speed)

    hist = [take([], 101), take([], 102)]
    revs, first = take([{"name": kind, "gear": "intermediate pinion", "tooth": 7, "step": 20}], 103)
    top = min(0.9 * 10_000 / speed, 0.45 * hist[0][0].shape[1])
    h = L.history([r for r, _ in hist], table, first_revolutions=[f for _, f in hist], max_order=top)
    found = L.localise(revs, h, table, first_revolution=first).describe()
    pinion = "intermediate pinion 24T (stage 2)"
    ev = next(s for s in found["shafts"] if s["shaft"] == "intermediate")
    assert found["named"] == pinion and ev["which"] == pinion, found["summary"]
    assert 0.1 < ev["stage_evidence"]["u"] <= 0.35  # the band the shaft was named with both gears in
    assert call_of(found, ["intermediate gear 63T (stage 1)"]).startswith("other damage: " + pinion)


def test_simulated_events_name_a_24t_pinion_chip_the_width_names_it_too():
    """Simulate and compare (signals.which_template): a chip on the 24T pinion of a 21/63 + 24/56
    train's intermediate shaft; the description's simulated chip, spall and crack on each gear at the
    record's speed (without its load, noise or tooth) fit the pinion's clearly better, and the pinion is
    named alone. The width rule names it as well since the evidence is read in each order's null sds
    (signals.evidence: z 13.0 > WIDTH_Z; before, z under WIDTH_Z and an event as wide as a 63T tooth's
    could be: both)."""
    from gearlab.data.which_templates import simulated_templates
    from gearlab.gearbox import order_table, resolve_gearbox

    table = order_table(resolve_gearbox(str(TWO)))
    speed = 25.0

    def take(faults, s):
        return two_stage_take(faults, s, speed, load_nm=10.5)

    hist = [take([], 201), take([], 202)]
    revs, first = take([{"name": "chip", "gear": "intermediate pinion", "tooth": 20, "step": 18}], 203)
    top = min(0.9 * 10_000 / speed, 0.45 * hist[0][0].shape[1])
    h = L.history([r for r, _ in hist], table, first_revolutions=[f for _, f in hist], max_order=top)
    pinion = "intermediate pinion 24T (stage 2)"
    width = L.localise(revs, h, table, first_revolution=first)
    assert width.named == pinion and width.ranking[0].z > L.WIDTH_Z, width.summary()  # what the width says
    templates = simulated_templates(table, speed, 20_000.0, gearbox=str(TWO), sim_fs=60_000.0)
    found = L.localise(revs, h, table, first_revolution=first, templates=templates).describe()
    ev = next(s for s in found["shafts"] if s["shaft"] == "intermediate")
    assert found["named"] == pinion and ev["which"] == pinion, found["summary"]
    fits = ev["stage_evidence"]["simulated fit"]
    assert fits[pinion] > fits["intermediate gear 63T (stage 1)"] + 0.1, fits
    assert "simulated event's fit" in found["summary"]


def two_stage_take(faults, seed: int, speed: float, **options):
    """(revolutions, first revolution of the train's cycle) of a 4 s take of the 21/63 + 24/56 train
    (TWO) simulated at 60 kHz, read at 20 kHz with its tacho, 25 dB of noise."""
    _, revolutions, first = gearbox_take(TWO, faults, seed, speed, snr_db=25.0, **options)
    return revolutions, first


def test_healthy_records_against_two_records_in_per_shaft_averages_localise_nothing():
    """Grand periods of 79, 54 and 35 input turns in 100-turn records: each shaft's own TSA. The history's
    two records give half-record units; a record read whole carried the other shafts' lines leaking
    into each TSA by the length averaged, and weights from noise smoothed across TSAs (a slow shaft's
    linear resampling holds a third of the input TSA's noise near the top order): 13 of 27 healthy
    records flagged at cc56176; read in blocks, the noise still smoothed across TSAs, 8 (cd7378b)."""
    flagged, z = 0, []
    for teeth in (((24, 79), (27, 72)), ((22, 36), (21, 63)), ((20, 50), (25, 35))):
        table = train(*teeth)
        for seed in range(3):
            rng = np.random.default_rng(seed)
            hist = L.history([record(table, 100, rng) for _ in range(2)], table)
            assert hist.layout.mode == "shafts"
            for _ in range(3):
                res = L.localise(record(table, 100, rng), hist, table)
                flagged += res.named is not None
                z.append(next(e.z for e in res.ranking if e.shaft == "input"))
    assert flagged <= 4 and np.mean(z) < 1.0, (flagged, np.round(z, 1))


def test_a_slower_shafts_own_tsa_holds_the_records_noise_not_the_faster_shafts_lines():
    """Per-shaft TSAs: a faster shaft's lines, at no whole order of a slower shaft, leaked into its average
    and its turn-to-turn scatter (the noise its evidence is weighed by): on 24/79 + 27/72 the output's
    noise at its orders came out up to 2336 times that of the record's noise alone. Each shaft's TSA now
    averages the record less the faster shafts' averages."""
    for teeth in (((24, 79), (27, 72)), ((22, 36), (21, 63)), ((20, 50), (25, 35))):
        table = train(*teeth)
        lay = L.layout(table, POINTS, 100)
        assert lay.mode == "shafts"
        lines = L.content(record(table, 100, np.random.default_rng(0)), lay)
        alone = L.content(0.3 * np.random.default_rng(1).standard_normal((100, POINTS)), lay)
        for s, shaft in enumerate(table.shafts[1:], start=1):
            ratio = lines.noise[lay.source == s] / alone.noise[lay.source == s]
            assert ratio.max() < 4 and np.median(ratio) < 1.1, (
                teeth,
                shaft,
                np.round(np.percentile(ratio, [50, 90, 100]), 2),
            )


def test_a_per_shaft_layout_finds_each_order_s_shafts_in_whole_numbers(monkeypatch):
    # each order k o_s of each shaft was tested against every shaft's order as a Fraction division: 7,500 of them for a
    # 26/63 + 24/77 box at 4096 points (0.35 s of CPU a layout; a three-stage box's 1.5 s), every take and history
    table = train((26, 63), (24, 77))
    divisions = []
    real = Fraction.__truediv__
    monkeypatch.setattr(Fraction, "__truediv__", lambda a, b: divisions.append(1) or real(a, b))
    lay = L.layout(table, 4096, 40)
    monkeypatch.undo()
    assert lay.mode == "shafts" and len(divisions) < 100, len(divisions)
    o = table.shaft_orders
    for s, k, sync in zip(lay.source, lay.index, lay.sync):  # the shafts whose whole turns the order k o_s is
        assert list(sync) == [(int(k) * o[s] / r).denominator == 1 for r in o], (s, k, sync)
