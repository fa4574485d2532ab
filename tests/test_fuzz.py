"""Fuzzing (the quality bar: any input is refused in one line): the scenario loader and the
measured-data importers take any input and answer with a result or a one-line
GearlabInputError: never another exception, never a hang, and a rejected run leaves nothing
behind.

The examples are derandomised (the same every run, for CI). For a longer hunt set
GEARLAB_FUZZ_EXAMPLES, e.g. `GEARLAB_FUZZ_EXAMPLES=3000 pytest tests/test_fuzz.py`.
"""

from __future__ import annotations

import atexit
import contextlib
import copy
import faulthandler
import io
import os
import random
import shutil
import sys
import tempfile
import tomllib
import zipfile
from datetime import timedelta
from pathlib import Path

import h5py
import numpy as np
import pytest
import scipy.io
import tomli_w
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_importers import make_record, write_formats, write_mat73

from gearlab.data.importers import MeasuredSpec, import_measured
from gearlab.engine import load_scenario
from gearlab.errors import GearlabInputError
from gearlab.kinds import SCENARIO_KINDS
from gearlab.registry import get_registry
from gearlab.scenario import EXECUTION_TABLE, OUTPUT_TABLE, SCENARIO_TABLE
from gearlab.settings import declared

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = int(os.environ.get("GEARLAB_FUZZ_EXAMPLES", "0"))


def fuzz(examples: int):
    """Derandomised (the same examples on every run), no example database, and a deadline that
    flags a slow input without failing on a busy machine."""
    return settings(
        max_examples=EXAMPLES or examples,
        derandomize=True,
        database=None,
        deadline=timedelta(seconds=5),
        suppress_health_check=[HealthCheck.too_slow],
    )


@contextlib.contextmanager
def no_hang(seconds: float = 60.0):
    """A hang in C code (a huge integer power, h5py walking a damaged file) cannot be
    interrupted from Python: rather than hang the test run, dump every thread's stack and end
    the process with exit code 1 (pytest captures the dump: rerun with -s to read it)."""
    faulthandler.dump_traceback_later(seconds, exit=True)
    try:
        yield
    finally:
        faulthandler.cancel_dump_traceback_later()


def refused_or_fine(action) -> object:
    """Run *action*: its result, or None when it raised a one-line GearlabInputError."""
    with no_hang():
        try:
            return action()
        except GearlabInputError as exc:
            message = str(exc)
            assert message and "\n" not in message and "\r" not in message, repr(message)
            return None


# ============================================================================= scenarios


# Stands in for the shipped scenarios' records where they are not here (../shared is optional):
# validation only asks that each named file exists, so the fuzzer reaches [target] files in any
# clone. Made once per process, removed at its end.
STAND_INS = Path(tempfile.mkdtemp(prefix="gearlab-fuzz-"))
atexit.register(shutil.rmtree, STAND_INS, ignore_errors=True)


def stand_in(name: str) -> Path:
    """A small record named *name* in STAND_INS (one per name: a scenario lists each once)."""
    path = STAND_INS / name
    if not path.exists():
        with zipfile.ZipFile(path, "w") as z:
            z.writestr("record.txt", "0.1 0.2 0\n")
    return path


def measured_files_absolute(doc: dict) -> dict:
    """A shipped scenario with its [target] files (relative to scenarios/) made absolute, so it
    validates from any folder; a record that is not here is replaced by a stand-in."""
    files = doc.get("target", {}).get("files")
    if not isinstance(files, list):
        return doc
    for f in files:
        key = "file" if "file" in f else "path"  # 'path': the key's name before 'file'
        path = Path(f[key])
        f[key] = str(path if path.is_absolute() else (ROOT / "scenarios" / path).resolve())
        if not Path(f[key]).is_file():
            f[key] = str(stand_in(Path(f[key]).name))
    return doc


