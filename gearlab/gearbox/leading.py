"""Which of check_description's differences a verdict leads with (gearlab.gearbox.match): the gear read outward
from a tacho on a later shaft (outward, outward_first), or a later stage read on a weak line beside a far stronger
family (gearbox.outshone; inspect_first). `gearlab inspect` and the gap's structure check (gearlab.gap.structure)
both pick by these, from the findings' fields (kind, stage, gear, guess, follows), not their words, so both name
the same gear from the same lines.
"""

from __future__ import annotations

from .description import Gearbox
from .match import wheel_upstream
from .orders import order_table


def outward(stages: list[dict], box: Gearbox, tacho: int, origin: str = "") -> tuple[dict, str] | None:
    """The first gear, read outward from the tacho's shaft (index *tacho*, after the input), whose tooth
    count check_description's *stages* (read with that tacho) contradict: ({stage, gear, seen, described},
    its line), or None. A stage's mesh, in orders of its shaft nearer the tacho, is that gear's count while
    every gear between is as described; the far gear's count is its shaft's sidebands of the mesh. A wrong
    gear puts every stage beyond it off (Q, 38/89 + 49/95 with an output tacho, described with a 48-tooth
    later pinion: the input read 2 % slow, stage 1's mesh at 37.2); the nearest stage first, the input's
    side after the output's at one distance. The gap's structure check and inspect both read it. *origin*:
    what the reading starts from, where no tacho gives it (default: the tacho on its shaft)."""
    table = order_table(box)
    found = []
    for side in (range(tacho + 1, len(stages) + 1), range(tacho, 0, -1)):  # stage numbers, outward
        for k in side:
            entry, s = stages[k - 1], table.stages[k - 1]
            wheel_near = k <= tacho  # the stage's wheel on the tacho's side of it
            near = k if wheel_near else k - 1
            gears = [("wheel", s.wheel_teeth, "z2"), ("pinion", s.pinion_teeth, "z1")][:: 1 if wheel_near else -1]
            if entry.get("measured_order") is None:  # no line where the near gear would mesh: beyond here unread
                break
            z = entry["measured_order"] / float(table.shaft_orders[near])
            role, said, _ = gears[0]
            # no whole count of the pinion, a whole one of the wheel before it on its shaft: that wheel (16/52 + 34/40
            # described with 51: 'the pinion shows 33.3 teeth'; 28/76 + 19/65 with 75, 18.75 of its 19: unsaid)
            ratio, up = entry["measured_order"] / entry["expected_order"], ""
            if not entry["matched"] and not wheel_near and k - 1 > tacho:
                up = wheel_upstream(table, k - 1, ratio, z)
            if not entry["matched"] and (round(z) != said or up):
                why = f"the stage-{k} mesh at {z:.1f} orders of the {table.shafts[near]} shaft"
                found.append((abs(near - tacho), k, role, z, said, f"the {role} shows {z:.1f} teeth ({why})"))
                if up:
                    wheel, up = table.stages[k - 2].wheel_teeth, up.split(" puts it there")[0]
                    why += f", no whole count of its pinion{up} puts it there"
                    found[-1] = (abs(near - tacho), k - 1, "wheel", wheel / ratio, wheel, why)
                break
            role, said, key = gears[1]
            seen, spread = entry.get(f"{key}_seen"), entry.get(f"{key}_resolution") or 0.0
            if seen is None:  # the far shaft's order not seen: the stages beyond are read at its described one
                continue
            if abs(seen - said) > max(0.5, spread):
                evidence = f"the {role} shows {seen:.1f} ± {spread:.1f} teeth (its shaft's sidebands of the mesh)"
                found.append((abs(near - tacho), k, role, seen, said, evidence))
                break
    if not found:
        return None
    _, k, role, z, said, evidence = min(found, key=lambda f: f[:2])
    count = f"{round(z)}" if abs(z - round(z)) <= 0.25 else f"{z:.1f}"
    line = (
        f"stage {k} {role}: {count} teeth fit the recording, {said} described; read outward from "
        f"{origin or f'the tacho on the {table.shafts[tacho]} shaft'}, {evidence}, {said} expected"
    )
    return {"stage": k, "gear": role, "seen": float(z), "described": int(said)}, line


def outward_first(check: dict, box: Gearbox, tacho: int) -> dict | None:
    """*check*'s differences (check_description's, read with a tacho on shaft *tacho* after the input) led by the
    stage the outward reading (outward) finds, in place: its own findings first (else outward's line), the
    stages beyond it (farther from the tacho, read at a speed its difference moved) marked as following
    from it. A 31/77 + 23/58 reducer with an output tacho, described with a 24-tooth second pinion, was
    told 'stage 1: no line at mesh order 31' first, as if a second difference. Returns the outward record,
    or None (unchanged)."""
    findings = check["findings"]
    found = outward(check["stages"], box, tacho) if findings else None
    if found is None:
        return None
    k, role = found[0]["stage"], found[0]["gear"]

    def distance(j: int) -> int:
        return abs((j if j <= tacho else j - 1) - tacho)

    # its own findings but those check_description reads as following from another stage (read inward from the
    # input: a 111/157 + 115/173 box with an output tacho, described with a 172-tooth wheel, was told first
    # 'stage 2: mesh order 81.78 measured, 81.31 expected, as follows from stage 1's difference'), or that guess a
    # count for the stage's other gear than the one outward found
    own = [f for f in findings if f["stage"] == k and not f["follows"] and f["guess"] in (None, role)]
    own = own or [dict(kind="outward", stage=k, gear=role, guess=None, follows=[], text=found[1], bare=found[1])]
    rest = []
    for f in (f for f in findings if f["stage"] != k):
        if f["stage"] is None or distance(f["stage"]) <= distance(k):
            rest.append(f)
            continue
        # beyond it: read at the speed its difference moves, so no other count is guessed there, nor another stage
        # followed from (the same box was also told 'stage 1: ... (a 112-tooth pinion on the input shaft? described
        # 111)')
        text = f"{f['bare']}, as follows from stage {k}'s difference (read at the speed it moves)"
        rest.append(f | dict(guess=None, follows=[k], text=text))
    findings[:] = own + rest
    check["differences"][:] = [f["text"] for f in findings]
    return found[0]


def inspect_first(stages: list[dict]) -> tuple[dict, str] | None:
    """(the gear, its line) check_description leads inspect's verdict with where a later stage was read on a weak
    line beside a far stronger family (gearbox.outshone), or None: the gap names what inspect names from the same
    lines. 39/109 + 44/93 + 62/101 described with 108 (or 110): outward read stage 2 on its own sideband and named
    'stage 2 wheel: 94 teeth' ('stage 3 pinion: 62.6' with 110) where inspect named the 109-tooth wheel."""
    for entry in stages:
        if "outshone" in entry:
            return entry["outshone"]["gear"], entry["outshone"]["line"]
    return None
