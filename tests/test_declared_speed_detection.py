"""A detection run's declared speed that the history's mesh lines refuse stops the run, as the gap's does.

Without a tacho, [target] speed is read nominal (±1 % searched about it); where no history record's mesh lines
confirm it, a record is read at the declared speed whole. The gap diagnosis then stops with one line
(gap_inputs); the detection kind trained and scored on: a one-stage 29/73 box at 24.4 Hz, described as 28/73
(or given its output shaft's 584 rpm) gave a report at AUC 0.31-0.39 and no word of the difference.
"""

from __future__ import annotations

import numpy as np
import pytest
from gearboxes import description, stage

from gearlab.engine import load_scenario
from gearlab.kinds.detection_records import check_structure, read_target


def _box(path, seed: int) -> None:
    """A 29/73 box at 24.4 Hz (1464 rpm) in m/s², no tacho, tab-separated with a 'time' column: each mesh
    harmonic modulated by both shafts, white noise."""
    fs, f = 8000.0, 24.4
    t = np.arange(int(40 / f * fs)) / fs
    theta = 2 * np.pi * f * t
    mod = 1 + 0.2 * np.cos(theta + 0.4) + 0.15 * np.cos(29 / 73 * theta + 1.0)
    x = sum(mod * np.cos(h * 29 * theta + 0.7 * h) / h for h in (1, 2, 3))
    x = x + np.random.default_rng(seed).normal(0, 0.05, t.size)
    np.savetxt(path, np.column_stack([t, x]), fmt="%.6f", delimiter="\t", header="time\tacc_ms2", comments="")


def _scenario(folder, z1: int, speed: str | None) -> None:
    """Three takes h1, h2 (history) and t1 (test) of the 29/73 box, the box described with *z1* pinion teeth, and
    detect.toml reading them (with [target] speed = *speed* where given)."""
    for name, seed in (("h1", 0), ("h2", 1), ("t1", 2)):
        _box(folder / f"{name}.txt", seed)
    (folder / "box.toml").write_text(
        description(stage(z1, 73, module="2.5 mm"), name="box", speed="1480 rpm", load="40 N*m")
    )
    files = ", ".join(
        f'{{ file = "{n}.txt", role = "{r}", label = "{lab}" }}'
        for n, r, lab in (("h1", "history", "healthy"), ("h2", "history", "healthy"), ("t1", "test", "fault"))
    )
    declared = f'speed = "{speed}"\n' if speed else ""
    (folder / "detect.toml").write_text(
        '[scenario]\nname = "d"\nkind = "detection"\n[source]\ngearbox = "box.toml"\nfaults = { chip = [20] }\n'
        f'[target]\nvibration = "acc_ms2"\n{declared}files = [{files}]\n[detection]\nblocks = [10]\n'
    )


@pytest.mark.parametrize(
    ("z1", "declared", "differs"),
    [(29, "1480 rpm", False), (28, "1480 rpm", True), (29, "584 rpm", True)],
    ids=["right", "a tooth count off", "the output's speed"],
)
def test_a_declared_speed_no_history_line_confirms_stops_the_detection_run(tmp_path, z1, declared, differs):
    _scenario(tmp_path, z1, declared)
    spec = load_scenario(tmp_path / "detect.toml").spec
    conditions = read_target(spec.target, spec.detection.blocks, lambda e: None)
    where = "detect.toml: [source] key 'gearbox'"
    line = check_structure(spec.source, spec.target, conditions, where)
    if not differs:
        assert line is None
        return
    assert line is not None and "\n" not in line
    assert line.startswith(f"{where}: the history of condition ")
    assert "declared, but no history record's mesh lines confirm it (h1.txt: " in line
    assert "gearlab inspect h1.txt --gearbox" in line


def test_a_data_file_refused_during_a_run_is_named_with_its_scenario(tmp_path, cli):
    # a record's reading names its entry by table alone ("[target] key 'files' entry 1 key 'file': h1.txt: ..."):
    # the run's one line had no scenario in front, where every other line names it
    _scenario(tmp_path, 29, None)
    lines = (tmp_path / "h1.txt").read_text().splitlines()
    lines[500] = lines[500].split("\t")[0] + "\tn/a"  # a logger's dropout, past the header validate reads
    (tmp_path / "h1.txt").write_text("\n".join(lines) + "\n")
    code, _, err = cli("run", tmp_path / "detect.toml", "--out", tmp_path / "runs")
    assert code == 2, err
    line = err.strip().splitlines()[-1]  # after the run's progress lines
    assert line.startswith(f"error: {tmp_path / 'detect.toml'}: [target] key 'files' entry 1 key 'file': "), line
    assert line.endswith("h1.txt: line 501 column 1: 'n/a' is not a number"), line