def real_scenarios() -> dict[str, dict]:
    out = {
        p.name: measured_files_absolute(tomllib.loads(p.read_text()))
        for p in sorted((ROOT / "scenarios").glob("*.toml"))
    }
    out = {name: doc for name, doc in out.items() if doc is not None}
    # what the shipped scenarios do not show: measured data, a study's overrides, explicit faults
    out["measured.toml"] = {
        "scenario": {"name": "measured", "kind": "dataset"},
        "datasets": [
            {
                "file": "rec.npz",
                "vibration": "acc",
                "tacho": "tacho",
                "labels": "label",
                "class_names": ["healthy", "fault"],
                "fs": "50 kHz",
                "transient": "none",
            }
        ],
    }
    out["study.toml"] = {
        "scenario": {"name": "study", "kind": "noise_study"},
        "study": {"noises": ["gaussian"]},
        "dataset": {
            "teeth": [1, 2],
            "duplicates": 2,
            "healthy": 40,
            "revolutions": 4,
            "speed": "25 Hz",
            "faults": {"crack": [5, 10], "pit": [20]},
            "effects": [{"name": "sensor_noise", "snr_db": 3, "seed": 1}],
        },
        "protocol": {"runs": 2, "batch": 8, "epochs": 3},
    }
    out["cases.toml"] = {
        "scenario": {"name": "cases", "kind": "stiffness"},
        "stiffness": {"pair": "meng2020", "points": 256},
        "cases": [
            {
                "name": "c",
                "faults": [
                    {
                        "kind": "spall",
                        "tooth": 3,
                        "params": {"w_s": "8 mm", "l_s": "1 mm", "h_s": "0.5 mm", "x_1": "2 mm"},
                    }
                ],
            }
        ],
    }
    return out


REAL = real_scenarios()

# Names a scenario refers to: plugin, preset, model and channel names, units, choices.
WORDS = [
    "crack",
    "chip",
    "spall",
    "pit",
    "ten_dof",
    "eight_dof",
    "six_dof",
    "luo2019",
    "meng2020",
    "A-pinion",
    "A-casing-ch5",
    "B-6-ch5",
    "B-8",
    "A-casing_noise-gaussian",
    "fast",
    "cnn3",
    "source_only",
    "target_only",
    "mmd",
    "dann",
    "coral",
    "finetune",
    "gaussian",
    "laplace",
    "student_t",
    "pinion_x",
    "pinion_y",
    "casing_x",
    "stats",
    "none",
    "local",
    "ray",
    "auto",
    "cpu",
    "cuda",
    "stiffness",
    "dataset",
    "transfer",
    "noise_study",
    "all",
    "classifier",
    "last",
    "healthy",
    "fault",
    "rec.npz",
    "rec.csv",
    "x.wav",
    "../x.mat",
    "/",
    ".",
    "runs",
    "a/b",
    ".hidden",
    "naïve ✓",
    "\u0000",
    "\n",
    "é" * 300,
]
UNIT_TEXTS = [
    "3.175 mm",
    "20 deg",
    "25.2 Hz",
    "7 N*m",
    "200 kHz",
    "-5 Hz",
    "0 Hz",
    "1e400 Hz",
    "nan Hz",
    "inf N*m",
    "25 kg",
    "furlong",
    "1,5 mm",
    "9**9**9 Hz",
    "2**10000 Hz",
    "((9**9)**9)**9 Hz",
    "10**400 Hz",
    "1e308 kHz",
    "5 %",
    "pi",
    "",
    " ",
    "3 µm",
    "10 degC",
    "1/0 Hz",
    "Hz",
    "m/m",
    "40 rpm",
    "1 Hz Hz",
    "(",
    "1 Hz)",
    "1 + 2 Hz",
    "[1, 2] Hz",
    "1e-320 Hz",
    "0x10 Hz",
    "1_000 Hz",
]
NUMBERS = [
    0,
    1,
    -1,
    2,
    5,
    13,
    20,
    21,
    64,
    4096,
    2**20 + 1,
    2**31,
    2**63,
    2**64 + 1,
    10**30,
    -(10**30),
    10**400,
    0.0,
    -0.0,
    0.5,
    1e-9,
    1e-320,
    0.95,
    1.5,
    1e308,
    float("inf"),
    float("-inf"),
    float("nan"),
]

# Every plugin parameter (fault sizes, adapter settings, model constants) and every schema key.
PARAMS = sorted(
    {
        name
        for plugins in get_registry().plugins.values()
        for plugin in plugins.values()
        for name in declared(plugin.params)
    }
)
QUANTITIES = ["speed", "load", "fs", "snr_db", *PARAMS]
KEYS = sorted(
    {
        *SCENARIO_TABLE.keys,
        *OUTPUT_TABLE.keys,
        *EXECUTION_TABLE.keys,
        *QUANTITIES,
        *(key for module in SCENARIO_KINDS.values() for table in module.TABLES.values() for key in table.keys),
        "kind",
        "tooth",
        "step",
        "params",
        "seed",
    }
)
TABLES = sorted({"scenario", "output", "execution", *(name for m in SCENARIO_KINDS.values() for name in m.TABLES)})

