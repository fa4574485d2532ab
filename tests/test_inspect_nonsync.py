"""`gearlab inspect FILE --gearbox G --history ...` shows the non-synchronous evidence a detection run and
`gearlab score` read (gearlab.signals.nonsync): the record less every shaft's synchronous average, its
strongest envelope lines against the history's with their z and the threshold, and the call. Simulated
PHM 2009 rig records at 40 Hz (as tests/test_nonsync.py): bearing-like strikes at 3.57 a turn are
other damage at that order in the terminal and in --json; a healthy take is no change."""

import json

import numpy as np
import pytest
from test_nonsync import REVOLUTIONS, SPEED, STRIKES, strikes

NON_SYNC = "other damage: non-synchronous (bearing-like), at order"


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    from gearlab.data.simulated import simulated_record

    where = tmp_path_factory.mktemp("nonsync")
    out = {}
    for name, seed in (("h1", 1), ("h2", 2), ("ok", 5), ("bearing", 6)):
        rec = simulated_record([], speed_hz=SPEED, revolutions=REVOLUTIONS, snr_db=30.0, seed=seed)
        if name == "bearing":
            rec = strikes(rec, STRIKES, 0.015, 0.3, seed=7)
        np.savez(where / f"{name}.npz", acc=rec.vibration, tacho=rec.tacho, fs=rec.fs)
        out[name] = str(where / f"{name}.npz")
    return out


def _inspect(files, name, *more):
    from typer.testing import CliRunner

    from gearlab.cli import app

    args = ["inspect", files[name], "--gearbox", "phm09", "--vibration", "acc", "--tacho", "tacho"]
    args += ["--pulses-per-rev", "1"]  # the simulated rig's tacho marks each turn once
    out = CliRunner().invoke(app, [*args, "--history", files["h1"], "--history", files["h2"], *more])
    assert out.exit_code == 0, out.output
    return out.stdout


def test_inspect_json_carries_the_strikes_lines_z_threshold_and_call(files):
    loc = json.loads(_inspect(files, "bearing", "--json"))["localisation"]
    ns = loc["nonsync"]
    assert ns["changed"] and ns["z"] > 3 * ns["threshold"], ns
    assert abs(ns["order"] - STRIKES) < 0.02, ns
    assert ns["hz"] == pytest.approx(ns["order"] * SPEED, rel=0.01)
    lines = ns["lines"]
    assert 1 < len(lines) <= 5 and lines[0]["z"] == pytest.approx(ns["z"])  # the strongest first: the record's z
    assert [x["z"] for x in lines] == sorted((x["z"] for x in lines), reverse=True)
    # the strikes' lines: at their order's harmonics
    over = [x["order"] / STRIKES for x in lines if x["z"] > ns["threshold"]]
    assert len(over) > 1 and all(abs(k - round(k)) < 0.02 for k in over), lines
    assert loc["named"] is None, loc["summary"]  # no shaft's average carries it
    assert loc["call"] == f"{NON_SYNC} {ns['order']:.2f}", loc["call"]


def test_inspect_terminal_shows_the_lines_and_the_call(files):
    text = _inspect(files, "bearing")
    ns = json.loads(_inspect(files, "bearing", "--json"))["localisation"]["nonsync"]
    assert "non-synchronous envelope lines" in text
    assert f"{ns['lines'][0]['order']:.2f}" in text and f"{ns['z']:.2f}" in text and f"{ns['threshold']:.2f}" in text
    assert f"{NON_SYNC} {ns['order']:.2f}" in " ".join(text.split())  # the call, however the terminal wraps it


def test_a_healthy_take_reads_no_non_synchronous_change(files):
    loc = json.loads(_inspect(files, "ok", "--json"))["localisation"]
    ns = loc["nonsync"]
    assert not ns["changed"] and ns["z"] <= ns["threshold"], ns
    assert not loc["call"].startswith("other damage"), loc["call"]


def test_inspect_report_html_and_png_show_the_lines_and_the_call(files, tmp_path):
    loc = json.loads(_inspect(files, "bearing", "--json", "--report", str(tmp_path / "out")))["localisation"]
    ns, folder = loc["nonsync"], tmp_path / "out"
    html = (folder / "report.html").read_text()
    assert "non-synchronous envelope lines" in html and f"call: {loc['call']}" in html
    for x in ns["lines"]:
        assert f"<td>{x['order']:.2f}</td>" in html and f"<td>{x['z']:.2f}</td>" in html
    assert f"threshold z {ns['threshold']:.2f}" in html
    for png in ("order_spectrum.png", "nonsync_lines.png"):
        assert f'src="{png}"' in html and (folder / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_takes_too_short_for_the_residual_say_so_in_the_call():
    from gearlab.data.spec import dataset_preset
    from gearlab.gearbox import order_table
    from gearlab.inspect_history import call_of, nonsync_lines
    from gearlab.kinds.detection_which_gear import gearbox_of

    table = order_table(gearbox_of(dataset_preset("phm09-30")))
    take = np.random.default_rng(0).standard_normal((10, 512))  # 10 turns: under one 16-turn block
    ns = nonsync_lines(take, [take, take], table, SPEED)
    assert "z" not in ns and ns["note"].startswith("not read: non-synchronous residual: 10 input revolutions"), ns
    call = call_of({"named": None}, ns)
    assert call == f"no change against the history: nothing localised; non-synchronous {ns['note']}", call
    assert call_of({"named": "input pinion 32T (stage 1)"}, ns) == "localised change: input pinion 32T (stage 1)"
