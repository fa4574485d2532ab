"""`gearlab inspect --gearbox`: a pulse tacho on another shaft than the one it is read as, with another count of
marks a turn than the one it is read with. Either alone is told by gearbox.match.tacho_elsewhere (the shaft) and
inspect._tacho_marks (the marks); both together scale every order by their product, which neither tries: a
19/47 + 29/71 reducer's 1-mark output tacho read as the input's 2 reads every order 12.11 x its own (6.056 x 2),
and inspect said 'a 230-tooth pinion on the input shaft? described 19'.
"""

from __future__ import annotations

from .gearbox import Gearbox, order_table
from .gearbox.match import TACHO_SPEED_TOL, tacho_shaft_words, tol_mesh

MARKS = range(1, 9)  # the counts of marks a turn tried, as _tacho_marks tries them


def shaft_and_marks(check: dict, box: Gearbox, read: str, ppr: int, ratio: float | None, bin_: float) -> list[str]:
    """The verdict's line for a tacho of k marks a turn on shaft s read as *ppr* on shaft *read*: every order reads
    f = (o_read / o_s) (ppr / k) times its own. Named where the speed read is 1 / f of the described (*ratio*: read /
    described, within TACHO_SPEED_TOL) and every stage's mesh line lies at f times its order (check_description's
    measured orders, *bin_*: the order resolution); else []. Without a described speed nothing is said: the lines
    alone fit any shaft and count whose product is f."""
    stages = check["stages"]
    if ratio is None or not stages or any(s.get("measured_order") is None for s in stages):
        return []
    table = order_table(box)
    o_read = float(table.shaft_orders[box.shafts.index(read)])
    seen = [(s["expected_order"], s["measured_order"]) for s in stages]
    for name, o in zip(table.shafts, table.shaft_orders):
        for k in MARKS:
            f = o_read / float(o) * ppr / k
            # one alone is the others' to tell; a product near 1 (2 marks on a shaft turning half as fast, read as 1)
            # reads as the right one
            alone = float(o) == o_read or k == ppr or abs(f - 1.0) <= TACHO_SPEED_TOL
            if alone or abs(ratio * f - 1.0) > TACHO_SPEED_TOL:
                continue
            if all(abs(x - f * m) <= tol_mesh(f * m, bin_) for m, x in seen):
                m = seen[0][0]
                return [
                    f"stage 1: mesh order {f * m:.4g} measured, {m:.4g} expected ({tacho_shaft_words(name, f, read)} "
                    f"with {k} pulse(s) per revolution, not {ppr}? (--tacho-shaft {name} --pulses-per-rev {k}, keys "
                    "'tacho_shaft' and 'pulses_per_rev' in a scenario)"
                ]
    return []