# Any character but a lone surrogate: st.text's own alphabet (characters(codec="utf-8")), the same intervals and
# the same examples, without the table of what UTF-8 encodes that hypothesis first builds by trying each of the
# 1.1 million code points (1.8 s of CPU in a clone whose .hypothesis folder does not have it yet).
TEXT = st.characters(exclude_categories=("Cs",))

scalars = st.one_of(
    st.sampled_from(NUMBERS),
    st.integers(),
    st.floats(),
    st.booleans(),
    st.sampled_from(WORDS + UNIT_TEXTS),
    st.text(TEXT, max_size=12),
)
values = st.recursive(
    scalars,
    lambda inner: st.one_of(
        st.lists(inner, max_size=4),
        st.dictionaries(st.sampled_from(KEYS) | st.text(TEXT, max_size=8), inner, max_size=4),
    ),
    max_leaves=8,
)
keys = st.sampled_from(KEYS) | st.text(TEXT, max_size=10)


def places(node, found=None) -> list[tuple[object, object]]:
    """Every (container, key or index) of a parsed TOML document, nested ones included."""
    found = [] if found is None else found
    items = node.items() if isinstance(node, dict) else enumerate(node) if isinstance(node, list) else ()
    for key, value in items:
        found.append((node, key))
        places(value, found)
    return found


def nudge(value):
    """A number pushed out of shape: negative, zero, huge, not finite, of another type."""
    if isinstance(value, bool):
        return st.just(not value)
    if isinstance(value, int):
        return st.sampled_from([-value, 0, value + 1, value * 10**12, 2.5, str(value), 10**400])
    if isinstance(value, float):
        return st.sampled_from([-value, 0.0, value * 1e300, float("nan"), float("inf"), 3, str(value)])
    if isinstance(value, str):
        # a name over 255 bytes, alone or as a folder on the way: no file system takes it
        return st.sampled_from(
            [value.upper(), value[:-1], value + "x", "", value + "\n", value * 50, f" {value} "]
            + ["x" * 300, f"{'y' * 300}/{value}", f"{value}.{'z' * 256}"]
        )
    return st.sampled_from([[], {}, [value], {"x": value}])


@st.composite
def mutated_scenarios(draw) -> dict:
    """A shipped scenario with 1-3 edits: a key deleted, a value replaced by anything or pushed
    out of range, a key added, a key renamed, a quantity (with a unit) set. Where to edit is drawn uniformly (hypothesis
    would favour the first key, the [scenario] table, every time)."""
    rnd = random.Random(draw(st.integers(0, 2**64)))  # uniform choices, seeded by the example
    doc = copy.deepcopy(REAL[rnd.choice(sorted(REAL))])
    for _ in range(rnd.randint(1, 3)):
        spots = places(doc)
        if rnd.random() < 0.8:  # [scenario] is checked first: edits there would hide the rest
            head = doc.get("scenario")
            spots = [(c, k) for c, k in spots if c is not head and (c is not doc or k != "scenario")]
        if not spots:
            break
        op = rnd.choice(["delete", "replace", "nudge", "add", "rename", "quantity"])
        parent, key = rnd.choice(spots)
        if op == "delete":
            del parent[key]
        elif op == "replace":
            parent[key] = draw(values)
        elif op == "nudge":
            parent[key] = draw(nudge(parent[key]))
        else:
            tables = {id(c): c for c, _ in spots if isinstance(c, dict)} or {id(doc): doc}  # each table once
            table = rnd.choice(list(tables.values()))
            if op == "add":
                table[draw(keys)] = draw(values)
            elif op == "quantity":  # a quantity, with or without its unit, of any text
                table[rnd.choice(QUANTITIES)] = draw(st.sampled_from(UNIT_TEXTS + NUMBERS) | st.text(TEXT, max_size=12))
            elif table:
                table[draw(keys)] = table.pop(rnd.choice(sorted(table)))
    return doc


@st.composite
def random_scenarios(draw) -> dict:
    """A document of the right shape with random contents: [scenario] of some kind, then
    tables (and arrays of tables) named as real ones, holding schema keys with any values."""
    doc: dict = {
        "scenario": draw(
            st.dictionaries(
                st.sampled_from(["name", "kind", "description"]) | keys,
                st.sampled_from(sorted(SCENARIO_KINDS)) | scalars,
                max_size=4,
            )
        )
    }
    for name in draw(st.lists(st.sampled_from(TABLES) | st.text(TEXT, max_size=6), max_size=5)):
        table = st.dictionaries(keys, values, max_size=6)
        doc[name] = draw(st.lists(table, max_size=3) if draw(st.booleans()) else table)
    return doc


