"""`gearlab validate` and the TUI's palette Validate say the same of a detection scenario: a history its takes'
tachos show too short for its units (kinds.detection_screen) is refused by both, in the run's own line, where the
TUI once said OK (gearlab.validate_scenario, the one check both call)."""

from __future__ import annotations

from gearboxes import description, stage
from test_csv_footer import _rows, _write
from test_score_keys import BOX, DETECT, record
from test_tui import drive

from gearlab.tui import GearlabApp

HISTORY = '{ file = "h.csv", role = "history", label = "healthy" }'
TEST = '{ file = "t.csv", role = "test", label = "healthy" }'


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

    async def script(pilot):
        app = pilot.app
        notices, notify = [], app.notify
        app.notify = lambda message, **kw: notices.append((message, kw.get("title"))) or notify(message, **kw)
        (entry,) = [e for e in app.entries if e.path.name == "s.toml"]
        app._validate(entry)
        await pilot.pause()
        assert notices == [(refusal, "invalid")], notices

    drive(GearlabApp(folder), script)


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

    async def script(pilot):
        app = pilot.app
        notices, notify = [], app.notify
        app.notify = lambda message, **kw: notices.append((message, kw.get("title"))) or notify(message, **kw)
        (entry,) = [e for e in app.entries if e.path.name == "s.toml"]
        app._validate(entry)
        await pilot.pause()
        assert notices == [(out.strip(), "valid"), (err.strip().removeprefix("warning: "), "warning")], notices

    drive(GearlabApp(folder), script)
