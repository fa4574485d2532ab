"""Measured data through a dataset scenario: a file written by `gearlab simulate` is imported
through the same pipeline as a third party's recording."""

import json

import numpy as np


def test_dataset_scenario_imports_a_measured_file(cli, run_scenario, tmp_path, monkeypatch, unrendered_figures):
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    code, _, err = cli(
        "simulate", "--model", "six_dof", "--preset", "meng2020", "--duration", "0.3", "--out", tmp_path / "rec.npz"
    )
    assert code == 0, err
    run = run_scenario(
        '[scenario]\nname = "measured"\nkind = "dataset"\n\n'
        '[[datasets]]\nfile = "rec.npz"\nname = "bench"\nvibration = "pinion_y"\ntacho = "tacho"\n'
    )
    summary = json.loads((run / "summary.json").read_text())
    bench = summary["datasets"]["bench"]
    assert bench["shape"][1] == 4096
    assert 10 <= bench["n"] <= 12  # 12 revolutions at 40 Hz in 0.3 s, minus any start-up transient


def test_measured_entry_needs_exactly_one_source(cli, write_scenario, tmp_path):
    bad = write_scenario('[scenario]\nname = "m"\nkind = "dataset"\n\n[[datasets]]\npreset = "B-6"\nfile = "x.npz"\n')
    code, _, err = cli("validate", bad)
    assert code == 2 and "exactly one of 'preset'" in err
    # no 'vibration': the file's one signal channel, so a file of two needs the key
    np.savez(tmp_path / "x.npz", acc=np.zeros(10), axial=np.zeros(10), fs=np.array(1e3))
    bad = write_scenario('[scenario]\nname = "m"\nkind = "dataset"\n\n[[datasets]]\nfile = "x.npz"\n', "b.toml")
    code, _, err = cli("validate", bad)
    assert code == 2 and "key 'vibration': missing, and" in err and "has 2 signal channels (acc, axial)" in err