def toml_bytes(doc: dict) -> bytes:
    return tomli_w.dumps(doc).encode()


@pytest.fixture(scope="module")
def scenario_file(tmp_path_factory):
    """One file the examples overwrite; validation is warmed up (registry, units, gear pairs)
    so that the deadline measures the input's cost, not the first import."""
    path = tmp_path_factory.mktemp("fuzz") / "s.toml"
    write_formats(path.parent, make_record(n=8000))  # the records the scenarios name (rec.npz)
    for doc in REAL.values():
        path.write_bytes(toml_bytes(doc))
        validate(path)
    return path


def validate(path: Path):
    """What `gearlab validate` does, in this process: load and resolve, describe."""

    def action():
        scenario = load_scenario(path)
        return SCENARIO_KINDS[scenario.kind].describe(scenario)

    return refused_or_fine(action)


def test_shipped_scenarios_are_valid(scenario_file):
    for name, doc in REAL.items():
        scenario_file.write_bytes(toml_bytes(doc))
        assert validate(scenario_file) is not None, name


def test_the_fuzz_reaches_target_files_and_names_no_file_system_takes(scenario_file):
    """In any clone, with the records of ../shared or without: the detection scenario's
    [target] files are among those mutated, and a mutation may make a name (or a folder on the
    way) longer than 255 bytes, which is refused in one line."""
    chip = copy.deepcopy(REAL["phm09_chip.toml"])
    assert chip["target"]["files"]
    assert any(len(part.encode()) > 255 for v in nudge("rec.zip").elements for part in v.split("/"))
    first = chip["target"]["files"][0]["file"]
    for long in ("x" * 300, f"{'y' * 300}/{first}", f"{first}.{'z' * 256}"):
        chip["target"]["files"][0]["file"] = long
        scenario_file.write_bytes(toml_bytes(chip))
        with pytest.raises(GearlabInputError, match="File name too long"):
            load_scenario(scenario_file)


@fuzz(400)
@given(doc=mutated_scenarios())
def test_mutated_scenarios_load_or_are_refused(scenario_file, doc):
    scenario_file.write_bytes(toml_bytes(doc))
    validate(scenario_file)


@fuzz(250)
@given(doc=random_scenarios())
def test_random_scenarios_load_or_are_refused(scenario_file, doc):
    scenario_file.write_bytes(toml_bytes(doc))
    validate(scenario_file)


@st.composite
def damaged_texts(draw) -> bytes:
    """A shipped scenario's text cut short, with bytes changed or inserted, or random bytes."""
    text = toml_bytes(REAL[draw(st.sampled_from(sorted(REAL)))])
    op = draw(st.sampled_from(["cut", "flip", "insert", "random"]))
    if op == "random":
        return draw(st.binary(max_size=200))
    at = draw(st.integers(0, len(text)))
    if op == "cut":
        return text[:at]
    if op == "flip":
        return text[:at] + draw(st.binary(min_size=1, max_size=4)) + text[at + 4 :]
    return text[:at] + draw(st.sampled_from([b"\n", b"=", b"[", b"]]", b'"', b"\\u0000", b"\xff", b"\x00"])) + text[at:]


@fuzz(200)
@given(data=damaged_texts())
def test_damaged_scenario_files_load_or_are_refused(scenario_file, data):
    scenario_file.write_bytes(data)
    validate(scenario_file)


