"""A phase's units go to the pool longest first (issue 42): the short ones fill in behind the
long ones, ties keep their order."""

from gearlab.learn.schedule import longest_first


def test_long_units_first_ties_in_order():
    units = ["a1", "b9", "c1", "d9", "e0", "f1"]
    assert longest_first(units, lambda u: int(u[1])) == ["b9", "d9", "a1", "c1", "f1", "e0"]


def transfer_protocol(repetitions: int = 2):
    from tiny import protocol

    from gearlab.parts.training import method

    entries = [
        ("source_only", False, {}),
        ("target_only", True, {}),
        ("mmd", False, {}),
        ("finetune", True, {"variant": "classifier"}),
        ("likelihood_ratio", False, {}),
    ]
    methods = [method({"adapter": a, "supervised": s, "params": p}, "test") for a, s, p in entries]
    return protocol(methods, ks=(0, 2), repetitions=repetitions)


def test_a_transfer_run_fills_in_behind_its_primings_and_ends_with_short_units(tmp_path):
    """Phase 1: the units that make a shared state in their order (a killed run keeps the first ones,
    tests/test_protocol's resume test), then every unit that needs no state, trainings before the
    detectors; phase 2: the units that load a state, the joint trainings first (issue 42)."""
    from gearlab.kinds.transfer import schedule, units
    from gearlab.learn.protocol import shared_state, unit_key

    p = transfer_protocol()

    def state_file(unit):
        state = shared_state(unit[2], unit[0], unit[1], p)
        return None if state is None else tmp_path / f"{state}.pt"

    first, second = schedule(units(p), state_file, p)
    keys = lambda phase: [unit_key(*u) for u in phase]  # noqa: E731
    assert keys(first) == [
        "rep0/k0/source_only-unsup", "rep0/k0/mmd-unsup", "rep1/k0/source_only-unsup", "rep1/k0/mmd-unsup",
        "rep0/k0/target_only-sup", "rep0/k2/target_only-sup", "rep1/k0/target_only-sup", "rep1/k2/target_only-sup",
        "rep0/k0/likelihood_ratio-unsup", "rep0/k2/likelihood_ratio-unsup",
        "rep1/k0/likelihood_ratio-unsup", "rep1/k2/likelihood_ratio-unsup",
    ]  # fmt: skip
    assert keys(second) == [
        "rep0/k2/mmd-unsup", "rep1/k2/mmd-unsup",
        "rep0/k0/finetune-sup-variant=classifier", "rep0/k2/source_only-unsup",
        "rep0/k2/finetune-sup-variant=classifier", "rep1/k0/finetune-sup-variant=classifier",
        "rep1/k2/source_only-unsup", "rep1/k2/finetune-sup-variant=classifier",
    ]  # fmt: skip
    # resumed with the states made: nothing left to make, the same units each once
    for unit in first[:4]:
        state_file(unit).write_bytes(b"")
    pending = [u for u in units(p) if unit_key(*u) not in {"rep0/k0/source_only-unsup", "rep0/k0/mmd-unsup"}]
    again, rest = schedule(pending, state_file, p)
    assert keys(again) == keys(first)[4:]
    assert sorted(keys(again) + keys(rest)) == sorted(keys(pending))


def test_a_transfer_table_does_not_hang_on_the_order_units_ended_in():
    from gearlab.kinds.transfer import table

    p = transfer_protocol(repetitions=5)
    label = p.methods[2].label
    values = [1e16, 1.0, -1e16, 1.0, 3.0]  # a sum whose rounding depends on its order
    records = [{"method": label, "k": 0, "rep": r, "accuracy": v} for r, v in enumerate(values)]
    assert table(records, p) == table(records[::-1], p) == table(records[2:] + records[:2], p)
