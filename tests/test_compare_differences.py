"""Issue 41 item 3: `gearlab compare` shows the scenario differences beside the figures' differences.
The terminal printed them; its --html page and the TUI's comparison (C) did not."""

import shutil

import pytest
from conftest import ROOT

from gearlab.compare import compare_html, differences_text, load_runs


@pytest.fixture(scope="module")
def two_runs(tmp_path_factory):
    """A quick stiffness run and a copy of it whose scenario asks 8192 points. Run in this process: what is
    compared is two run directories, not how `gearlab run` starts (a `gearlab` child process imported gearlab
    and rendered the run's figures, which nothing here reads: 1.6 s of CPU, against 0.2 s here)."""
    from gearlab.engine import run_scenario

    base = tmp_path_factory.mktemp("compare_differences")
    scenario = ROOT / "scenarios" / "stiffness_verification.toml"
    first = run_scenario(scenario, quick=True, out=base / "runs").path
    second = first.with_name(first.name[:-1] + ("1" if first.name[-1] != "1" else "2"))
    shutil.copytree(first, second)
    toml = second / "scenario.toml"
    toml.write_text(toml.read_text().replace("points = 4096", "points = 8192"))
    return first, second


def test_the_page_and_the_tui_say_what_differs_in_the_scenarios(two_runs, tmp_path):
    first, second = two_runs
    runs = load_runs([first, second])
    assert differences_text(runs) == "scenario differences: stiffness.points A 4096, B 8192"
    page = compare_html(runs, tmp_path)
    assert "<p id='differences'>scenario differences: stiffness.points A 4096, B 8192</p>" in page
    assert differences_text(load_runs([first, first])) == "scenarios: the same (apart from their names)"