# Inputs the fuzzing found; kept as plain tests so that they stay fixed.
FOUND = {
    "NaN learning rate": ("quick.toml", ("protocol", "lr"), float("nan"), "outside [1e-09, 10.0]"),
    "NaN dropout": ("quick.toml", ("network", "dropout"), float("nan"), "outside"),
    "huge integer speed": ("dataset_B.toml", ("datasets", 0, "speed"), 10**400, "expected a finite number"),
    "huge power in a unit text": ("dataset_B.toml", ("datasets", 0, "speed"), "9**9**9 Hz", "power"),
    "decimal comma": ("dataset_B.toml", ("datasets", 0, "speed"), "25,2 Hz", "decimal point"),
    "percent as a speed": ("dataset_B.toml", ("datasets", 0, "speed"), "5 %", "wrong dimension"),
    "billions of repetitions": ("quick.toml", ("protocol", "repetitions"), 10**12, "outside"),
    "name with a NUL": ("quick.toml", ("scenario", "name"), "a\u0000b", "plain name"),
    "output dir with a NUL": ("quick.toml", ("output", "dir"), "runs\u0000", "NUL"),
    "fault kind not a name": (
        "stiffness_verification.toml",
        ("cases", 0, "faults", 0, "kind"),
        ["crack"],
        "expected a fault name",
    ),
    "tooth not a number": (
        "stiffness_verification.toml",
        ("cases", 0, "faults", 0, "tooth"),
        "2",
        "expected a tooth number",
    ),
    "params not a table": (
        "stiffness_verification.toml",
        ("cases", 0, "faults", 2, "params"),
        [{"w_s": 1}],
        "expected a table of parameters",
    ),
    "key with a line break": ("quick.toml", ("protocol", "ks\nx"), 1, "'ks\\nx'"),
    "k that is a list": ("quick.toml", ("protocol", "ks"), [[], 4], "expected a list of distinct whole numbers"),
    "a seed torch cannot take": ("quick.toml", ("protocol", "seed"), 2**64, "outside [0, 4294967295]"),
    "a dataset beyond memory": ("study.toml", ("dataset", "duplicates"), 10**400, "expected at most 1000000"),
}


@pytest.mark.parametrize("case", list(FOUND))
def test_inputs_found_by_fuzzing_are_refused_clearly(scenario_file, case):
    name, where, value, fact = FOUND[case]
    doc = copy.deepcopy(REAL[name])
    node = doc
    for key in where[:-1]:
        node = node.setdefault(key, {}) if isinstance(node, dict) else node[key]
    node[where[-1]] = value
    scenario_file.write_bytes(toml_bytes(doc))
    with pytest.raises(GearlabInputError) as info:
        load_scenario(scenario_file)
    assert fact in str(info.value) and "\n" not in str(info.value)


def test_an_snr_beyond_any_float_is_refused(scenario_file):
    doc = copy.deepcopy(REAL["dataset_B.toml"])
    doc["datasets"][3]["effects"][0]["snr_db"] = 10**400
    scenario_file.write_bytes(toml_bytes(doc))
    with pytest.raises(GearlabInputError, match="snr_db"):
        load_scenario(scenario_file)


def test_integer_beyond_pythons_conversion_limit_is_refused(scenario_file):
    """tomllib raises ValueError, not TOMLDecodeError, on an integer of more than 4300 digits."""
    scenario_file.write_text(
        f'[scenario]\nname = "n"\nkind = "stiffness"\n[stiffness]\npair = "luo2019"\npoints = {"9" * 5000}\n'
    )
    with pytest.raises(GearlabInputError, match="invalid TOML: Exceeds the limit"):
        load_scenario(scenario_file)


# ============================================================================= importers


@pytest.fixture(scope="module")
def valid_files(tmp_path_factory):
    """Every format of test_importers' record, shortened to 4 revolutions for speed."""
    return write_formats(tmp_path_factory.mktemp("valid"), make_record(n=8000))


@pytest.fixture(scope="module")
def damaged_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("damaged")


FORMATS = ["csv", "npz", "h5", "wav-float32", "wav-int16", "mat5", "mat73"]


@st.composite
def damaged_bytes(draw, data: bytes) -> bytes:
    op = draw(st.sampled_from(["cut", "flip", "insert", "overwrite", "repeat"]))
    at = draw(st.integers(0, len(data) - 1))
    if op == "cut":
        return data[:at]
    if op == "flip":
        bit = draw(st.integers(0, 7))
        return data[:at] + bytes([data[at] ^ (1 << bit)]) + data[at + 1 :]
    if op == "insert":
        return data[:at] + draw(st.binary(min_size=1, max_size=16)) + data[at:]
    if op == "overwrite":
        chunk = draw(st.binary(min_size=1, max_size=64))
        return data[:at] + chunk + data[at + len(chunk) :]
    length = draw(st.integers(1, 256))
    return data[:at] + data[at : at + length] + data[at:]


def import_file(path: Path, **options):
    return refused_or_fine(lambda: import_measured(MeasuredSpec(name="rig", path=str(path), **options)))


@pytest.mark.parametrize("fmt", FORMATS)
@fuzz(40)
@given(data=st.data())
def test_damaged_files_import_or_are_refused(valid_files, damaged_dir, fmt, data):
    path, options, _ = valid_files[fmt]
    damaged = damaged_dir / f"{fmt}{path.suffix}"
    damaged.write_bytes(data.draw(damaged_bytes(path.read_bytes())))
    import_file(damaged, **options)


