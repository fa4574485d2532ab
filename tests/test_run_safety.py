"""A run directory that cannot be turned against its user (issue 40).

A run directory may come from someone else. Whatever was planted in it (a symbolic link at a
name a run writes or reads, a hard link, a pipe, another account's file), `gearlab run
--resume` and `gearlab report` refuse it in one line with exit code 2 and write or read
nothing outside it; every write of the package goes through gearlab.confined (checked by
reading the source); the measured-file readers refuse what would read another file (HDF5
external storage and links) or take more memory than GEARLAB_MAX_RECORD_MB (a zip bomb).
"""

from __future__ import annotations

import ast
import json
import os
import shutil
import stat
import tracemalloc
import zipfile
from pathlib import Path

import h5py
import numpy as np
import pytest
from tiny import stiffness

from gearlab import confined
from gearlab.confined import Confined, refuse_unsafe
from gearlab.data.importers import MeasuredSpec, import_measured, read_channels
from gearlab.data.readers.text import read_columns
from gearlab.data.recordings import cut_recording
from gearlab.errors import GearlabInputError
from gearlab.learn.protocol import StateStore
from gearlab.runs import RunDir

ROOT = Path(__file__).resolve().parents[1]
SECRET = b"the user's own file: never to be written, read or shown by gearlab\n"

PITTED = '[[cases]]\nname = "pitted"\nfaults = [{ kind = "pit", tooth = 9, step = 20 }]\n'
STIFFNESS = stiffness(256, ["crack"], (1, 10), tooth=5, cases=PITTED)


def one_line_refusal(code: int, out: str, err: str) -> str:
    """The refusal: exit code 2, no traceback, one error line (after any progress lines)."""
    text = (out + err).strip()
    assert code == 2, text
    errors = [line for line in text.splitlines() if line.startswith("error")]
    assert "Traceback" not in text and len(errors) == 1 and text.endswith(errors[0]), text
    return errors[0]


# ----------------------------------------------------------------------------- a finished run


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    """A finished stiffness run (seconds): results, cases, tables, figures, report (its lock gone)."""
    from gearlab.engine import run_scenario

    base = tmp_path_factory.mktemp("finished")
    (base / "s.toml").write_text(STIFFNESS)
    run = run_scenario(base / "s.toml", out=base / "runs")
    return run.path


@pytest.fixture
def victims(tmp_path):
    """A file and a folder of the user's, outside any run directory."""
    victim = tmp_path / "important.txt"
    victim.write_bytes(SECRET)
    folder = tmp_path / "elsewhere"
    folder.mkdir()
    (folder / "keep.txt").write_bytes(SECRET)
    return victim, folder


def untouched(victim: Path, folder: Path) -> None:
    assert victim.read_bytes() == SECRET
    assert sorted(p.name for p in folder.iterdir()) == ["keep.txt"]
    assert (folder / "keep.txt").read_bytes() == SECRET


def copy_of(run: Path, tmp_path: Path) -> Path:
    """A copy of the run with its last result dropped, so that a resume has work to do."""
    copy = tmp_path / "runs" / "stiff" / run.name
    shutil.copytree(run, copy)
    lines = (copy / "results.jsonl").read_text().splitlines(keepends=True)
    (copy / "results.jsonl").write_text("".join(lines[:-1]))
    return copy


# every name a run writes or reads, and folders it writes into (what a stiffness run lacks
# included: the names other kinds write, the temporary names of an interrupted write)
PLANTED = [
    ".lock",
    "results.jsonl",
    "run.json",
    "scenario.toml",
    "scenario.original.toml",
    "summary.json",
    "table.md",
    "table.csv",
    "report.html",
    "cases",
    "cases/pitted.csv",
    "figures",
    "figures/tvms_cases.png",
    "figures/zz.png",
    "figures/.signals_rig.tmp.png",
    ".summary.json.0123456789ab.tmp",
    "progress",
    "progress/rep0__k0.txt",
    "states",
    "latent",
    "targets",
    "bound.json",
    "conditions.json",
]


