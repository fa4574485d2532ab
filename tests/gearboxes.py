"""Gearbox descriptions as a user writes them (docs/your_gearbox.md), for the tests that need one on
disk: `description(stage(19, 53), name="rig", speed="28 Hz", ...)` is the TOML text. A section or key
left as None is not written, so a test can leave out what it checks is not needed."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np


def stage(z1, z2, module="2 mm", width="20 mm", bores=("20 mm", "20 mm")) -> str:
    """One [[stages]] table: pinion z1 and wheel z2 of *module* and face *width*, on *bores*."""
    gears = f'pinion = {{ z = {z1}, bore = "{bores[0]}" }}\nwheel = {{ z = {z2}, bore = "{bores[1]}" }}\n'
    return f'[[stages]]\nmodule = "{module}"\nface_width = "{width}"\n' + gears


def _table(table: str, **keys) -> str:
    given = "".join(f'{key} = "{value}"\n' for key, value in keys.items() if value is not None)
    return f"[{table}]\n{given}" if given else ""


def description(*stages, name=None, speed=None, load=None, near=None, direction=None, tacho=None, marks=None) -> str:
    """A description's text: [gearbox], [operation], the *stages* (stage() texts), [sensor] (*marks*: the
    tacho's pulses_per_rev, a count written unquoted)."""
    head = _table("gearbox", name=name) + _table("operation", speed=speed, load=load)
    sensor = _table("sensor", near=near, direction=direction, tacho=tacho)
    if marks is not None:
        sensor = (sensor or "[sensor]\n") + f"pulses_per_rev = {marks}\n"
    return head + "".join(stages) + sensor


def reducer_26_63_24_77(**keys) -> str:
    """An outside user's two-stage 26/63 + 24/77 reducer at 45 Hz, the sensor near the input (*keys*: description's
    name, load, tacho ...)."""
    stages = (
        stage(26, 63, bores=("25 mm", "35 mm")),
        stage(24, 77, module="3 mm", width="30 mm", bores=("35 mm", "50 mm")),
    )
    return description(*stages, speed="45 Hz", near="input", **keys)


def described_pair(*stages):
    """A simulator's pair as the gap sees it: stage 1's, carrying the next (StagePair.next_stage)."""
    pair = None
    for z1, z2 in reversed(stages):
        pair = SimpleNamespace(Z1=z1, Z2=z2, next_stage=pair)
    return pair


def two_file_detection(name: str, source: str) -> str:
    """A detection scenario on box.toml whose [source] holds *source* (TOML lines), read against a
    history a.csv and a test b.csv of columns acc and tacho (test_slow_shaft_learned, test_dataset_memory)."""
    files = ", ".join(
        f'{{ file = "{f}", role = "{r}", label = "healthy" }}' for f, r in (("a.csv", "history"), ("b.csv", "test"))
    )
    target = f'[target]\nvibration = "acc"\ntacho = "tacho"\nfiles = [{files}]\n'
    head = f'[scenario]\nname = "{name}"\nkind = "detection"\n\n[source]\ngearbox = "box.toml"\n'
    return f"{head}{source}\n{target}\n[protocol]\nbatch = 2\n"


# the load and sensor of the two-stage reducers of the slower-shaft and train-cycle tests
REDUCER = dict(load="15 N*m", near="input", direction="x")
# outside user AF's 23/59 + 19/67 box at 31 Hz (tests/test_outside_ah, _ak, _al: gearlab's own simulation of it)
AF_BOX = description(
    stage(23, 59, module="2.5 mm", bores=("25 mm", "30 mm")),
    stage(19, 67, module="3 mm", width="25 mm", bores=("30 mm", "40 mm")),
    name="af2359",
    speed="31 Hz",
    load="40 N*m",
    near="input",
    tacho="input",
)

# a 20/30 + 20/50 reducer, tacho on the input: the slower-shaft tests' gearbox (test_slow_shaft*)
SLOW_BOX = description(
    stage(20, 30, "2 mm", "15 mm", ("15 mm", "20 mm")),
    stage(20, 50, "2.5 mm", "20 mm", ("20 mm", "30 mm")),
    name="slowbox",
    speed="30 Hz",
    tacho="input",
    **REDUCER,
)


def shaft_orders(teeth) -> list[float]:
    """Each shaft's turns per input turn of a train of (pinion, wheel) tooth counts, input first."""
    orders = [1.0]
    for z1, z2 in teeth:
        orders.append(orders[-1] * z1 / z2)
    return orders


