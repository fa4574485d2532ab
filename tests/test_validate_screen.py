"""`gearlab validate` and the TUI's palette Validate say the same of a detection scenario: a history its takes'
tachos show too short for its units, or a test take whose tacho shows a run-up too short at its history's speed
(kinds.detection_screen), is refused by both, in the run's own line, where the TUI once said OK
(gearlab.validate_scenario, the one check both call)."""

from __future__ import annotations

import threading

from gearboxes import description, stage
from test_csv_footer import _rows, _write
from test_outside_fh import BOX as MILL
from test_outside_fh import _sweep, _sweep_scenario
from test_score_keys import BOX, DETECT, record
from test_tui import STIFFNESS, drive, text_of
from textual.widgets import TabbedContent

from gearlab.tui import GearlabApp, validating

HISTORY = '{ file = "h.csv", role = "history", label = "healthy" }'
TEST = '{ file = "t.csv", role = "test", label = "healthy" }'


def one_scenario_held(monkeypatch, tmp_path, validate):
    """tmp_path/scenarios (returned) holding one valid scenario, s.toml; the TUI's validation replaced by *validate*."""
    monkeypatch.setattr(validating, "validate_scenario", validate)
    monkeypatch.chdir(tmp_path)
    folder = tmp_path / "scenarios"
    folder.mkdir()
    (folder / "s.toml").write_text(STIFFNESS.replace("{runs}", "runs"))
    return folder


def _palette_validate(folder) -> list[tuple[str, str]]:
    """(message, title) of each notice the TUI's palette 'Validate s.toml' shows, in *folder*."""
    notices = []

    async def script(pilot):
        app = pilot.app
        notify = app.notify
        app.notify = lambda message, **kw: notices.append((message, kw.get("title"))) or notify(message, **kw)
        (entry,) = [e for e in app.entries if e.path.name == "s.toml"]
        app._validate(entry)
        await app.workers.wait_for_complete()  # validate runs in a worker thread
        await pilot.pause()

    drive(GearlabApp(folder), script)
    return notices


def test_the_tui_s_validate_refuses_a_short_history_as_the_cli_does(tmp_path, cli):
    # one 0.2 s history take of a 21/59 box at 25 Hz (5 input turns, 4 revolution units of the 8 a history needs): the
    # CLI's validate refused it; the palette's 'Validate s.toml' said 'OK: fan (detection); ...'
    folder = tmp_path / "scenarios"
    folder.mkdir()
    (folder / "box.toml").write_text(BOX)
    record(folder / "h.csv", seconds=0.2)
    record(folder / "t.csv", seconds=0.5)
    (folder / "s.toml").write_text(DETECT.format(files=f"{HISTORY}, {TEST}"))
    code, out, err = cli("validate", folder / "s.toml")
    assert code == 2 and "expected at least 8" in err, (out, err)
    refusal = err.strip().removeprefix("error: ")

    assert _palette_validate(folder) == [(refusal, "invalid")]


def test_the_tui_s_validate_says_a_footer_as_the_cli_does(tmp_path, cli):
    # a logger's footer under a gap scenario's take: the CLI's validate warned of it, the palette's said OK alone
    folder = tmp_path / "scenarios"
    folder.mkdir()
    _write(folder / "c.csv", ["time,acc", *_rows(","), "", "End of data", "Samples: 400"])
    (folder / "k.toml").write_text(description(stage(105, 143, "1 mm", "12 mm"), speed="10 Hz", load="30 N*m"))
    text = '[scenario]\nname = "s"\nkind = "gap"\n[source]\ngearbox = "k.toml"\n[target]\nvibration = "acc"\n'
    text += 'unit = "m/s^2"\nfiles = [{ file = "c.csv", role = "history", label = "healthy" }]\n'
    (folder / "s.toml").write_text(text)
    code, out, err = cli("validate", folder / "s.toml")
    assert code == 0 and err.startswith("warning: ") and "End of data" in err, (out, err)

    assert _palette_validate(folder) == [(out.strip(), "valid"), (err.strip().removeprefix("warning: "), "warning")]