def plant(run: Path, name: str, victim: Path, folder: Path) -> None:
    """A symbolic link at *name*: to the user's folder where a folder is, else to the file."""
    where = run / name
    is_folder = where.is_dir() or name in ("progress", "states", "latent", "targets")
    if where.is_dir():
        shutil.rmtree(where)
    elif where.exists():
        if name == "results.jsonl":  # the reproduction: the store's lines now in the user's file
            victim.write_bytes(SECRET)
        where.unlink()
    where.parent.mkdir(parents=True, exist_ok=True)
    where.symlink_to(folder if is_folder else victim)


@pytest.mark.parametrize("name", PLANTED)
def test_a_link_planted_at_any_name_is_refused_by_resume(finished, tmp_path, victims, cli, name):
    victim, folder = victims
    run = copy_of(finished, tmp_path)
    plant(run, name, victim, folder)
    text = one_line_refusal(*cli("run", "--resume", run))
    assert "refused" in text and "symbolic link" in text
    untouched(victim, folder)


@pytest.mark.parametrize("name", PLANTED)
def test_a_link_planted_at_any_name_is_refused_by_report(finished, tmp_path, victims, cli, name):
    victim, folder = victims
    run = copy_of(finished, tmp_path)
    plant(run, name, victim, folder)
    text = one_line_refusal(*cli("report", run))
    assert "refused" in text and "symbolic link" in text
    untouched(victim, folder)
    page = run / "report.html"
    assert page.is_symlink() or SECRET not in page.read_bytes()


def test_the_probes_lock_link_writes_no_pid(tmp_path, victims, cli):
    """S1: a folder holding an empty scenario.toml and .lock -> the user's file."""
    victim, folder = victims
    evil = tmp_path / "evil"
    evil.mkdir()
    (evil / "scenario.toml").touch()
    (evil / ".lock").symlink_to(victim)
    one_line_refusal(*cli("run", "--resume", evil))
    untouched(victim, folder)


@pytest.mark.parametrize("name", [".lock", "results.jsonl"])
def test_a_file_changed_in_place_with_another_hard_link_is_refused(finished, tmp_path, victims, cli, name):
    """The lock is truncated and the store appended in place: a second name for the user's
    file there (a hard link, which no scan of links sees) is refused, the file untouched."""
    victim, folder = victims
    run = copy_of(finished, tmp_path)
    (run / name).unlink(missing_ok=True)  # a finished run leaves no .lock
    os.link(victim, run / name)
    text = one_line_refusal(*cli("run", "--resume", run))
    assert "hard link" in text
    untouched(victim, folder)


def test_a_pipe_or_device_in_the_run_is_refused_without_waiting(finished, tmp_path, cli):
    run = copy_of(finished, tmp_path)
    os.mkfifo(run / "figures" / "zz.png")  # reading it would wait for a writer forever
    assert "named pipe" in one_line_refusal(*cli("report", run))
    if os.geteuid() == 0:
        (run / "figures" / "zz.png").unlink()
        os.mknod(run / "figures" / "zz.png", stat.S_IFCHR | 0o600, os.makedev(1, 3))  # /dev/null's numbers
        assert "a device" in one_line_refusal(*cli("report", run))


def test_another_accounts_entry_is_refused(finished, tmp_path, cli, monkeypatch):
    run = copy_of(finished, tmp_path)
    if os.geteuid() == 0:
        os.chown(run / "table.md", 4242, 4242)
        assert "owned by uid 4242" in one_line_refusal(*cli("report", run))
    me = os.geteuid()
    monkeypatch.setattr(confined, "_owner", lambda: me + 1)  # as if another account ran the report
    assert f"owned by uid {me}" in one_line_refusal(*cli("report", run))


