"""Settings declared once (gearlab.settings): the scenario keys, the --quick limits and the
reference tables of docs/settings.md all come from the dataclass fields.

Run this file as a script to rewrite docs/settings.md after changing a declaration:
    python tests/test_settings.py
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from gearlab.data.spec import NoiseSpec
from gearlab.errors import GearlabInputError
from gearlab.gap.diagnose import Settings
from gearlab.kinds import SCENARIO_KINDS
from gearlab.learn.networks import NetworkSettings
from gearlab.learn.noise_study import NoiseProtocol
from gearlab.learn.protocol import Method, Protocol
from gearlab.scenario import keys_of, validate_table
from gearlab.settings import declared, from_inline, markdown_table, shrunk

DOC = Path(__file__).resolve().parent.parent / "docs" / "settings.md"

# (title, dataclass, which scenario tables it declares)
TABLES = [
    (
        "[network]",
        NetworkSettings,
        "transfer, detection, gap and noise_study scenarios (gap and noise_study: "
        'default name = "fast"; noise_study: default dropout = 0.1)',
    ),
    (
        "[protocol] (chapter-5 training)",
        Protocol,
        "transfer and detection [protocol], gap [accuracy]: the training "
        "keys (repetitions: transfer only; gap's [accuracy] defaults to 3)",
    ),
    ("[protocol] (chapter-4 noise study)", NoiseProtocol, "noise_study [protocol]"),
    ("[diagnosis]", Settings, "gap [diagnosis]; the gap benchmark's [search] takes the same fields"),
    (
        "noise = {...}",
        NoiseSpec,
        "a dataset's inline noise table ([source], [target], [[datasets]]; noise_study "
        "[dataset]: snr_db and seed only, the kind comes from [study])",
    ),
]


def reference() -> str:
    parts = [
        "# Settings reference\n",
        "Generated from the settings dataclasses (their field metadata: `gearlab.settings.setting`) by\n"
        "`python tests/test_settings.py`; `tests/test_settings.py` fails when this page and the\n"
        "declarations differ. The scenario key checks and the `--quick` limits come from the same\n"
        "declarations. How a scenario uses each table: docs/scenarios.md.\n",
    ]
    for title, cls, where in TABLES:
        parts.append(f"## {title}\n\n`{cls.__module__}.{cls.__name__}`: {where}.\n\n{markdown_table(cls)}")
    return "\n".join(parts)


def test_the_docs_reference_is_generated_from_the_declarations():
    assert DOC.read_text() == reference(), "docs/settings.md is stale: run python tests/test_settings.py"


def test_scenario_keys_come_from_the_declaration():
    transfer = SCENARIO_KINDS["transfer"].TABLES
    for name, (meta, default) in declared(Protocol).items():
        if name in transfer["protocol"].keys:
            key = transfer["protocol"].keys[name]
            assert key.default == default and key.types == meta.types and key.doc == meta.doc, name
    assert transfer["network"].keys["dropout"].default == NetworkSettings().dropout
    assert SCENARIO_KINDS["gap"].TABLES["network"].keys["name"].default == "fast"  # a kind's own default
    assert SCENARIO_KINDS["noise_study"].TABLES["protocol"].keys.keys() == declared(NoiseProtocol).keys()


def test_bounds_and_checks_come_from_the_declaration(tmp_path):
    table = type(SCENARIO_KINDS["transfer"].TABLES["protocol"])(keys_of(Protocol, ("max_epochs", "lr")))
    with pytest.raises(GearlabInputError, match=r"s.toml: \[protocol\] key 'max_epochs': 0 is outside \[1, 100000\]"):
        validate_table(tmp_path / "s.toml", "protocol", table, {"max_epochs": 0})
    network = type(table)(keys_of(NetworkSettings))
    with pytest.raises(
        GearlabInputError, match=r"\[network\] key 'name': unknown network 'fsat' \(did you mean 'fast'"
    ):
        validate_table(tmp_path / "s.toml", "network", network, {"name": "fsat"})


def test_quick_shrinks_by_the_declared_limits():
    p = Protocol(methods=(Method("mmd", False),), repetitions=5, prime_epochs=100, max_epochs=20)
    q = shrunk(p)
    assert (q.repetitions, q.prime_epochs, q.baseline_epochs, q.min_epochs, q.max_epochs) == (2, 30, 60, 60, 20)
    assert q.patience == p.patience and q.batch == p.batch  # no limit declared
    assert shrunk(p, repetitions=1).repetitions == 1  # a kind's own limit wins


def test_an_inline_table_is_read_as_declared():
    assert from_inline(NoiseSpec, {"kind": "laplace", "snr_db": 0}, "w") == NoiseSpec("laplace", 0.0, 0)
    assert from_inline(NoiseSpec, {"snr_db": 3}, "w", {"kind": "gaussian", "seed": 7}) == NoiseSpec("gaussian", 3.0, 7)
    with pytest.raises(GearlabInputError, match=r"w: unknown key\(s\) sed; expected kind, snr_db, seed"):
        from_inline(NoiseSpec, {"kind": "laplace", "snr_db": 0, "sed": 1}, "w")
    with pytest.raises(
        GearlabInputError, match=r"w: expected \{kind = 'gaussian'\|'laplace'\|'student_t', snr_db = number\}"
    ):
        from_inline(NoiseSpec, {"kind": "laplace"}, "w")
    assert [f.name for f in dataclasses.fields(NoiseSpec)] == list(declared(NoiseSpec))


if __name__ == "__main__":
    DOC.write_text(reference())
    print(f"wrote {DOC}")
