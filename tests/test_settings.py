"""Settings declared once (gearlab.settings): the scenario keys, the --quick limits and the
reference tables of docs/settings.md all come from the declarations.

After changing a declaration, rewrite docs/settings.md with:
    python -m gearlab.settings_doc
"""

from __future__ import annotations

import copy
import dataclasses
import re

import pytest
from conftest import ROOT

from gearlab import settings_doc
from gearlab.data.spec import NoiseSpec
from gearlab.errors import GearlabInputError
from gearlab.kinds import SCENARIO_KINDS
from gearlab.kinds.stiffness import Sweep
from gearlab.learn.networks import NetworkSettings
from gearlab.learn.noise_study import NoiseProtocol
from gearlab.learn.protocol import Method, Protocol
from gearlab.scenario import keys_of, validate_table
from gearlab.settings import declared, from_inline, shrunk, typed


def test_the_docs_reference_is_generated_from_the_declarations():
    assert settings_doc.DOC.read_text() == settings_doc.reference(), (
        "docs/settings.md is stale: run python -m gearlab.settings_doc"
    )
    assert settings_doc.main(["--check"]) == 0


def test_the_reference_has_every_table_of_every_kind(tmp_path):
    text = settings_doc.reference()
    sections = text.split("\n## ")
    for kind, module in SCENARIO_KINDS.items():
        section = next(s for s in sections if s.startswith(f'kind = "{kind}"'))
        for name, table in module.TABLES.items():
            assert f"### `{'[[' if table.array else '['}{name}{']]' if table.array else ']'}`" in section, (kind, name)
    # a declared setting brings its bounds, unit and --quick limit
    assert "| `budget` | int | 16 |  | [1, 10000] | ≤ 4 | source simulations per effect fit" in text
    assert "| `speed` | number or str |  | Hz |  |  | input-shaft speed" in text
    assert "| `load` | number or str |  | N*m |" in text
    # the one noise declaration: the sensor_noise in `effects`, no `noise` key in any table
    assert "{name = 'sensor_noise', kind = 'laplace', snr_db = 0, seed = 1}" in text and "| `noise` |" not in text
    # a stale page is found, and the generator rewrites it
    stale = tmp_path / "settings.md"
    stale.write_text(text.replace("≤ 4", "≤ 5"))
    assert settings_doc.main([str(stale), "--check"]) == 1
    assert settings_doc.main([str(stale)]) == 0 and stale.read_text() == text


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


# Scenario keys written by hand (gearlab.scenario.Key) where a settings dataclass should declare
# them: none is left (98 before issue 38 item 4); a module listed here could only go down.
HAND_WRITTEN_KEYS: dict[str, int] = {}


def test_scenario_keys_are_declared_only_as_settings():
    package = ROOT / "gearlab"
    for path in package.rglob("*.py"):
        name = path.relative_to(package).as_posix()
        if name == "scenario.py":  # keys_of, which makes a Key of each declared field
            continue
        found = len(re.findall(r"\bKey\(", path.read_text()))
        assert found <= HAND_WRITTEN_KEYS.get(name, 0), (
            f"gearlab/{name}: {found} Key(...) written by hand; declare the table as a frozen dataclass of "
            "gearlab.settings.setting fields and give Table(keys_of(cls))"
        )


def test_a_table_is_read_typed_and_a_list_default_is_not_shared():
    sweep = typed(Sweep, {"faults": ["crack"], "tooth": 3, "steps": [1, 4], "unknown_to_sweep": 1})
    assert (sweep.faults, sweep.tooth, sweep.steps) == (["crack"], 3, [1, 4])
    a, b = Sweep(), Sweep()
    a.faults.append("crack")
    assert b.faults == [] and declared(Sweep)["steps"][1] == [1, 20]


def _gearbox_rows() -> dict[str, set[str]]:
    """{table title: its keys} as docs/settings.md's gearbox section lists them."""
    section = settings_doc.reference().split("## A gearbox description file")[1]
    rows, table = {}, None
    for line in section.splitlines():
        if m := re.match(r"\| (`[^|]*`)? *\| `(\w+)` \|", line):
            table = m.group(1) or table
            rows.setdefault(table.strip("`"), set()).add(m.group(2))
    return rows


def test_the_reference_has_every_key_a_gearbox_description_takes(tmp_path):
    # the reader's own "unknown key; known keys: ..." of every table against the page's rows: a key
    # the reader takes and the page misses (or the other way) fails
    from gearlab.gearbox.description import PER_GEAR, TABLES, parse_gearbox

    rows = _gearbox_rows()
    assert {t.strip("[]").split(".")[0] for t in rows} >= set(TABLES), rows.keys()
    gear = {"z": 20, "bore": "20 mm"}
    box = {"stages": [{"module": "2 mm", "face_width": "20 mm", "pinion": dict(gear), "wheel": dict(gear, z=57)}]}
    where = {
        "[gearbox]": lambda d: d.setdefault("gearbox", {}),
        "[operation]": lambda d: d.setdefault("operation", {}),
        "[materials.NAME]": lambda d: d.setdefault("materials", {}).setdefault("bronze", {}),
        "[[stages]]": lambda d: d["stages"][0],
        "[stages.pinion], [stages.wheel]": lambda d: d["stages"][0]["pinion"],
        "[[shafts]]": lambda d: d.setdefault("shafts", [{}, {}])[0],
        "[sensor]": lambda d: d.setdefault("sensor", {}),
        "[dynamics]": lambda d: d.setdefault("dynamics", {}),
    }
    assert set(where) == set(rows)
    for title, table in where.items():
        data = copy.deepcopy(box)
        table(data)["bogus_key"] = 1
        with pytest.raises(GearlabInputError) as err:
            parse_gearbox(data, "my.toml")
        known = set(str(err.value).split("known keys: ")[1].split(", "))
        assert known == rows[title] | (set(PER_GEAR) if "pinion" in title else set()), title
    assert "| `[[stages]]` | `module` | float | required | m | [0.1 mm, 100 mm] |" in settings_doc.reference()


def test_the_gearbox_pages_example_is_a_description_that_loads(tmp_path):
    from gearlab.gearbox import load_gearbox

    page = (ROOT / "docs" / "gearbox.md").read_text()
    path = tmp_path / "rig20.toml"
    path.write_text(re.search(r"```toml\n(.*?)```", page, re.S).group(1))
    box = load_gearbox(path)
    assert (box.name, box.speed_hz, box.stages[0].wheel.material.name) == ("rig20", 25.0, "bronze")