def test_a_clean_copy_resumes_and_reports(finished, tmp_path, cli):
    run = copy_of(finished, tmp_path)
    (run / "figures" / ".tvms_cases.tmp.png").write_bytes(b"cut short")  # an earlier version's temporary
    code, out, err = cli("run", "--resume", run)
    assert code == 0, out + err
    assert not list(run.rglob("*.tmp*"))
    assert cli("report", run)[0] == 0


# ----------------------------------------------------------------------------- the helper


def test_the_helper_never_follows_a_link(tmp_path, victims):
    victim, folder = victims
    root = tmp_path / "run"
    (root / "figures").mkdir(parents=True)
    (root / "out").symlink_to(folder)
    (root / "figures" / "a.png").symlink_to(victim)
    with pytest.raises(GearlabInputError, match="symbolic link"):
        Confined(root, ("out", "x.png")).write(b"png")
    with pytest.raises(GearlabInputError, match="symbolic link"):
        Confined(root, ("figures", "a.png")).read_bytes()
    with pytest.raises(GearlabInputError, match="symbolic link"):
        Confined(root, ("figures", "a.png")).append(b"line\n")
    Confined(root, ("figures", "a.png")).write(b"png")  # a whole file replaces the link itself
    assert not (root / "figures" / "a.png").is_symlink() and (root / "figures" / "a.png").read_bytes() == b"png"
    untouched(victim, folder)
    assert sorted(p.name for p in (root / "figures").iterdir()) == ["a.png"]  # no temporary left


@pytest.mark.parametrize("parts", [("..", "x"), ("/etc/passwd",), ("a\0b",), ("a/../../x",), ("n" * 256,)])
def test_the_helper_refuses_names_that_lead_out_or_cannot_be(tmp_path, parts):
    with pytest.raises(GearlabInputError, match="refused"):
        Confined(tmp_path, parts)


def test_temporary_names_are_fresh_and_fit(tmp_path):
    long = "n" * 255  # the longest name: its temporary still fits
    Confined(tmp_path, (long,)).write(b"x")
    assert (tmp_path / long).read_bytes() == b"x"
    assert [p.name for p in tmp_path.iterdir()] == [long]


def test_refuse_unsafe_walks_every_folder(tmp_path, victims):
    victim, _ = victims
    (tmp_path / "run" / "a" / "b").mkdir(parents=True)
    refuse_unsafe(tmp_path / "run")
    (tmp_path / "run" / "a" / "b" / "c").symlink_to(victim)
    with pytest.raises(GearlabInputError, match="c: refused: a symbolic link"):
        refuse_unsafe(tmp_path / "run")


# ----------------------------------------------------------------------------- no write bypasses it

# Where a file may be opened or written without gearlab.confined, and why: none of these is
# in a run directory. (path, function or None for the whole module) -> reason.
ALLOWED = {
    ("gearlab/confined.py", None): "the helper itself",
    ("gearlab/files.py", None): "atomic_write, for files outside any run directory; /proc/self/status",
    ("gearlab/cli", None): "files the user names on the command line: --out, --csv, --plot, --html",
    ("gearlab/data", None): "measured input files (read only) and the dataset cache in $GEARLAB_CACHE",
    ("gearlab/runs.py", "input_digest"): "measured input files, hashed: for --resume, and by gearlab score",
    ("gearlab/settings_doc.py", "main"): "docs/settings.md in the source tree, a developer's command",
    ("gearlab/executors.py", "report"): "a unit's count (a gap fit's evaluations), in a temporary folder of its own",
}
SAVES = {"save", "savez", "savez_compressed", "savetxt", "tofile"}
LOADS = {"load", "loadtxt", "fromfile"}
NOT_FILES = {"RunDir", "webbrowser", "executor"}  # X.open(...) that opens no file (executor: a Ray session)


def _in_memory(node: ast.AST, buffers: set[str]) -> bool:
    """Whether the target of a save or the source of a load is an io.BytesIO/StringIO."""
    if isinstance(node, ast.Name):
        return node.id in buffers
    return isinstance(node, ast.Call) and ast.unparse(node.func) in ("io.BytesIO", "io.StringIO")


