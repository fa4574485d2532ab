"""Whether a take `gearlab score` is given is of the run's gearbox: its mesh lines read as `gearlab inspect` reads
them against the run's description (inspect_record's check), and where its speed is no condition's, whether its
tacho reads another shaft or count of marks than the run's keys say."""

from __future__ import annotations

from ..errors import GearlabInputError
from ..gearbox.match import tol_mesh
from ..gearbox.orders import TachoShaft
from .detection_in_band import IN_BAND
from .detection_records import SPEED_GROUP

# the refusal's words for a take whose tooth counts certainly differ (tooth_counts_differ): its scores would weigh
# another gearbox's lines against the run's history, every method calling the changed mesh damage
OTHER_BOX = "a take of another gearbox, not this run's to score"


def tacho_shaft(keys: dict) -> TachoShaft:
    """The shaft the run's tacho read (absent: the input); a TachoShaft, or {name, a, b} as scoring.json keeps it."""
    shaft = keys.get("tacho_shaft")
    return shaft if isinstance(shaft, TachoShaft) else TachoShaft(**(shaft or {"name": "input"}))


def inspected(meta: dict, path: str, keys: dict, speed: float, box=None, read: tuple = ()) -> dict | None:
    """inspect's report of the record at *path* read with the run's *keys* against the run's gearbox description
    (the keys', else *box*: a run with a tacho, the one its source simulates), at the speed of the run's condition
    nearest *speed* where it has no tacho; None where its lines fit, the run has no description, or inspect
    refuses it (the speed's own line is then said). *read*: the record as cut_recording read it (its 'read'): not
    read again; the description's check alone (InspectOptions.check_only: no TSA, no fixed-frequency search)."""
    box = keys.get("gearbox") or box
    if box is None:
        return None
    from ..inspect import InspectOptions, inspect_record

    near = min((c["speed_hz"] for c in meta["conditions"].values()), key=lambda f: abs(f - speed))
    shaft = keys.get("tacho_shaft")
    tacho = None if keys.get("tacho") in (None, "") else str(keys["tacho"])
    options = InspectOptions(
        vibration=None if keys.get("vibration") in (None, "") else str(keys["vibration"]),
        tacho=tacho,
        pulses_per_rev=keys.get("pulses_per_rev") if tacho else None,
        tacho_shaft=None if shaft is None else shaft.name,
        speed_hz=None if tacho else near,
        fs=keys.get("fs"),
        sensitivity=keys.get("sensitivity"),
        gain=keys.get("gain"),
        unit=keys.get("unit"),
        check_only=True,
    )
    try:
        report = inspect_record(path, box, options, read)
    except GearlabInputError:
        return None
    return report if report.get("matches") is False else None


def history_stages(run, meta: dict, name: str, box) -> list[dict] | None:
    """The stages of the run's description *box* as inspect's check reads them off condition *name*'s history
    revolutions laid end to end (as the gap reads a target's: gap.structure_later), each with its 'measured_order';
    None where the run's units are another shaft's turns (meta's unit_shaft: the input's orders are not theirs)."""
    if "unit_shaft" in meta:
        return None
    from ..gap.structure_later import _lines
    from ..gearbox.match import check_description
    from ..parts import scoring

    cond = meta["conditions"][name]
    rows = scoring.load_arrays(run.file("scoring", cond["file"]))["history"]
    return check_description(_lines(rows, cond["max_order"]), box, rows.shape[0], True)["stages"]


def tooth_counts_differ(report: dict, history: list[dict] | None) -> str | None:
    """Where *report* (inspected's) is another gearbox's take for certain, as inspect's check calls a tooth count
    wrong: a stage's mesh line measured off its described order by more than the order resolution allows, at
    another whole count (gearbox.match's 'mesh_moved'), the speed read as said (no tacho misread, a declared speed
    the lines confirm, no other count and speed alike), and off where the run's *history* (history_stages) puts
    that mesh: a run whose history itself shows another count than its description scores takes of that history's
    box. What the history shows where it is not the described ('' where it is); None where no count differs so.
    A damaged tooth leaves the mesh where it is (a chip or a crack of EJ's 33/97 + 26/119 box: the description
    matches); a stage with no line at its mesh order (a weak mesh), or a history that does not show it, is no such
    certainty."""
    check = report["check"]
    if check.get("tacho_misread") or check.get("speed_confirmed") is False or check["ambiguous"] or not history:
        return None
    bin_, moved = report["order_resolution"], []
    for f in check.get("findings", ()):
        took = check["stages"][f["stage"] - 1] if f["kind"] == "mesh_moved" else {}
        had = history[f["stage"] - 1] if took else {}
        if took.get("measured_order") is None or had.get("measured_order") is None:
            continue
        if abs(took["measured_order"] - had["measured_order"]) > tol_mesh(had["measured_order"], bin_):
            moved.append(had)
    if not moved:
        return None
    own = [f"stage {h['stage']}'s mesh at order {h['measured_order']:.4g}" for h in moved if not h.get("matched")]
    return f"the run's history shows {' and '.join(own)}" if own else ""


