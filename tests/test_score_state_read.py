"""`gearlab score` reads a run's saved scoring state as its takes use it: a condition's localisation state holds
the envelope's history in each of dozens of bands (992 arrays in the tiny run's), and a take is read in one band, so
reading every array at each call (0.12 s of CPU) paid for what no take read. The rows are those of the state read
whole."""

from __future__ import annotations

from detection_scenario import scenario, shared_run
from textrecords import signals, text, write_zip

from gearlab.kinds.detection_scoring import score
from gearlab.parts import scoring
from gearlab.runs import RunDir


def test_a_score_reads_the_saved_arrays_its_take_reads_with_the_rows_of_the_whole_state(
    tmp_path, module_cache, monkeypatch
):
    run = shared_run(scenario(tmp_path, methods=("matched_filter",)), tmp_path / "runs")
    vib, tacho = signals(revolutions=40, seed=31, chip=4.0, phase=0.3)
    take = str(write_zip(tmp_path / "take.zip", text(vib, tacho)))
    load, loaded = scoring.load_arrays, []

    def counted(source):
        loaded.append(load(source))
        return loaded[-1]

    monkeypatch.setattr(scoring, "load_arrays", counted)
    rows = score(RunDir(run), [take])
    (state,) = [a for a in loaded if "envelope_bands" in a]  # the localisation's
    assert len(state) > 500
    assert 0 < len(state._read) < len(state) / 4

    monkeypatch.setattr(scoring, "load_arrays", lambda source: dict(load(source)))  # every array read
    whole = score(RunDir(run), [take])
    assert [{k: v for k, v in r.items() if k != "already"} for r in whole] == rows