def test_validate_refuses_a_test_take_the_run_refuses_for_its_units_at_the_history_s_speed(tmp_path, cli):
    # three steady 3 s history takes of a 39/61 box at 30 Hz and a 3 s test take sweeping 60 % about it: validate said
    # OK, the run stopped at '... holds 7 of its 89 revolutions (7 in the band in all), a unit of every kind needs 30
    # revolutions': the test take's tacho alone shows it, read as the history's are
    (tmp_path / "box.toml").write_text(MILL)
    for i in (1, 2, 3):
        _sweep(tmp_path / f"h{i}.csv", i, sweep=0.0)
    _sweep(tmp_path / "test.csv", 7, sweep=0.6)
    _sweep_scenario(tmp_path / "run.toml")
    code, out, err = cli("run", tmp_path / "run.toml", "--quick", "--out", tmp_path / "runs")
    (line,) = [x for x in err.splitlines() if "a unit of every kind needs" in x]
    assert code == 2 and "test.csv (" in line and "holds 7 of its 89 revolutions" in line, err
    code, out, said = cli("validate", tmp_path / "run.toml")
    assert code == 2 and said.strip() == line, (said, line)
    _sweep(tmp_path / "test.csv", 7, sweep=0.0)  # the same take steady: validate says OK
    code, out, err = cli("validate", tmp_path / "run.toml")
    assert code == 0 and out.startswith("OK: "), err


def test_the_screen_answers_keys_while_a_validation_runs_and_a_second_one_is_refused(tmp_path, monkeypatch):
    # validate_scenario ran on the app's own thread: a detection history's tachos read (14 s of phm09_chip.toml) froze
    # the screen, no key read until it ended. Here a validate held until the test lets it go
    gate, calls = threading.Event(), []

    def held(path):
        calls.append(path.name)
        assert gate.wait(60), "never let go"  # a hung test's bound
        return f"OK: {path.name}"

    folder = one_scenario_held(monkeypatch, tmp_path, held)
    notices = []

    async def script(pilot):
        app = pilot.app
        notify = app.notify
        app.notify = lambda message, **kw: notices.append((message, kw.get("title"))) or notify(message, **kw)
        (entry,) = app.entries
        app._validate(entry)
        await pilot.pause()
        assert text_of(app, "ValidatingLine") == "validating s.toml ... (the keys work meanwhile)"
        await pilot.press("2")  # a key pressed meanwhile is handled
        assert app.query_one("#views", TabbedContent).active == "run" and calls == ["s.toml"] and not notices
        app._validate(entry)  # a second Validate while the first runs: refused, said so
        assert notices == [("validating s.toml already: wait for its result, then validate again", None)]
        assert calls == ["s.toml"]
        gate.set()
        await app.workers.wait_for_complete()
        await pilot.pause()
        assert notices[1:] == [("OK: s.toml", "valid")] and not app.query_one("ValidatingLine").display
        app._validate(entry)  # ended: validated again when asked
        await app.workers.wait_for_complete()
        assert calls == ["s.toml", "s.toml"] and notices[2:] == [("OK: s.toml", "valid")]

    drive(GearlabApp(folder), script)


def test_the_screen_parses_a_text_take_s_tacho_alone_and_refuses_what_the_whole_parse_refuses(tmp_path, cli):
    """The screen parses a text take's tacho column alone (readers.text.asked_numbers_only); a field that is no
    number in another column, which fails the whole parse the run reads with, is seen where the screen would refuse:
    the refusal is then the whole parse's (a history take that does not read is left to the run: OK here, as the
    screen said when it parsed every field)."""
    (tmp_path / "box.toml").write_text(BOX)
    for name, seconds in (("h", 0.2), ("t", 0.5)):  # a history of 4 revolution units, 8 needed
        rows = record(tmp_path / f"{name}.csv", seconds=seconds).read_text().splitlines()
        (tmp_path / f"{name}.txt").write_text("\n".join(r.replace(",", " ") for r in rows) + "\n")
    files = HISTORY.replace("h.csv", "h.txt") + ", " + TEST.replace("t.csv", "t.txt")
    (tmp_path / "s.toml").write_text(DETECT.format(files=files))
    code, out, err = cli("validate", tmp_path / "s.toml")
    assert code == 2 and "expected at least 8" in err, (out, err)
    rows = (tmp_path / "h.txt").read_text().splitlines()
    time_s, acc, tacho = rows[100].split()
    rows[100] = f"{time_s} n/a {tacho}"  # the vibration's field, not the tacho's
    (tmp_path / "h.txt").write_text("\n".join(rows) + "\n")
    code, out, err = cli("validate", tmp_path / "s.toml")
    assert code == 0 and out.startswith("OK: "), (out, err)
