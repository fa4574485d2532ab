"""`gearlab score` puts a take in the condition of its load where two conditions run at one speed.

docs/your_gearbox.md step 5 groups takes by load by hand (condition = ...: one per load, NA4 is a size); step 7
scored a new take in the condition of nearest speed alone. On a 29/73 box with a light and a heavy condition
0.04 % apart in speed, a heavy-load history take went to 'light' (level 1.6 x): NA4 called 6 of 6 record30 units,
FM4 4 of 6, a healthy take 'fault'. Of the conditions within IN_BAND of its speed the take now goes to the one
whose history level is nearest its own, and the printout says why.
"""

import json

import pytest
from detection_scenario import run_in_module, scenario
from textrecords import scaled_record

LOUD = 1.6  # the heavy load's level over the light one's


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    folder = tmp_path_factory.mktemp("loads")
    (folder / "data").mkdir()
    files = []
    for name, role, label, seed, scale, cond in (
        ("l1", "history", "healthy", 1, 1.0, "light"),
        ("l2", "history", "healthy", 2, 1.0, "light"),
        ("l3", "test", "fault", 3, 1.0, "light"),  # a label for the report alone
        ("h1", "history", "healthy", 4, LOUD, "heavy"),
        ("h2", "history", "healthy", 5, LOUD, "heavy"),
        ("h3", "test", "healthy", 6, LOUD, "heavy"),
    ):
        scaled_record(folder / "data" / f"{name}.zip", seed, scale)
        files.append((name, role, label, cond))
    path = scenario(folder, files=[(n, r, lab, 0.0) for n, r, lab, _ in files], methods=("matched_filter",))
    text_ = path.read_text()
    for name, _, _, cond in files:  # each file's condition, by hand
        text_ = text_.replace(f'"../data/{name}.zip",', f'"../data/{name}.zip", condition = "{cond}",')
    path.write_text(text_)
    out = run_in_module(path, folder / "runs", figures=False)
    return out, scaled_record(folder / "heavy_new.zip", 9, LOUD), scaled_record(folder / "light_new.zip", 10, 1.0)


def test_a_take_goes_to_the_condition_of_its_level_among_those_at_its_speed(cli, made):
    out, heavy, light = made
    for new, want in ((heavy, "heavy"), (light, "light")):
        code, stdout, err = cli("score", out, new, "--json")
        assert code == 0, err
        rows = json.loads(stdout)
        assert {r["condition"] for r in rows} == {want}, {r["condition"] for r in rows}
        assert all("nearest level" in r["condition_by"] for r in rows)
        assert not any(r["level"] for r in rows)  # in its own condition: no 'level x its history's' warning
    code, printed, err = cli("score", out, heavy)
    assert code == 0, err
    assert "condition heavy (nearest level of those at its speed: " in printed


def test_a_condition_asked_is_kept(cli, made):
    out, heavy, _ = made
    code, stdout, err = cli("score", out, heavy, "--condition", "light", "--json")
    assert code == 0, err
    rows = json.loads(stdout)
    assert {r["condition"] for r in rows} == {"light"} and not any(r["condition_by"] for r in rows)
    assert all(r["level"] for r in rows)  # 1.6 x its history's, said
