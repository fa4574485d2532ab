"""A detection run's figures drawn side by side in the run's pool of workers (issue 42: phm09_chip drew its
9 figures one after the other, ~21 s of CPU with the other core idle): the same files, byte for byte,
as drawn in the run's own process; a caller's own gearlab.plots.save is still the one called."""

import shutil
from pathlib import Path

import pytest
from detection_scenario import run_in_module, scenario

from gearlab.executors import LocalExecutor
from gearlab.kinds import detection_figures
from gearlab.kinds.detection_figures import draw, drawing_in
from gearlab.runs import RunDir


@pytest.fixture(scope="module")
def finished(tmp_path_factory, module_cache) -> Path:
    """A tiny finished detection run, its figures not drawn."""
    folder = tmp_path_factory.mktemp("figures")
    return run_in_module(scenario(folder), folder / "runs", cwd=folder / "data", figures=False)


def fresh(run: Path, to: Path) -> RunDir:
    shutil.copytree(run, to)
    return RunDir(to)


def figures(run: RunDir) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted((run.path / "figures").iterdir())}


@pytest.mark.slow
def test_figures_drawn_in_the_pool_are_the_figures_drawn_here(finished, tmp_path, monkeypatch):
    here = fresh(finished, tmp_path / "here")
    draw(here)
    assert set(figures(here)) == {"detection_roc.png", "detection_scores_1.png", "detection_time_1.png"}
    pooled = fresh(finished, tmp_path / "pooled")

    def not_here(*args, **kwargs):
        raise AssertionError("drawn in the run's process")

    # the workers import the module afresh: a figure drawn in this process would fail
    monkeypatch.setattr(detection_figures, "_scores_figure", not_here)
    monkeypatch.setattr(detection_figures, "POOLED_FROM", 2)  # a tiny run has three figures
    with LocalExecutor(2) as pool, drawing_in(pool):
        draw(pooled)
    assert figures(pooled) == figures(here)


@pytest.mark.slow
def test_a_callers_own_save_is_called_in_this_process(finished, tmp_path, monkeypatch):
    run = fresh(finished, tmp_path / "run")
    saved = []

    def save(fig, path, **options):
        import matplotlib.pyplot as plt

        plt.close(fig)
        saved.append(path.name)
        return path

    monkeypatch.setattr("gearlab.plots.save", save)
    monkeypatch.setattr(detection_figures, "POOLED_FROM", 2)
    with LocalExecutor(2) as pool, drawing_in(pool):
        draw(run)
    assert sorted(saved) == ["detection_roc.png", "detection_scores_1.png", "detection_time_1.png"]
