"""The later stages of a multi-stage train in the gap's structure check (gearlab.gap.structure, docs/gap.md
"Structure"): each later mesh order read off the target as `gearlab inspect` reads a record (gearbox.match's
check_description), against the source's reading of itself or, with no source, against the description as inspect
judges it; and the reading the structure check shares with it (the train as gearbox.order_table reads it, the
revolutions' lines, a wheel's count off its shaft's sidebands).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class _Stage:
    index: int
    pinion: object
    wheel: object


@dataclass(frozen=True)
class _Gear:
    z: int


@dataclass(frozen=True)
class _PairDescription:
    """The source's gear pair as the one-stage description gearlab.gearbox.order_table reads."""

    stages: tuple
    shafts: tuple = ("input", "output")

    @classmethod
    def of(cls, z1: int, z2: int) -> _PairDescription:
        return cls((_Stage(1, _Gear(int(z1)), _Gear(int(z2))),))

    @classmethod
    def train(cls, pair) -> _PairDescription:
        """Every stage of a simulator's pair: a two-stage model's carries the next (StagePair.next_stage)."""
        stages = []
        while pair is not None:
            stages.append(_Stage(len(stages) + 1, _Gear(int(pair.Z1)), _Gear(int(pair.Z2))))
            pair = getattr(pair, "next_stage", None)
        from ..gearbox.description import SHAFT_NAMES

        return cls(tuple(stages), SHAFT_NAMES[len(stages)])


def wheel_shaft(pair) -> str:
    """The shaft of *pair*'s stage-1 wheel as the structure lines name a train's shafts (_PairDescription.train), its
    wheel and its order: what the gap report's output-shaft view resolves, the output shaft of one stage alone, not of
    a longer train ('intermediate 1 shaft (stage 1's 63-tooth wheel, 0.3333 input orders)' on a three-stage one)."""
    from .views import gear_ratio

    z1, z2 = gear_ratio(pair)
    name = _PairDescription.train(pair).shafts[1] if hasattr(pair, "Z1") else "output"
    return f"{name} shaft (stage 1's {z2}-tooth wheel, {z1 / z2:.4g} input orders)"