def file_calls(path: Path) -> list[tuple[str | None, int, str]]:
    """(enclosing function, line, call) of every open, savefig, np.save*/load*, torch.save/load,
    Path.write_* and atomic_write in the module, other than to or from a buffer in memory."""
    tree = ast.parse(path.read_text())
    found = []

    def visit(node: ast.AST, function: str | None, buffers: set[str]) -> None:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            function = node.name
            buffers = {
                t.id
                for n in ast.walk(node)
                if isinstance(n, ast.Assign) and _in_memory(n.value, set())
                for t in n.targets
                if isinstance(t, ast.Name)
            }
        if isinstance(node, ast.Call):
            f, args = node.func, node.args
            target = args[0] if args else None
            base = ast.unparse(f.value) if isinstance(f, ast.Attribute) else None
            attr = f.attr if isinstance(f, ast.Attribute) else f.id if isinstance(f, ast.Name) else ""
            hit = (
                (isinstance(f, ast.Name) and attr in ("open", "atomic_write"))
                or (base is not None and attr == "open" and base not in NOT_FILES)
                or (attr in ("write_text", "write_bytes") and len(args) == 1)  # Path's; RunDir's takes a name
                or (attr == "savefig" and not _in_memory(target, buffers))
                or (base in ("np", "numpy") and attr in SAVES and not _in_memory(target, buffers))
                or (base in ("np", "numpy", "torch") and attr in LOADS and not _in_memory(target, buffers))
                or (base == "torch" and attr == "save" and not _in_memory(args[1] if len(args) > 1 else None, buffers))
            )
            if hit:
                found.append((function, node.lineno, ast.unparse(node)[:100]))
        for child in ast.iter_child_nodes(node):
            visit(child, function, buffers)

    visit(tree, None, set())
    return found


def allowed(module: str, function: str | None) -> bool:
    return any(
        (module == where or module.startswith(where + "/")) and name in (None, function) for where, name in ALLOWED
    )


def test_every_file_write_of_the_package_goes_through_the_helper():
    bypass = []
    for path in sorted([*(ROOT / "gearlab").rglob("*.py"), *(ROOT / "plugins").rglob("*.py")]):
        module = path.relative_to(ROOT).as_posix()
        bypass += [
            f"{module}:{line} ({function}): {call}"
            for function, line, call in file_calls(path)
            if not allowed(module, function)
        ]
    assert not bypass, (
        "file calls outside gearlab.confined (add a reason to ALLOWED if none is a run's):\n" + "\n".join(bypass)
    )


def test_the_listing_sees_each_kind_of_call(tmp_path):
    source = tmp_path / "m.py"
    source.write_text(
        "import io\nimport numpy as np\nimport torch\n"
        "def f(fig, path, run, state):\n"
        "    buf = io.BytesIO()\n"
        "    fig.savefig(buf)\n    np.savez(buf, a=1)\n    torch.save(state, buf)\n"  # in memory: fine
        "    run.write_text('table.md', 'x')\n    np.load(io.BytesIO(b''))\n"  # the helper, a buffer: fine
        "    fig.savefig(path)\n    np.save(path, 1)\n    torch.save(state, path)\n"
        "    path.write_text('x')\n    open(path, 'w')\n    path.open('w')\n    np.load(path)\n"
    )
    assert [line for _, line, _ in file_calls(source)] == [11, 12, 13, 14, 15, 16, 17]
    assert allowed("gearlab/data/readers/npz.py", "x") and not allowed("gearlab/runs.py", "records")


# ----------------------------------------------------------------------------- HDF5


def _raw(tmp_path: Path) -> Path:
    other = tmp_path / "other.bin"
    np.arange(4000, dtype="<f8").tofile(other)
    with h5py.File(tmp_path / "other.h5", "w") as f:
        f["acc"] = np.arange(4000, dtype="<f8")
    return other


def _external_storage(f, tmp_path):
    f.create_dataset("acc", shape=(4000,), dtype="<f8", external=[(str(_raw(tmp_path)), 0, 32000)])


