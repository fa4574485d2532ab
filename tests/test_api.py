"""The notebook API (gearlab/__init__.py, gearlab.notebook; docs/api.md, issue 38 item 5): the page's
```python blocks run in order in one namespace, each `# prints:` line the start of a line its
block printed (a verdict may go on with notes); every docstring example runs (doctest);
`import gearlab` stays light and every name it offers resolves; the functions refuse bad input
in one line.

Runs in a fresh folder with a fresh dataset cache: about 20 s for the page and 30 s for the
docstrings on a busy core (small datasets, a gap diagnosis of one candidate at budget 4)."""

from __future__ import annotations

import contextlib
import doctest
import io
import json
import re
import subprocess
import sys

import numpy as np
import pytest
from conftest import ROOT

import gearlab
import gearlab.notebook
from gearlab.errors import GearlabInputError

PAGE = ROOT / "docs" / "api.md"
FENCE = re.compile(r"^```python\n(.*?)^```$", re.M | re.S)


@pytest.fixture
def workdir(tmp_path, monkeypatch, unrendered_figures):
    """A fresh folder and cache; the runs' figures written unrendered (these tests read what the
    API returns and prints, no figure's pixels: test_cli and test_verdict read those)."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("GEARLAB_CACHE", str(tmp_path / "cache"))
    return tmp_path


def test_the_page_runs_and_prints_what_it_says(workdir):
    blocks = FENCE.findall(PAGE.read_text())
    assert len(blocks) >= 6
    namespace: dict = {"__name__": "api_md"}
    for i, block in enumerate(blocks, start=1):
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            exec(compile(block, f"docs/api.md block {i}", "exec"), namespace)
        printed = out.getvalue().splitlines()
        for line in block.splitlines():
            if line.startswith("# prints: "):
                expected = line.removeprefix("# prints: ")
                assert any(p.startswith(expected) for p in printed), (i, line, printed)
    # the page shows every step of the API
    used = set(re.findall(r"gearlab\.(\w+)\(", "\n".join(blocks)))
    assert used == set(gearlab._API), set(gearlab._API) ^ used


DOCTESTS = [t for t in doctest.DocTestFinder().find(gearlab.notebook) if t.examples]


def test_every_function_of_the_api_has_a_docstring_and_most_an_example():
    names = set(gearlab._API)
    assert names == set(gearlab.notebook.__all__)
    for name in names:
        assert (getattr(gearlab, name).__doc__ or "").strip(), name
    with_example = {t.name.rpartition(".")[2] for t in DOCTESTS}
    # the two that read a run someone made before are shown on docs/api.md instead
    assert names - with_example == {"open_run", "run_verdict"}


@pytest.mark.parametrize("test", DOCTESTS, ids=[t.name.rpartition(".")[2] for t in DOCTESTS])
def test_the_docstring_example_runs(test, workdir):
    test.globs = {**test.globs, "gearlab": gearlab}
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    out = io.StringIO()
    result = runner.run(test, out=out.write)
    assert result.failed == 0, out.getvalue()


def test_import_gearlab_loads_nothing_heavy_and_every_name_resolves():
    code = (
        "import sys, json, gearlab\n"
        "heavy = ('torch', 'numba', 'scipy.stats', 'sklearn', 'matplotlib')\n"
        "before = [m for m in heavy if m in sys.modules]\n"
        "names = {n: callable(getattr(gearlab, n)) for n in gearlab._API}\n"
        "after = [m for m in heavy if m in sys.modules]\n"
        "print(json.dumps([before, after, names, 'simulate' in dir(gearlab)]))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-3000:]
    before, after, names, listed = json.loads(done.stdout.strip().splitlines()[-1])
    assert before == [] and after == []  # resolving the names imports no heavy module either
    assert names and all(names.values()) and listed
    with pytest.raises(AttributeError, match="no attribute 'simulat'"):
        gearlab.simulat  # noqa: B018


def test_bad_input_is_one_line_naming_the_key(workdir):
    with pytest.raises(GearlabInputError, match=r"gearlab.simulate: \[datasets\] key 'teeth': expected a list"):
        gearlab.simulate("B-6-ch5", teeth=3)
    with pytest.raises(GearlabInputError, match=r"key 'helthy': unknown key \(did you mean 'healthy'"):
        gearlab.simulate("B-6-ch5", helthy=3)
    with pytest.raises(GearlabInputError, match=r"unknown dataset preset 'B-7-ch5'"):
        gearlab.simulate("B-7-ch5")
    with pytest.raises(GearlabInputError, match=r"unknown setting 'budjet' \(did you mean 'budget'"):
        gearlab.diagnose_gap("B-6-ch5", None, budjet=4)
    with pytest.raises(GearlabInputError, match=r"the source must be a simulation"):
        gearlab.diagnose_gap(np.zeros((3, 4096)), None)
    with pytest.raises(GearlabInputError, match=r"'mmd' trains a network"):
        gearlab.fit_detector("mmd", None, np.zeros((3, 4096)))
    with pytest.raises(GearlabInputError, match=r"the source must be a labelled dataset"):
        gearlab.fit_detector("matched_filter", np.zeros((3, 4096)), np.zeros((3, 4096)))
    with pytest.raises(GearlabInputError, match=r"give the revolutions' fault labels"):
        gearlab.score_detector(None, np.zeros((3, 4096)))
    with pytest.raises(GearlabInputError, match=r"no such file"):
        gearlab.import_recording("missing.csv", "acc", speed="25 Hz")


def test_a_measured_target_reaches_the_diagnosis_with_its_chain(workdir, monkeypatch):
    """diagnose_gap of an imported, unlabelled record: every revolution in physical units, the
    record's acquisition chain and bandwidth handed to gearlab.gap.diagnose.diagnose."""
    import gearlab.gap.diagnose as diagnose_module

    t = np.arange(40_000) / 20e3
    acc = np.cos(2 * np.pi * 25 * 25 * t) + 0.1 * np.random.default_rng(0).standard_normal(t.size)
    np.savez("rig.npz", acc=acc, tacho=(25 * t % 1 < 0.1).astype(float), fs=20e3)
    data = gearlab.import_recording("rig.npz", "acc", tacho="tacho", transient="none")
    seen = {}

    def fake(source, rows, settings, executor=None, on_event=None, chain=None):
        seen.update(source=source, rows=rows, settings=settings, chain=chain)
        return {"verdict": "stub"}

    monkeypatch.setattr(diagnose_module, "diagnose", fake)
    assert gearlab.diagnose_gap("B-6-ch5", data, budget=4)["verdict"] == "stub"
    mean, std = data.reference
    np.testing.assert_allclose(seen["rows"], data.X.astype(np.float64) * std + mean)
    assert seen["chain"] is not None and seen["chain"].fs == pytest.approx(20e3)
    assert seen["settings"].max_order == seen["chain"].max_order > 0 and seen["settings"].budget == 4
    assert seen["source"].name == "B-6-ch5"


@pytest.mark.parametrize(
    ("keys", "says"),
    [
        ({"pulses_per_rev": 0}, "pulses_per_rev: expected 1 .. 10000, got 0"),
        ({"gain": "-1 V"}, "gain: expected a positive number of volts per file unit"),
        ({"fs": "20 MHz"}, "fs: expected a sampling rate in (0, 10 MHz]"),
        ({"tacho_kind": "edges"}, "tacho_kind: 'edges' is not one of"),
        ({"gearbox": "luo2019", "tacho_shaft": "idler"}, "tacho_shaft: unknown shaft 'idler'; the shafts are"),
    ],
)
def test_inspect_recording_refuses_what_the_cli_refuses(tmp_path, keys, says):
    """One check of inspect's options for the notebook and the CLI: the keyword is named as written."""
    import gearlab
    from gearlab.errors import GearlabInputError

    path = tmp_path / "rig.npz"
    np.savez(path, acc=np.sin(np.arange(4000)), fs=20e3)
    with pytest.raises(GearlabInputError) as caught:
        gearlab.inspect_recording(path, vibration="acc", **keys)
    assert str(caught.value).startswith(says) and "\n" not in str(caught.value)