class Spectra:
    """The spectra, lines and inspect's readings of the revolutions one structure check reads
    (structure.structure_line): it reads one history several ways (mesh_check, inspect's stages, a tacho's misread,
    what passed unchecked), and a long history's spectrum and running median cost seconds a reading (a three-stage
    box's 7 takes of 20 s at 20 kHz: ~45 s each), check_description a quarter of a second. Made per check and dropped
    with it. Keyed on the rows' memory, shape and strides (a view of the same revolutions is the same rows), each held
    while the check lasts so no other array is given their memory; read-only, so no reading changes what the next one
    reads."""

    def __init__(self) -> None:
        self._read: dict = {}

    def _entry(self, rows) -> dict:
        rows = np.asarray(rows, dtype=np.float64)
        key = (rows.__array_interface__["data"][0], rows.shape, rows.strides)
        if key not in self._read:
            from ..signals import spectrum

            orders, amp = spectrum(rows.reshape(-1), rows.shape[1])
            orders.flags.writeable = amp.flags.writeable = False
            self._read[key] = {"rows": rows, "spectrum": (orders, amp)}
        return self._read[key]

    def spectrum(self, rows) -> tuple:
        """(orders, amplitude) of revolutions *rows* (n, P) laid end to end: signals.spectrum at P points a turn."""
        return self._entry(rows)["spectrum"]

    def lines(self, rows, max_order: int):
        """The spectral lines of revolutions *rows* (n, P) laid end to end, as `gearlab inspect` reads a record."""
        from ..gearbox.speed import THRESHOLD_DB, find_lines

        entry = self._entry(rows)
        if max_order not in entry:
            n, points = entry["rows"].shape
            top = 0.9 * (min(max_order, points // 2) if max_order else points // 2)
            found = find_lines(*entry["spectrum"], THRESHOLD_DB, 1.5 / n, top)
            for values in (found.at, found.amp, found.db):
                values.flags.writeable = False
            entry[max_order] = found
        return entry[max_order]

    def check(self, rows, max_order: int, box, on_input: bool, tacho_shaft: int | None = None, beyond=()) -> dict:
        """gearbox.match.check_description of revolutions *rows*' lines (up to *max_order*) against *box*, its tacho
        on the input (*on_input*) or on shaft *tacho_shaft*, the stages *beyond* it left out: taken once a check for
        each such reading (read-only: its readers take from it, none changes it). A tacho on the input is read alike
        given as shaft 0 or as none (check_description reads shaft 0 as no later shaft), so both are one reading."""
        from ..gearbox.match import check_description

        tacho_shaft = None if on_input and tacho_shaft == 0 else tacho_shaft
        key = ("check", max_order, box, bool(on_input), tacho_shaft, tuple(beyond))
        entry = self._entry(rows)
        if key not in entry:
            lines = self.lines(rows, max_order)
            entry[key] = check_description(lines, box, entry["rows"].shape[0], on_input, tacho_shaft, beyond)
        return entry[key]


def _lines(rows: np.ndarray, max_order: int, spectra: Spectra | None = None):
    """The spectral lines of revolutions *rows* (n, P) laid end to end, as `gearlab inspect` reads a record; read
    once per structure check where its *spectra* are given."""
    return (spectra or Spectra()).lines(rows, max_order)


def _inspected(
    rows: np.ndarray, max_order: int, box, on_input: bool, tacho_shaft=None, spectra: Spectra | None = None
) -> dict:
    """gearbox.match.check_description of revolutions *rows* against *box* as `gearlab inspect` reads a record (its
    tacho on the input, or on shaft *tacho_shaft*); taken once per structure check where its *spectra* are given."""
    return (spectra or Spectra()).check(rows, max_order, box, on_input, tacho_shaft)


def wheel_line(mesh: dict, z2: int, role: str = "wheel") -> str | None:
    """The one line of a wheel's (or the *role* 'pinion''s) tooth-count difference (mesh_check's
    reading of its shaft's sidebands, more than half a tooth and its resolution off *z2*), or None."""
    key = "z1" if role == "pinion" else "z2"
    seen, spread = mesh["inspect"].get(f"{key}_seen"), mesh["inspect"].get(f"{key}_resolution") or 0.0
    # read around the described mesh only: a later stage's (the PHM 2009 rig's 48T idler pinion meshing
    # at order 16, read as stage 1's 32/96 by a one-stage reading) gave '47.7 teeth' for the 96T wheel
    # ... or around the mesh found a wheel sideband or two off it, the pinion as described (an output
    # tacho read through a first wheel one tooth off: the mesh at M + M / z2)
    near = mesh["inspect"].get("matched") or mesh["inspect"].get("pinion_as_described")
    if seen is None or not near or abs(seen - z2) <= max(0.5, spread):
        return None
    return (
        f"the {role} shows {seen:.1f} ± {spread:.1f} teeth (its shaft's sidebands of the mesh), {z2} expected: the "
        f"source simulates a {z2}-tooth {role}"
    )


# A later mesh the source puts this far over the target's floor shows there (25 dB over a line's threshold): a source's
# mesh level off the record's by less is a transfer path, more is no such mesh (AM's 29/66 + 22/95 described with 65)
UNSEEN_DB = 40.0


def unseen_mesh(k: int, target: list, source: list) -> str | None:
    """The line saying stage *k*'s mesh is missing from the target where the source reads it (check_description's
    *target* and *source* stages) at a level, under its first mesh, that would put it UNSEEN_DB over the target's
    floor, or None."""
    t1, s1, s = target[0], source[0], source[k]
    if not (s.get("matched") and s1.get("amplitude") and t1.get("amplitude")):
        return None
    over = t1["db_over_floor"] + 20 * np.log10(s["amplitude"] / s1["amplitude"])
    if over < UNSEEN_DB:
        return None
    return (
        f"stage {k + 1}: no line at mesh order {float(s['expected_order']):.4g}, where the source's mesh would stand "
        f"{over:.0f} dB over the target's floor (a tooth count of stage {k + 1}, or a wheel upstream, differs)"
    )


def later_stages(
    target: np.ndarray, source: np.ndarray, pair, max_order: int = 0, spectra: Spectra | None = None
) -> dict:
    """Stages after the first of a multi-stage source: where the target's lines put each stage's mesh order against
    where the source's own lines put it, both read alike (inspect's check_description on each). A later stage's mesh
    is often weak, or held by its harmonics, so it is not tested against the description's order but against the
    source's reading of itself (a mesh of no whole input order: against the description's): the stage differs when
    the target's reading moves off that and the target holds no line there (no *source*: against the described
    order), or when the target holds no line where the source's mesh, at its level under the first mesh, would
    stand UNSEEN_DB over the target's floor. With no *source* the gap knows what inspect knows, and a later mesh the
    target shows no line at differs as inspect says it (check_description's 'no_line'). {'stages': [{stage,
    expected, source, target}], 'line': the one line of the first difference, or None}. *spectra*: the structure
    check's readings (Spectra), or None."""
    from ..gearbox import order_table
    from ..gearbox.match import tol_mesh, wheel_upstream

    box = _PairDescription.train(pair)
    out: dict = {"stages": [], "line": None}
    if len(box.stages) < 2:
        return out
    spectra = spectra or Spectra()  # each history's lines and inspect's reading of them: one spectrum
    table = order_table(box)
    read = {}
    for name, rows in (("target", target), ("source", source)):
        if rows is not None:  # no source: a measured target read against the description alone
            lines = _lines(rows, max_order, spectra)
            check = _inspected(rows, max_order, box, True, None, spectra)
            read[name] = (lines, rows.shape[0], check["stages"])
    for k in range(1, len(box.stages)):
        t, s = read["target"][2][k], read["source"][2][k] if source is not None else {}
        entry = {
            "stage": k + 1,
            "expected": float(table.stages[k].mesh),
            "source": s.get("measured_order"),
            "target": t.get("measured_order"),
        }
        out["stages"].append(entry)
        # A mesh of no whole input order is held by the source at one phase (its revolutions are one
        # steady period each, builder.steady_response): laid end to end they show whole orders only,
        # so its reading of itself says nothing and the target is read against the described order.
        whole = abs(entry["expected"] - round(entry["expected"])) < 1e-6 and source is not None
        reference = entry["source"] if whole else entry["expected"]
        if entry["target"] is None and source is not None and out["line"] is None:
            out["line"] = unseen_mesh(k, read["target"][2], read["source"][2])  # a weak mesh in the noise: None
        if entry["target"] is None and source is None and out["line"] is None and t.get("no_line"):
            # no source to weigh the mesh's level by: inspect's reading of the same lines (a 21/92 + 30/63 box
            # described with 91 teeth: inspect 'no line at mesh order 6.923', the gap 'not fully checked')
            out["line"] = f"{t['no_line']}, as gearlab inspect reads the target: a tooth count of stage {k + 1}, or a "
            out["line"] += "wheel upstream, differs"
        if out["line"] is None and "outshone" in t:  # read on a weak line beside a far stronger family (inspect's)
            out["line"] = t["outshone"]["line"]
        if reference is None or entry["target"] is None or out["line"] is not None:
            continue
        lines, n, _ = read["target"]
        tol = max(tol_mesh(reference, 1.0 / n), tol_mesh(reference, 1.0 / read["source"][1]) if whole else 0.0)
        st = table.stages[k]
        others = [float(t.mesh) for q, t in enumerate(table.stages) if q != k]
        louder = _outshone(lines, reference, st, tol, others)
        if louder is None and (
            abs(entry["target"] - reference) <= tol or _held(lines, reference, entry["target"], st, tol)
        ):
            continue
        if louder is not None:
            entry["target"] = louder
        seen, moved = entry["target"] / float(st.pinion_shaft_order), entry["target"] / entry["expected"]
        out["line"] = (
            f"stage {k + 1}: mesh order {entry['target']:.4g} measured, {entry['expected']:.4g} expected: the source "
            f"simulates a {st.pinion_teeth}-tooth pinion on the {st.pinion_shaft} shaft turning at order "
            f"{float(st.pinion_shaft_order):.4g} (the target's mesh is {seen:.1f} such teeth: a tooth count of "
            f"stage {k + 1}, or a wheel upstream, differs{wheel_upstream(table, k, moved, seen)})"
        )
    # a later wheel: its shaft's sidebands of its mesh, as for the first (wheel_line); the last wheel's
    # count shows nowhere else (a 17/44 + 21/53 reducer described with 52 teeth passed the gap and detection)
    for k in range(1, len(box.stages)):
        line = None if out["line"] else wheel_line({"inspect": read["target"][2][k]}, table.stages[k].wheel_teeth)
        if line:
            out["line"] = f"stage {k + 1}: {line}"
    return out


def _held(lines, reference: float, measured: float, stage, tol: float) -> bool:
    """Whether the target holds the described later mesh at *reference* itself: a line there, unless it
    is a sideband of the stronger mesh *measured* by the pinion's shaft (a pinion j teeth off puts
    its order on the real mesh's j-th sideband: a 26/73 + 32/59 description of a 33-tooth second
    pinion's records, 11.397 = 11.753 - 0.356, was 'unexplained')."""
    at = lines.near(reference, tol)
    if at is None:
        return False
    o = float(stage.pinion_shaft_order)
    real = lines.near(measured, tol)
    sideband = any(abs(reference - measured - j * o) <= tol for j in (-3, -2, -1, 1, 2, 3))
    return not (sideband and real is not None and lines.amp[real] > lines.amp[at])


# A line this many times stronger than the described later mesh's, a pinion-shaft sideband away from
# it, is the real mesh (a mesh's sidebands may outgrow its line by a few dB, not by 20)
OUTSHONE = 10.0


def _outshone(lines, reference: float, stage, tol: float, others: list[float]) -> float | None:
    """The order of a line OUTSHONE x stronger than the one at the described later mesh *reference*,
    j <= 3 of the pinion shaft's orders away and on no other stage's mesh harmonic, or None: a
    27/88 + 21/65 description of a 22-tooth second pinion's records read its own order (6.443,
    the real 6.75's sideband, 34 dB weaker) off the history laid end to end."""
    at = lines.near(reference, tol)
    if at is None:
        return None
    o = float(stage.pinion_shaft_order)
    for j in (1, -1, 2, -2, 3, -3):
        q = lines.near(reference + j * o, tol)
        if q is None or lines.amp[q] < OUTSHONE * lines.amp[at]:
            continue
        x = float(lines.at[q])
        if not any(abs(x - h * m) <= tol for m in others for h in range(1, 11)):
            return x
    return None