def _external_link(f, tmp_path):
    _raw(tmp_path)
    f["acc"] = h5py.ExternalLink(str(tmp_path / "other.h5"), "/acc")


def _soft_link(f, tmp_path):
    f["g/real"] = np.arange(4000.0)
    f["acc"] = h5py.SoftLink("/g/real")


def _virtual(f, tmp_path):
    _raw(tmp_path)
    layout = h5py.VirtualLayout(shape=(4000,), dtype="<f8")
    layout[:] = h5py.VirtualSource(str(tmp_path / "other.h5"), "acc", shape=(4000,))
    f.create_virtual_dataset("acc", layout)


@pytest.mark.parametrize(
    "make, said",
    [
        (_external_storage, "dataset '/acc' keeps its samples in another file"),
        (_external_link, "'/acc' is an external link"),
        (_soft_link, "'/acc' is a soft link"),
        (_virtual, "dataset '/acc' is a virtual dataset"),
    ],
)
def test_hdf5_channels_stored_elsewhere_are_refused(tmp_path, make, said):
    path = tmp_path / "rec.h5"
    with h5py.File(path, "w") as f:
        make(f, tmp_path)
        f.attrs["fs"] = 1000.0
    with pytest.raises(GearlabInputError, match=said) as caught:
        read_channels(path, ["acc"])
    assert str(path) in str(caught.value) and "\n" not in str(caught.value)


def test_an_external_link_is_no_rate_field_either(tmp_path):
    _raw(tmp_path)
    with h5py.File(tmp_path / "rec.h5", "w") as f:
        f["acc"] = np.arange(4000.0)
        f["fs"] = h5py.ExternalLink(str(tmp_path / "other.h5"), "/acc")
    assert read_channels(tmp_path / "rec.h5", ["acc"])[1] is None  # not opened


# ----------------------------------------------------------------------------- memory


def refused_peak(path: Path, message: str) -> int:
    """The most memory (bytes) that reading two columns of *path* took before it was refused with *message*."""
    tracemalloc.start()
    try:
        with pytest.raises(GearlabInputError, match=message):
            read_columns(path, [0, 1])
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_a_zip_bomb_is_refused_under_the_memory_limit(tmp_path, monkeypatch):
    """S7: 49 kB of zip holding 32 MB of '0 0 0' lines: refused by its declared size under
    GEARLAB_MAX_RECORD_MB, before anything is inflated."""
    bomb = tmp_path / "bomb.zip"
    with zipfile.ZipFile(bomb, "w", compression=zipfile.ZIP_DEFLATED, compresslevel=9) as z:
        with z.open("r.txt", "w", force_zip64=True) as f:
            for _ in range(54):
                f.write(b"0 0 0\n" * 100_000)
    assert bomb.stat().st_size < 100_000
    monkeypatch.setenv("GEARLAB_MAX_RECORD_MB", "4")
    assert refused_peak(bomb, "more than the limit of 4 MB") < 4 * 2**20


def test_the_limit_holds_while_streaming(tmp_path, monkeypatch):
    """Text within the limit whose columns outgrow it (short rows): stopped while read, at
    about the limit, not after."""
    text = tmp_path / "r.txt"
    text.write_bytes(b"0 0 0\n" * 1_500_000)  # 9 MB of text, 24 MB of the two columns
    monkeypatch.setenv("GEARLAB_MAX_RECORD_MB", "10")
    assert refused_peak(text, "the columns read so far") < 10 * 2**20 + 40 * 2**20  # the limit, plus a block's tokens


# ----------------------------------------------------------------------------- T1, T2, V


def test_a_damaged_network_state_is_one_line(tmp_path):
    """T2: a resumed run's states/*.pt cut short or overwritten: one line naming it."""
    (tmp_path / "states").mkdir()
    (tmp_path / "states" / "rep0_primed.pt").write_bytes(b"PK\x03\x04 not a state")
    store = StateStore(Confined(tmp_path, ("states",)))
    with pytest.raises(GearlabInputError, match=r"rep0_primed.pt: damaged network state .*remove the file"):
        store.get("rep0_primed", lambda: pytest.fail("made again"))