@pytest.mark.parametrize("suffix", [".csv", ".npz", ".h5", ".hdf5", ".wav", ".mat"])
@fuzz(25)
@given(data=st.binary(max_size=600))
def test_random_bytes_are_refused(damaged_dir, suffix, data):
    path = damaged_dir / f"random{suffix}"
    path.write_bytes(data)
    import_file(path, vibration="acc", speed_hz=25.0)


N = 3000  # samples of the structured records: 3 revolutions at 25 Hz and 25 kHz


def channels() -> st.SearchStrategy:
    """A channel's values: plausible signals, edge values, other dtypes and shapes."""
    t = np.arange(N)
    theta = 0.3 + 2 * np.pi * 25 * t / 25e3
    shaped = [
        np.sin(3 * theta),
        (theta + np.pi) % (2 * np.pi) - np.pi,
        theta,
        ((theta % (2 * np.pi)) < 1).astype(float) * 5,
        np.zeros(N),
        np.full(N, np.nan),
        np.where(t == 1234, np.inf, 0.0),
        np.full(N, 1e308),
        np.full(N, 5e-324),
        t.astype(np.int16),
        (t % 2).astype(bool),
        np.where(t < N // 2, "healthy", "fault"),
        np.full(N, "x\ny"),
        t * (1 + 1j),
        np.zeros(0),
        np.array(7.0),
        np.array("text"),
        np.zeros((N, 2)),
        np.zeros((1, N)),
        np.zeros(N - 1),
        np.zeros(N, dtype=np.float16),
        -theta,
        theta * 1e6,
        np.repeat([0.0, 1.0, 2.0], N // 3),
    ]
    return st.sampled_from(shaped)


rates = st.sampled_from(
    [
        np.array(25e3),
        np.array(25e3, dtype=np.float32),
        np.array(0.0),
        np.array(-1.0),
        np.array(np.nan),
        np.array(1e-300),
        np.array(1e300),
        np.array("25k"),
        np.array([25e3, 1.0]),
        np.array(True),
        np.array(2**62),
        np.arange(N) / 25e3,
        np.arange(N)[::-1] / 25e3,
        np.array(25e3 + 0j),
    ]
)


@st.composite
def records(draw) -> tuple[dict, dict]:
    """Named arrays of a record and the import options that point into them."""
    arrays = {"acc": draw(channels())}
    options: dict = {"vibration": "acc"}
    if draw(st.booleans()):
        arrays["tacho"] = draw(channels())
        options["tacho"] = "tacho"
        options["tacho_kind"] = draw(st.sampled_from(["auto", "angle", "pulses"]))
    else:
        options["speed_hz"] = draw(st.sampled_from([25.0, 1e-9, 1e9, 0.37, 12500.0]))
    if draw(st.booleans()):
        arrays["label"] = draw(channels() | st.sampled_from([np.array("fault"), np.array(1), np.array(-1)]))
        options["labels"] = "label"
        options["class_names"] = draw(st.sampled_from([("healthy", "fault"), ("healthy",), ("fault", "healthy", "x")]))
    for name in draw(st.lists(st.sampled_from(["fs", "Fs", "t", "time"]), max_size=2, unique=True)):
        arrays[name] = draw(rates)
    if draw(st.booleans()):
        options["fs"] = draw(st.sampled_from([25e3, 24e3, 1e-6, 1e12]))
    options["transient"] = draw(st.sampled_from(["stats", "none"]))
    return arrays, options


def write_record(directory: Path, fmt: str, arrays: dict) -> Path | None:
    """*arrays* in format *fmt*, or None where the format cannot hold them."""
    if fmt == "npz":
        path = directory / "r.npz"
        np.savez(path, **arrays)
    elif fmt == "csv":
        path = directory / "r.csv"
        columns = {k: np.atleast_1d(v).ravel() for k, v in arrays.items()}
        rows = max(len(c) for c in columns.values())
        lines = [",".join(columns)] + [
            ",".join(str(c[i]) if i < len(c) else "" for c in columns.values()) for i in range(rows)
        ]
        path.write_text("\n".join(lines) + "\n")
    elif fmt == "h5":
        path = directory / "r.h5"
        with h5py.File(path, "w") as f:
            for k, v in arrays.items():
                if v.dtype.kind == "U":
                    f.create_dataset(k, data=v.astype(object), dtype=h5py.string_dtype())
                elif k.lower() == "fs":
                    f.attrs[k] = v
                else:
                    f.create_dataset(k, data=v)
    elif fmt == "mat5":
        path = directory / "r5.mat"
        scipy.io.savemat(path, arrays)
    else:
        path = directory / "r73.mat"
        if any(v.dtype.kind not in "biuf" for v in arrays.values()):
            return None
        write_mat73(path, arrays)
    return path


@pytest.mark.parametrize("fmt", ["npz", "csv", "h5", "mat5", "mat73"])
@fuzz(60)
@given(record=records())
def test_records_of_any_content_import_or_are_refused(damaged_dir, fmt, record):
    arrays, options = record
    path = write_record(damaged_dir, fmt, arrays)
    if path is not None:
        import_file(path, **options)


# ============================================================================= the CLI


def run_cli(*args) -> tuple[int, str]:
    """`gearlab ARGS` in this process: (exit code, stderr)."""
    from gearlab.cli import main

    err = io.StringIO()
    argv = sys.argv
    sys.argv = ["gearlab", *map(str, args)]
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            main()
        code = 0
    except SystemExit as exc:
        code = exc.code or 0
    finally:
        sys.argv = argv
    return code, err.getvalue()


@pytest.fixture(scope="module")
def cli_dir(tmp_path_factory, valid_files):
    """A folder with a measured record the scenarios may name, and a cache of its own."""
    base = tmp_path_factory.mktemp("cli")
    (base / "rec.npz").write_bytes(valid_files["npz"][0].read_bytes())
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("GEARLAB_CACHE", str(base / "cache"))
        yield base


@fuzz(60)
@given(doc=mutated_scenarios(), quick=st.booleans())
def test_rejected_run_leaves_no_run_directory(cli_dir, doc, quick):
    """Scenarios that validation refuses, and those refused only once at work (a measured file
    that does not import, a --quick shrink the protocol cannot use): exit code 2, one error
    line, and no run directory left under --out."""
    path = cli_dir / "s.toml"
    path.write_bytes(toml_bytes(doc))
    try:
        load_scenario(path)
        kind = doc["scenario"]["kind"]
    except GearlabInputError:
        kind = None
    # A valid scenario would run for real; only a dataset of the measured record is quick enough.
    if kind is not None and not (kind == "dataset" and all("file" in d for d in doc.get("datasets", []))):
        return
    out = cli_dir / "runs"
    shutil.rmtree(out, ignore_errors=True)  # an earlier example's finished run
    with no_hang():
        code, err = run_cli("run", path, "--out", out, *(["--quick"] if quick else []))
    if code == 0:
        return
    assert code == 2, err
    assert err.splitlines()[-1].startswith("error: ") and "Traceback" not in err, err
    assert not out.exists() or not any(out.rglob("*")), f"a refused run left {sorted(out.rglob('*'))}"


@pytest.mark.parametrize("case", ["measured file damaged", "quick shrink refused"])
def test_run_refused_at_work_leaves_no_run_directory(cli_dir, case):
    out = cli_dir / "runs-refused"
    path = cli_dir / "refused.toml"
    if case == "measured file damaged":
        # its header is sound (validate reads no more), a later line is cut short
        (cli_dir / "bad.csv").write_text("time,acc\n0,1\n0.001,2\n0.002\n")
        doc = {
            "scenario": {"name": "m", "kind": "dataset"},
            "datasets": [{"file": "bad.csv", "vibration": "acc", "speed": 25.0}],
        }
        args, fact = [], "line 4 has 1 fields"
    else:
        # valid as written (28 training samples); --quick leaves 8, fewer than a batch
        doc = copy.deepcopy(REAL["study.toml"])
        doc["protocol"]["batch"] = 20
        args, fact = ["--quick"], "[protocol] key 'batch'"
    path.write_bytes(toml_bytes(doc))
    load_scenario(path)  # valid: refused only once at work, or once shrunk
    code, err = run_cli("run", path, "--out", out, *args)
    last = err.strip().splitlines()[-1]  # after the progress lines of the work begun
    assert code == 2 and last.startswith("error: ") and fact in last, err
    assert not out.exists() or not any(out.rglob("*"))


# ============================================================================= hostile scenarios (hardening)

# What a hostile (or careless) user puts into a name that may become a path component.
PATH_TEXTS = [
    "../../../../../../tmp/gearlab-escape",
    "..",
    ".",
    "/",
    "/tmp/gearlab-abs",
    "a/b",
    "a\\..\\b",
    "~",
    "../x",
    "x/..",
    ".hidden",
    " ",
    "x\u0000y",
    "con",
    "..\u2215x",
    "%2e%2e%2fx",
    "a\nb",
    "é" * 120,
    "x" * 5000,
]
HUGE = [10**30, -(10**30), 2**64, 1e300, -1e300, float("inf"), float("nan"), 10**400]


# Folders of gearlab-* in /tmp that other processes make and remove while a run here goes on: the
# fallback dataset cache, this module's stand-ins (every process that collects it makes its own) and an
# executor's count folder (a TemporaryDirectory, removed by its own block). Another session's suite on the
# same machine made and removed them between the two listings (a flaky failure, FlakyFailure: the
# listing differed by a gearlab-fuzz-* and a gearlab-counts-* folder, not by a hostile name's). So do the
# suite's other workers: a headless browser's profile (tests/browser.py), a local pool's shared arrays and
# the session folders of another pytest run (conftest.session_folder): a gearlab-chromium-* folder once.
OTHERS_TMP = (
    "gearlab-cache-",
    "gearlab-fuzz-",
    "gearlab-counts-",
    "gearlab-chromium-",
    "gearlab-shared-",
    "gearlab-test-",
)


def in_tmp() -> list[Path]:
    """The gearlab-* entries of /tmp that a hostile name could have made (OTHERS_TMP left out)."""
    return sorted(p for p in Path("/tmp").glob("gearlab-*") if not p.name.startswith(OTHERS_TMP))


def name_spots(doc: dict) -> list[tuple[dict, str]]:
    """The tables whose 'name' (or a 'file') may reach a path: [scenario], every [[datasets]],
    [[cases]], [source] and [target]."""
    spots: list[tuple[dict, str]] = [(doc["scenario"], "name")]
    for table in ("datasets", "cases"):
        spots += [(entry, "name") for entry in doc.get(table, []) if isinstance(entry, dict)]
    for table in ("source", "target"):
        if isinstance(doc.get(table), dict):
            spots += [(doc[table], "name"), (doc[table], "file")]
    return spots


@st.composite
def hostile_scenarios(draw) -> bytes:
    """A shipped (or the measured) scenario with a path in a name-like field, a huge value,
    or a value nested hundreds deep; as TOML text (tomli_w itself recurses too deep for the last)."""
    rnd = random.Random(draw(st.integers(0, 2**64)))
    doc = copy.deepcopy(
        REAL[rnd.choice(["measured.toml", "measured.toml", "cases.toml", "quick.toml", "dataset_B.toml", "study.toml"])]
    )
    op = rnd.choice(["path", "path", "huge", "deep"])
    if op == "path":
        for _ in range(rnd.randint(1, 2)):
            table, key = rnd.choice(name_spots(doc))
            table[key] = draw(st.sampled_from(PATH_TEXTS))
        return toml_bytes(doc)
    parent, key = rnd.choice([(c, k) for c, k in places(doc) if not isinstance(c[k], (dict, list))])
    if op == "huge":
        parent[key] = draw(st.sampled_from(HUGE))
        return toml_bytes(doc)
    parent[key] = "DEEP"
    depth = draw(st.sampled_from([200, 500, 2000]))
    return toml_bytes(doc).replace(b'"DEEP"', b"[" * depth + b"]" * depth, 1)


@fuzz(40)
@given(data=hostile_scenarios())
def test_hostile_scenarios_write_nothing_outside_out(cli_dir, data):
    """Exit code 2 with one error line (or a run that works), and nothing written outside --out:
    the listing of the folder that holds the scenario and --out is the same before and after,
    but for --out."""
    parent = cli_dir / "hostile"
    shutil.rmtree(parent, ignore_errors=True)
    parent.mkdir()
    (parent / "rec.npz").write_bytes((cli_dir / "rec.npz").read_bytes())
    path = parent / "s.toml"
    path.write_bytes(data)
    try:
        valid = load_scenario(path)
    except GearlabInputError:
        valid = None
    if valid is not None and not (valid.kind == "dataset" and all(d["file"] for d in valid.tables["datasets"])):
        return  # a valid scenario would run for real; only a measured dataset is quick enough
    out = parent / "out"
    before = {p for p in parent.rglob("*")}
    outside = in_tmp()
    with no_hang():
        code, err = run_cli("run", path, "--out", out)
    assert code in (0, 2), err
    if code == 2:
        assert err.splitlines()[-1].startswith("error: ") and "Traceback" not in err, err
        assert len(err.splitlines()[-1]) < 700, err
    after = {p for p in parent.rglob("*") if p != out and not p.is_relative_to(out)}
    assert after == before, f"written outside --out: {sorted(after - before)}"
    assert in_tmp() == outside
