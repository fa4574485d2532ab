"""One noise declaration: a recording's noise is the `sensor_noise` effect in a dataset table's
`effects`. With a `seed` it is the dataset's noise (data.spec.NoiseSpec: drawn from that seed
after every other effect, what chapter 4 and the Bayes bound assume); without one it is drawn at
its place from the effects' streams. The older `noise = {...}` key is refused in every table that
declared it, one line naming the file, the table, the key and the form to use; the one form gives
the datasets (and cache keys) the older one gave."""

import dataclasses
from pathlib import Path

import pytest
from conftest import ROOT

import gearlab
from gearlab.data.spec import DatasetSpec, NoiseSpec, dataset_preset
from gearlab.errors import GearlabInputError
from gearlab.registry import get_registry
from gearlab.settings import setting_of
from gearlab.signals import NOISE_KINDS, SNR_DB_RANGE

ONE = '{ name = "sensor_noise", kind = "laplace", snr_db = 0.0, seed = 1 }'
OLD = 'noise = { kind = "laplace", snr_db = 0.0, seed = 1 }'


def _scenario(name: str) -> str:
    text = (ROOT / "scenarios" / f"{name}.toml").read_text()
    assert f"effects = [{ONE}]" in text
    return text


def _one_line(cli, path) -> str:
    code, _, err = cli("validate", path)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1, err
    assert str(path) in lines[0], err
    return lines[0]


def test_the_noise_table_and_the_effect_declare_the_same_kinds_and_bounds():
    fields = {f.name: f.metadata["setting"] for f in dataclasses.fields(NoiseSpec)}
    effect = get_registry().get("effect", "sensor_noise")
    snr = setting_of(effect.params, "snr_db")
    assert (fields["snr_db"].low, fields["snr_db"].high) == (snr.low, snr.high) == SNR_DB_RANGE
    assert tuple(fields["kind"].choices) == tuple(effect.options["kind"]) == NOISE_KINDS


@pytest.mark.parametrize(
    "name,table", [("quick", "[target]"), ("dataset_B", "[[datasets]] #4"), ("gap_expB", "[target]")]
)
def test_the_older_noise_key_is_one_line_naming_the_effect_form(cli, write_scenario, name, table):
    bad = write_scenario(_scenario(name).replace(f"effects = [{ONE}]", OLD))
    line = _one_line(cli, bad)
    assert f"{table} key 'noise'" in line and f"effects = [{ONE}]" in line, line


def test_a_benchmark_source_and_a_noise_study_refuse_the_older_key_too(cli, write_scenario):
    bench = (ROOT / "scenarios" / "gap_benchmark.toml").read_text()
    bad = write_scenario(bench.replace('preset = "B-6-ch5"', f'preset = "B-6-ch5"\n{OLD}', 1))
    line = _one_line(cli, bad)
    assert "[source] key 'noise'" in line and 'effects = [{ name = "sensor_noise"' in line, line
    study = (ROOT / "scenarios" / "ch4_noise.toml").read_text()
    bad = write_scenario(f"{study}\n[dataset]\nnoise = {{ snr_db = 3.0 }}\n")
    line = _one_line(cli, bad)
    assert "[dataset] key 'noise'" in line and "snr_db = 0.0, seed = 0 }]" in line, line


def test_the_effect_with_a_seed_is_the_datasets_noise_with_the_keys_of_before():
    """quick.toml's target: the preset with NoiseSpec(laplace, 0 dB, seed 1) and no effect, the
    spec (and so the cache key and every realised row) the older `noise = {...}` gave."""
    spec = gearlab.load_scenario(ROOT / "scenarios" / "quick.toml").spec.target
    before = dataset_preset("B-8-ch5").with_(name="B-8-ch5-laplace", domain="B-8-ch5-laplace")
    assert spec == before.with_(noise=NoiseSpec("laplace", 0.0, 1)) and spec.effects == ()
    assert isinstance(spec, DatasetSpec) and spec.key() == before.with_(noise=NoiseSpec("laplace", 0.0, 1)).key()


def test_without_a_seed_it_stays_an_effect_and_effects_replace_a_presets_noise():
    from gearlab.kinds.common import effects_and_noise

    effects, noise = effects_and_noise([{"name": "sensor_noise", "kind": "gaussian", "snr_db": 30}], "t")
    assert noise is None and [name for name, _ in effects] == ["sensor_noise"]
    effects, noise = effects_and_noise(
        [{"name": "sensor_offset", "offset": "1 m/s^2"}, {"name": "sensor_noise", "snr_db": 6, "seed": 4}], "t"
    )
    assert noise == NoiseSpec("gaussian", 6.0, 4) and [name for name, _ in effects] == ["sensor_offset"]
    assert effects_and_noise([], "t") == ((), None)  # an empty list: no effect, no noise (a preset's removed)


