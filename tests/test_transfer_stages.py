"""The `transfer` kind tells its front-end every step (issue 41: no stage silent for more than 5 s):
the Bayes bound, which takes seconds (the target's noise-free twin, its likelihood ratios), is a
stage of its own between the datasets and the training runs; the shared states say their epochs;
the figures and report.html (every kind's last step, gearlab.events.telling_figures) are a stage."""

from __future__ import annotations

from tiny import transfer

from gearlab.engine import run_scenario


def test_the_bayes_bound_and_the_report_are_stages_of_their_own(tmp_path, monkeypatch):
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    path = tmp_path / "tiny.toml"
    path.write_text(transfer('[[methods]]\nadapter = "source_only"\n', max_epochs=2))
    events = []
    run = run_scenario(path, out=tmp_path / "runs", on_event=events.append)
    assert (run.path / "bound.json").exists()  # the tiny target is simulated with noise: there is a bound
    stages = [(e.kind, e.stage) for e in events if e.kind in ("stage", "advance") and e.stage]
    assert ("stage", "bound") in stages and ("advance", "bound") in stages
    begin, end = stages.index(("stage", "bound")), stages.index(("advance", "bound"))
    done = max(i for i, s in enumerate(stages) if s == ("advance", "datasets"))
    assert done < begin < end < stages.index(("stage", "runs"))  # after the datasets, before the runs
    bound_logs = [e for e in events if e.kind == "log" and "Bayes bound" in e.message]
    assert bound_logs  # what the stage does is said while it runs
    # the run's end (its figures, then report.html) is a stage of its own too, a step per figure
    figures = sorted(p.name for p in (run.path / "figures").iterdir())
    report = [e for e in events if e.stage == "report"]
    assert stages.index(("stage", "report")) > max(i for i, s in enumerate(stages) if s == ("advance", "runs"))
    assert [e.done for e in report if e.kind == "advance"] == [*range(1, len(figures) + 1), len(figures)]
    assert report[-1].total == len(figures) >= 2 and report[0].message == "figures and report.html"


def test_the_priming_and_the_source_model_say_how_far_they_are():
    """The shared states a repetition's first units train (the priming of the calibrated methods,
    the source-only model) took a minute of a quick run's 'priming 0/4' with no line under the bar
    (issue 41): their epochs reach the unit's progress as 'priming, epoch i of n'."""
    from test_protocol import SOURCE, TARGET, method, tiny

    from gearlab.learn.protocol import StateStore, run_unit

    p = tiny(methods=(method("source_only"), method("mmd")), prime_epochs=2, baseline_epochs=3, patience=3)
    for m, what in zip(p.methods, ("source model, epoch {} of 3", "priming, epoch {} of 2")):
        said: list[str] = []
        run_unit(p, SOURCE, TARGET, 0, 0, m, StateStore(None), on_epoch=lambda e, h, text="", to=said: to.append(text))
        shared = [t for t in said if t]  # the unit's own epochs say nothing more (text "")
        assert shared == [what.format(i) for i in range(1, 4 if m.adapter == "source_only" else 3)], (m, said)