def _detection(tmp_path: Path, first_path: str) -> Path:
    record = tmp_path / "data" / "rec.zip"
    record.parent.mkdir()
    with zipfile.ZipFile(record, "w") as z:
        z.writestr("rec.txt", "0.1 0.2 0\n")
    text = (ROOT / "scenarios" / "phm09_chip.toml").read_text()
    head, _, rest = text.partition("files = [\n")
    _, _, tail = rest.partition("]\n")
    files = (
        f'  {{ path = "{first_path}", role = "history", label = "healthy", condition = "c" }},\n'
        '  { path = "data/rec.zip", role = "test", label = "fault", condition = "c" },\n'
    )
    scenario = tmp_path / "chip.toml"
    scenario.write_text(head + "files = [\n" + files + "]\n" + tail)
    return scenario


@pytest.mark.parametrize("path", ["d" * 300 + ".zip", "data/" + "e" * 300 + "/rec.zip", "data/missing.zip"])
def test_detection_target_files_that_cannot_be_are_one_line(tmp_path, cli, path):
    """T1: a [target] files path with a 300-character name: one line, exit 2, from validate."""
    text = one_line_refusal(*cli("validate", _detection(tmp_path, path)))
    assert "[target] key 'files' entry 1" in text


def _dataset(tmp_path: Path, entry: str) -> Path:
    scenario = tmp_path / "d.toml"
    scenario.write_text(f'[scenario]\nname = "d"\nkind = "dataset"\n\n[[datasets]]\n{entry}\n')
    return scenario


@pytest.mark.parametrize(
    "entry, said",
    [
        ('file = "missing.npz"\nvibration = "acc"\nspeed = "25 Hz"', "missing.npz: no such file"),
        (f'file = "{"f" * 300}.npz"\nvibration = "acc"\nspeed = "25 Hz"', "File name too long"),
        ('preset = "B-6-ch5"\nvibration = "acc"', "key 'vibration': a key of measured data"),
        ('preset = "B-6-ch5"\nsensitivity = "10 mV/g"', "key 'sensitivity': a key of measured data"),
    ],
)
def test_dataset_entries_that_cannot_work_are_refused_by_validate(tmp_path, cli, entry, said):
    """V: validate finds a missing or over-long measured file, and a measured-data key on a
    simulated preset (which would be silently ignored)."""
    assert said in one_line_refusal(*cli("validate", _dataset(tmp_path, entry)))


def test_zipped_text_refuses_a_constant_vibration_as_npz_does(tmp_path):
    fs, n = 20_000.0, 40_000
    t = np.arange(n) / fs
    pulses = (np.sin(2 * np.pi * 25 * t) > 0.9).astype(float)
    record = tmp_path / "rec.zip"
    with zipfile.ZipFile(record, "w") as z:
        z.writestr("rec.txt", "".join(f"0.5 {p:g}\n" for p in pulses))
    with pytest.raises(GearlabInputError, match="all 40000 values equal 0.5"):
        cut_recording(record, vibration=0, tacho=1, pulses_per_rev=1, sensitivity=1.0, fs=fs)
    np.savez(tmp_path / "rec.npz", acc=np.full(n, 0.5), fs=np.array(fs))
    with pytest.raises(GearlabInputError, match="zero variance"):
        import_measured(MeasuredSpec(name="c", path=str(tmp_path / "rec.npz"), vibration="acc", speed_hz=25.0))


def test_run_json_that_is_not_json_is_one_line(finished, tmp_path, cli):
    run = copy_of(finished, tmp_path)
    (run / "run.json").write_bytes(b"\xff\x00 not json")
    assert "run.json: damaged" in one_line_refusal(*cli("run", "--resume", run))
    json.loads((finished / "run.json").read_text())  # the original is fine
    assert RunDir.open(finished).quick is False