@pytest.mark.parametrize(
    "effects,said",
    [
        (f'[{ONE}, {{ name = "sensor_lowpass" }}]', "#1 (sensor_noise): with a seed the noise is drawn after every"),
        (f'[{ONE}, {{ name = "sensor_noise", seed = 2 }}]', "#2 (sensor_noise): one sensor_noise has a seed"),
        ('[{ name = "sensor_noise", seed = -1 }]', "#1 (sensor_noise): seed must be a whole number"),
    ],
)
def test_a_seeded_noise_out_of_place_is_one_line(cli, write_scenario, effects, said):
    bad = write_scenario(_scenario("quick").replace(f"effects = [{ONE}]", f"effects = {effects}"))
    line = _one_line(cli, bad)
    assert f"[target] key 'effects' {said}" in line, line


@pytest.mark.parametrize("snr", [500, -40])
def test_a_noise_outside_the_bounds_is_one_line_exit_2(cli, write_scenario, snr):
    bad = write_scenario(_scenario("quick").replace("snr_db = 0.0, seed = 1", f"snr_db = {snr}, seed = 1"))
    line = _one_line(cli, bad)
    assert "[target] key 'effects' #1 (sensor_noise), parameter 'snr_db'" in line and "[-20, 80]" in line, line


def test_the_bounds_themselves_are_accepted(cli, write_scenario):
    text = _scenario("quick")
    for snr in SNR_DB_RANGE:
        good = write_scenario(text.replace("snr_db = 0.0", f"snr_db = {snr}"))
        code, out, err = cli("validate", good)
        assert code == 0 and "OK" in out, err


def test_a_noise_study_takes_the_level_and_seed_from_its_one_effect(write_scenario):
    study = (ROOT / "scenarios" / "ch4_noise.toml").read_text()
    path = write_scenario(f'{study}\n[dataset]\neffects = [{{ name = "sensor_noise", snr_db = 3.0, seed = 5 }}]\n')
    specs = gearlab.load_scenario(path).spec.datasets
    assert {s.noise for v in specs.values() for s in v.values()} == {NoiseSpec(k, 3.0, 5) for k in NOISE_KINDS}
    for effects, said in (
        ('[{ name = "sensor_noise", kind = "laplace" }]', "the noise kind comes from [study]"),
        ('[{ name = "sensor_lowpass" }]', "a noise study's one effect is its noise"),
    ):
        path = write_scenario(f"{study}\n[dataset]\neffects = {effects}\n")
        with pytest.raises(GearlabInputError) as e:
            gearlab.load_scenario(path)
        assert "[dataset] key 'effects'" in str(e.value) and said in str(e.value)


def test_the_noise_is_added_in_one_place():
    """gearlab.signals.add_noise is called by the one realisation (data.realise) and the sensor_noise
    effect it applies, and the signal effects are applied by the realisation alone: the builder, the
    gap diagnosis, both benchmarks, a simulated record and the notebook API all go through it."""
    callers = {}
    for path in sorted((ROOT / "gearlab").rglob("*.py")) + sorted((ROOT / "plugins").rglob("*.py")):
        text = path.read_text()
        for call in ("add_noise(", ".apply_signal("):
            if call in text.replace(f"def {call}", ""):
                callers.setdefault(call, []).append(str(path.relative_to(ROOT)))
    assert callers["add_noise("] == ["gearlab/data/realise.py", "plugins/effects/sensor_noise.py"]
    assert callers[".apply_signal("] == ["gearlab/data/realise.py", "gearlab/effects.py"]


def test_a_run_made_with_the_older_key_is_read_and_resumed_as_it_was_made(cli, write_scenario, tmp_path):
    """A run directory whose copies of the scenario hold `noise = {...}` (made before the one
    declaration): read as the seeded sensor_noise (the same spec and cache key), resumed as started."""
    import tomllib

    import tomli_w

    from gearlab.engine import scenario_of
    from gearlab.runs import RunDir

    text = '[scenario]\nname = "d"\nkind = "dataset"\n\n[[datasets]]\npreset = "B-8-ch5"\nteeth = [1]\n'
    path = write_scenario(text + f"faults = {{ crack = [13] }}\nhealthy = 2\neffects = [{ONE}]\n")
    code, out, err = cli("run", path, "--out", tmp_path / "runs")
    assert code == 0, err
    run = Path(out.strip().splitlines()[-1].split(": ", 1)[1])
    made = scenario_of(RunDir.open(run)).spec[0]
    for name in ("scenario.original.toml", "scenario.toml"):  # as such a run wrote them
        data = tomllib.loads((run / name).read_text())
        entry = data["datasets"][0]
        (seeded,) = entry.pop("effects")
        entry["noise"] = {k: v for k, v in seeded.items() if k != "name"}
        (run / name).write_text(tomli_w.dumps(data))
    assert "noise" in (run / "scenario.toml").read_text()
    read = scenario_of(RunDir.open(run)).spec[0]
    assert read == made and read.noise == NoiseSpec("laplace", 0.0, 1) and read.key() == made.key()
    code, out, err = cli("run", "--resume", run)
    assert code == 0, err