def mesh_train(theta, teeth, rng, fault, *, noise, level, bump, width, second, third, phase):
    """A train's vibration written by hand (not simulated by gearlab) at input angle *theta*: white
    noise (*noise*), then each stage's mesh harmonics (amplitudes *level*, x *second*, x *third*; 0.7 less
    a stage) amplitude-modulated at its shafts' orders; a *fault* (stage, "pinion" | "wheel", tooth
    counted from the shafts' common zero) lifts its mesh by *bump* for about *width* of a pitch."""
    orders = shaft_orders(teeth)
    x = rng.normal(0.0, noise, theta.size)
    for s, (z1, z2) in enumerate(teeth):
        lift = 1 + 0.15 * np.cos(orders[s] * theta + s) + 0.1 * np.cos(orders[s + 1] * theta + 2 * s)
        if fault is not None and fault[0] == s:
            o, z = (orders[s], z1) if fault[1] == "pinion" else (orders[s + 1], z2)
            off = np.angle(np.exp(1j * (o * theta - 2 * np.pi * (fault[2] - 0.5) / z)))
            lift = lift * (1 + bump * np.exp(-0.5 * (off / (width * 2 * np.pi / z)) ** 2))
        for h, w in ((1, 1.0), (2, second), (3, third)):
            x += level * 0.7**s * w * lift * np.cos(h * z1 * orders[s] * theta + phase * h + s)
    return x


# the end of a detection scenario's text (a format string): two history takes, a fault take, one method
TWO_HISTORIES_ONE_TEST = """files = [
  {{ file = "h1.csv", role = "history", label = "healthy" }},
  {{ file = "h2.csv", role = "history", label = "healthy" }},
  {{ file = "t1.csv", role = "test", label = "fault" }},
]
[[methods]]
adapter = "matched_filter"
"""


def box_s(folder) -> None:
    """An outside user's one-stage 20/47 box at 24.3 Hz, no tacho, the sensor near the input: *folder*/s.toml."""
    stages = stage(20, 47, bores=("25 mm", "40 mm"))
    (folder / "s.toml").write_text(description(stages, name="boxS", speed="24.3 Hz", load="50 N*m", near="input"))


def box_s_gap(folder, file: str, target: str) -> None:
    """*folder*/s.toml (box_s) and *folder*/gap.toml: box S's gap run against the history take *file*;
    *target*: [target]'s other key lines."""
    box_s(folder)
    (folder / "gap.toml").write_text(
        '[scenario]\nname = "u"\nkind = "gap"\n[source]\ngearbox = "s.toml"\n[target]\n'
        f'{target}files = [{{ file = "{file}", role = "history", label = "healthy" }}]\n'
    )


def box_s_take(rng, t: np.ndarray) -> np.ndarray:
    """Box S's vibration in g at times *t*: its 486 Hz mesh (20 x 24.3 Hz), 5 % modulated by the input shaft, and
    0.05 g of noise from *rng*."""
    return (1 + 0.05 * np.cos(2 * np.pi * 24.3 * t)) * np.cos(2 * np.pi * 486 * t) + rng.normal(0, 0.05, t.size)


def box_s_detection(folder, name: str, files, target: str) -> None:
    """*folder*/d.toml: scenario *name*, matched_filter watching box S's pinion for a chip (tooth 18); *files*:
    (file, role, extra keys) all labelled healthy; *target*: [target]'s other key lines."""
    listed = ",\n".join(f'  {{ file = "{f}", role = "{r}", label = "healthy"{extra} }}' for f, r, extra in files)
    (folder / "d.toml").write_text(
        f'[scenario]\nname = "{name}"\nkind = "detection"\n[source]\ngearbox = "s.toml"\nfaults = {{ chip = [18] }}\n'
        f"healthy = 8\n[target]\n{target}files = [\n{listed},\n]\n"
        '[[methods]]\nadapter = "matched_filter"\n[protocol]\nbatch = 4\n'
    )


def inspected(cli, take, *keys) -> dict:
    """`gearlab inspect TAKE KEYS --json`'s report, the command having exited 0."""
    import json

    code, out, err = cli("inspect", take, *keys, "--json")
    assert code == 0, err
    return json.loads(out)


def read_as_described(report: dict, speed_hz: float, orders) -> None:
    """An inspect report that says its description matches, its speed within 0.5 % of *speed_hz* and each stage's
    mesh order within 0.05 of *orders* (what an outside user's round checks first)."""
    assert report["matches"] is True, report["verdict"]
    assert abs(report["speed"]["mean_hz"] / speed_hz - 1) < 0.005, report["speed"]
    measured = [s["measured_order"] for s in report["check"]["stages"]]
    assert len(measured) == len(orders) and all(abs(m - o) < 0.05 for m, o in zip(measured, orders)), measured


def text_rows(fmt: str, *columns) -> str:
    """The rows of *columns* as text, each *fmt* (e.g. "%.6f,%.6f,%.1f") and a newline: the bytes of a "\\n".join of
    f-strings of the same formats and a last newline, formatted in one operation (a 60,000-row take of three
    columns: 0.15 -> 0.05 s of CPU)."""
    table = np.column_stack(columns)
    return ((fmt + "\n") * len(table)) % tuple(table.ravel().tolist())