def other_gearbox(meta: dict, path: str, keys: dict, speed: float, far: bool = True, box=None, read=()) -> str | None:
    """gearbox_line of the record at *path* (inspected)."""
    report = inspected(meta, path, keys, speed, box, read)
    return gearbox_line(report, path, keys.get("gearbox") or box, speed, far)


def gearbox_line(
    report: dict | None, path: str, box, speed: float, far: bool = True, other: str | None = None
) -> str | None:
    """The line of a record whose mesh orders do not fit the run's gearbox description *box*, as inspect read it
    (*report*, inspected's: "stage 2: mesh order 9.706 measured, 10.98 expected"); None where they fit. A 24/83
    box's record scored by a 21/65 + 34/91 box's run (no tacho: the speed from the mesh orders) was told only
    'runs at 51.78 Hz, more than 5 % from every condition': its 24th order read as stage 2's 10.98th. Not *far*:
    the record's *speed* is a condition's; *other* not None (tooth_counts_differ's words): a tooth count differs for
    certain, the line refuses it (EJ's rebuilt 26 -> 27-tooth pinion was called 'other damage' by every method);
    else it says its scores weigh another gearbox against the run's history (a warning: it is scored)."""
    if report is None:
        return None
    from ..gearbox import order_table

    said = report["check"].get("differences") or [report["verdict"]]
    if far and report["check"].get("tacho_misread"):
        # a tacho read on another shaft or count of marks (inspect_tacho): the mesh as read, the shaft and marks
        # left to moved_tacho's --key words (inspect's own, its options, made the one line too long to show)
        said = [d.split(" (", 1)[0] for d in said]
    # the stages' lines ('mesh order x measured, y expected', 'no line at mesh order z'), not the speed's search
    picked = [d for d in said if "mesh order" in d and ("measured" in d or "no line" in d)][:2] or said[:1]
    stages = " + ".join(f"{s.pinion_teeth}/{s.wheel_teeth}" for s in order_table(box).stages)
    said = f"{path}: its lines do not fit the run's gearbox '{box.name}' ({stages}): {'; '.join(picked)}; "
    inspect = f"gearlab inspect {path} --gearbox DESCRIPTION says what differs"
    if not far and other is not None:
        return f"{said}{other and other + '; '}{OTHER_BOX}; expected a take of the run's gearbox ({inspect})"
    if not far:
        return f"{said}its scores weigh another gearbox against the run's history ({inspect})"
    return (
        f"{said}its speed read as {speed:.2f} Hz is more than {SPEED_GROUP:.0%} from every condition's; expected a "
        f"record of that gearbox ({inspect})"
    )


def moved_tacho(meta: dict, path: str, keys: dict, speed: float, box, read: tuple = ()) -> str:
    """'; or ...' for a take whose tacho reads another shaft or count of marks than its *keys* say, its *speed*
    read no condition's: the one shaft of the run's description *box* (the input alone without one) and count of
    marks a turn (1-8) at which it runs within IN_BAND of a condition's speed and, with a description, its mesh
    lines fit it (inspected: inspect with those keys), with the --key that reads it so; "" where none or
    several fit. A 21/59 box's 2-mark output tacho read as the input's once a turn: 17.80 Hz, not 25 Hz."""
    if keys.get("tacho") is None:
        return ""
    read_as, pulses = tacho_shaft(keys), keys.get("pulses_per_rev") or 1
    shafts = [TachoShaft.of(box, name, "[sensor]") for name in box.shafts] if box is not None else [TachoShaft("input")]
    fits = []
    for shaft in shafts:
        for marks in range(1, 9):
            # the tacho's pulses a second over the input's turns: speed x pulses x read turns, as marks x shaft turns
            true = speed * pulses * float(read_as.turns) / (marks * float(shaft.turns))
            conditions = meta["conditions"].items()
            near = [c for c, v in conditions if abs(true - v["speed_hz"]) <= IN_BAND * v["speed_hz"]]
            if near and abs(true / speed - 1.0) > IN_BAND:
                fits.append((shaft, marks, true, near[0]))
    if box is not None:  # the lines of the take read so: a speed's match alone is one of ~20 tries
        fits = [
            f
            for f in fits
            if inspected(meta, path, keys | {"tacho_shaft": f[0], "pulses_per_rev": f[1]}, f[2], box, read) is None
        ]
    if len(fits) != 1:
        return ""
    shaft, marks, true, condition = fits[0]
    return (
        f"; or its tacho reads the {shaft.name} shaft, {marks} pulse{'s' * (marks > 1)} per revolution: it then runs "
        f"at {true:.2f} Hz, the speed of condition '{condition}' (gearlab score RUN FILE "
        f"--key tacho_shaft={shaft.name} --key pulses_per_rev={marks})"
    )
