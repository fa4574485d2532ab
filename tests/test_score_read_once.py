"""`gearlab score RUN TAKE` reads the take's file once: its speed, revolutions and the gearbox-fit check all come from
that one reading (cut_recording's keep_read, handed to inspect_record), as a 60 s CSV read twice cost 9 s of CPU
(issue 42). Every read_contents of the file is counted, a reading kept parsed (data.readers.parsed) among them."""

from __future__ import annotations

from detection_scenario import scenario, shared_run
from textrecords import record

from gearlab.data import recordings


def test_score_reads_a_new_take_once(tmp_path, cli, monkeypatch, no_figures):
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    out = shared_run(scenario(tmp_path, methods=("matched_filter",)), tmp_path / "runs")
    take = record(tmp_path / "new_chip.zip", revolutions=40, chip=4.0, seed=12, phase=1.1)
    reads, parsed = [], recordings.parsed

    def counted(fmt, path, names):
        reads.append((path.name, tuple(names)))
        return parsed(fmt, path, names)

    monkeypatch.setattr(recordings, "parsed", counted)
    code, _, err = cli("score", out, take, "--json")
    assert code == 0, err
    assert [name for name, _ in reads].count("new_chip.zip") == 1, reads
