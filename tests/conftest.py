import base64
import gc
import os
import shutil
import sys
from pathlib import Path

import pytest

from gearlab.physics.presets import PAIR_PRESETS, gear_pair
from gearlab.physics.stiffness import MeshStiffnessModel
from gearlab.registry import get_registry

ROOT = Path(__file__).resolve().parents[1]

# The test files of most CPU first (seconds in the README's suite at 0a03914, 2 workers): with
# `--dist loadfile` a file runs whole on one worker, handed out in collection order once xdist's own
# order (most tests first) is off. By test count, heavy files of few tests came last: there
# test_your_gearbox.py (2 tests, 15 s) kept one worker busy 28 s after the other had ended (load 6).
HEAVY_FIRST = (
    "test_tui.py",  # 94 s
    "test_gap_diagnose.py",  # 73 s
    "test_inspect.py",  # 53 s
    "test_tui_edges.py",  # 51 s (27 s at b2f7515, before four of its tests failed)
    "test_executors.py",  # 62 s of wall time in one process at 17d49c4 (4 s of its own CPU: Ray and the pools')
    "test_outside_cn.py",  # 27 s (a484985, the README's suite, 3 workers; collected late: alphabetical)
    "test_outside_cv.py",  # 27 s
    "test_protocol.py",  # 36 s
    "test_slow_shaft.py",  # 27 s of CPU in one process at 17d49c4 (then collected near the end)
    "test_outside_user.py",  # 26 s of CPU in one process at 17d49c4
    "test_crash_safety.py",  # 26 s
    "test_fuzz.py",  # 24 s
    "test_gap_load.py",  # 21 s (a484985)
    "test_box_b_takes.py",  # 21 s (a484985)
    "test_detection.py",  # 21 s
    "test_verdict.py",  # 17 s
    "test_outside_j.py",  # 13 s (a484985)
    "test_outside_at.py",  # 12 s (a484985)
    "test_inspect_simulated.py",  # 16 s
    "test_your_gearbox.py",  # 15 s
    "test_user_gearbox_e2e.py",  # 14 s
    "test_tacho_shaft.py",  # 15 s of CPU in one process at 17d49c4
    # last in collection order, and heavy: handed out near the end they kept one worker busy alone
    # (the README's suite at 83bd07c, 2 workers: gw0 ended on test_which_gear_corrected + _phase, 33 s)
    "test_which_gear_parity.py",  # 21 s of CPU at 83bd07c
    "test_which_gear_phase.py",  # 19 s (with the 29/71 + 22/57 pinion test moved in)
    "test_leftovers_39.py",  # 12 s
    "test_localise_noise_units.py",  # 11 s
    "test_which_gear_corrected.py",  # 10 s
    "test_which_gear_words.py",  # 9 s
    "test_localise_three_stages.py",  # 9 s
)


def pytest_xdist_auto_num_workers(config):
    """`-n auto` (the README's test command) starts one worker more than the cores this process may use.
    A worker waits with its core idle while a test's child process starts and imports gearlab, while
    Textual's pilot settles, while Ray starts its processes, while a pool's workers start. A third worker on
    2 cores runs its files in those waits, for one more collection (about 5 s of CPU): the README's command
    in a fresh clone, 2 idle cores: pytest 265 / 267 s with two workers, 252 / 256 / 264 s with three.
    PYTEST_XDIST_AUTO_NUM_WORKERS (xdist's own) and `-n logical` are left to xdist."""
    if os.environ.get("PYTEST_XDIST_AUTO_NUM_WORKERS") or config.option.numprocesses == "logical":
        return None
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    return cores + 1


def pytest_configure(config):
    if getattr(config.option, "loadscopereorder", False):
        config.option.loadscopereorder = False  # xdist hands files out in the order below
    try:  # one full collection at the session's end, not pytest's five (GC_AT_THE_END)
        from _pytest.unraisableexception import gc_collect_iterations_key
    except ImportError:  # another pytest: its own number
        return
    config.stash[gc_collect_iterations_key] = GC_AT_THE_END
    library_asserts_kept_plain(config)
    rewritten_in_shared_folder()


def pytest_sessionstart(session):
    """The suite's datasets in one folder of its own, removed at the end, unless GEARLAB_CACHE is set: a
    run read and filled the user's cache (2.3 GB of test datasets on a developer's machine), so a second
    run timed what a fresh machine (CI) does not have. Set by the controlling process before xdist starts
    its workers, which inherit it and share the folder (the cache writes atomically)."""
    if hasattr(session.config, "workerinput"):
        return
    if "GEARLAB_CACHE" not in os.environ:
        os.environ["GEARLAB_CACHE"] = session_folder(session.config, "gearlab-test-cache-")
    # always the session's own: a finished run of another session may come from other code
    os.environ[SHARED_RUNS] = session_folder(session.config, "gearlab-test-runs-")
    if sys.dont_write_bytecode and REWRITTEN not in os.environ and getattr(session.config.option, "numprocesses", 0):
        os.environ[REWRITTEN] = session_folder(session.config, "gearlab-test-pyc-")
        rewritten_in_shared_folder()  # this process too, where it collects itself (--collect-only)


# The session's folder of finished runs that test files share (detection_scenario.shared_run): set by the
# controlling process, read by its xdist workers.
SHARED_RUNS = "GEARLAB_TEST_RUNS"


def session_folder(config, prefix: str) -> str:
    """A temporary folder of the session's, removed at its end."""
    import tempfile

    folder = tempfile.mkdtemp(prefix=prefix)
    config.add_cleanup(lambda: shutil.rmtree(folder, ignore_errors=True))
    return folder


# The session's folder of rewritten test modules where no bytecode is written beside the sources
# (PYTHONDONTWRITEBYTECODE, as in the fresh clone the README's test command is timed in): set by the
# controlling process, read by its xdist workers (rewritten_in_shared_folder).
REWRITTEN = "GEARLAB_TEST_REWRITTEN"


def rewritten_in_shared_folder() -> None:
    """Where PYTHONDONTWRITEBYTECODE is set, pytest writes no rewritten test module: each xdist worker
    rewrote the asserts of all 230 test files it collects (5.1 s of CPU a worker: --collect-only 9.1 s
    against 4.0 s with them cached), each the same. The session's folder (REWRITTEN) takes the
    rewritten modules instead of tests/__pycache__, written there by rewrite_ahead, so the workers
    share that work (gw0 from the first file, the others from the last) and the sources' folders get
    no bytecode. Without REWRITTEN (one process, or bytecode written as usual): nothing changes."""
    folder = os.environ.get(REWRITTEN)
    if not folder:
        return
    try:
        from _pytest.assertion import rewrite
    except ImportError:  # another pytest: its own cache
        return

    def get_cache_dir(file_path: Path) -> Path:
        return Path(folder, *Path(file_path).resolve().parts[1:-1])

    rewrite.get_cache_dir = get_cache_dir


def library_asserts_kept_plain(config) -> None:
    """pytest rewrites the asserts of every module of a distribution that declares a pytest plugin,
    from its source: hypothesis's 73 modules, imported by the test files during collection, were
    parsed, rewritten and compiled again in every worker (0.5 s of CPU each, side by side, collection
    only; PYTHONDONTWRITEBYTECODE keeps no result), where their bytecode would do. Its internal
    asserts guard hypothesis itself; the tests' own asserts are rewritten as before."""
    hook = getattr(config.pluginmanager, "rewrite_hook", None)
    if hook is None or not hasattr(hook, "_must_rewrite"):  # another pytest, or --assert=plain
        return
    hook._must_rewrite.discard("hypothesis")
    hook._marked_for_rewrite_cache.clear()


def freed_memory_kept_for_reuse() -> None:
    """glibc's allocator gives a large block (a simulation's series, a record's 4 x denser reading: 1-30 MB)
    its own mapping and returns it to the system when it is freed, and shrinks the heap when its top is
    free: the next array of that size is mapped again and every page of it faults in zeroed. The test
    processes keep freed memory for the next array instead (mallopt: blocks up to 32 MB from the heap,
    the heap trimmed beyond 1 GB free), and so do the gearlab processes they start (the same settings
    through glibc's environment variables; a value already set is kept). Side by side (test_slow_shaft,
    test_which_gear_phase, test_tui_edges, test_detection in one process, nice, twice each): minor page
    faults 1.67 M -> 0.28 M, system CPU 4.8/4.7 -> 2.0/1.8 s, maximum RSS the same (0.97-1.00 GB).
    What a test computes is unchanged: only where freed memory goes. Elsewhere than glibc: nothing."""
    for name, value in MALLOC_KEPT.items():
        os.environ.setdefault(f"MALLOC_{name}_", str(value))
    try:
        import ctypes

        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):  # not glibc (macOS, musl without mallopt, Windows)
        return
    for option, name in ((-3, "MMAP_THRESHOLD"), (-1, "TRIM_THRESHOLD")):  # M_MMAP_THRESHOLD, M_TRIM_THRESHOLD
        value = os.environ[f"MALLOC_{name}_"]
        if value.isdigit():  # a value of the user's that glibc would not read either: left to glibc
            mallopt(option, int(value))


MALLOC_KEPT = {"MMAP_THRESHOLD": 32 << 20, "TRIM_THRESHOLD": 1 << 30}  # bytes; 32 MB is glibc's largest threshold
freed_memory_kept_for_reuse()


# pytest looks for exceptions raised in __del__ (unraisable) with five full garbage collections when
# a process ends; each walked a worker's whole heap again (0.6 s apiece after tests/test_tui.py alone,
# 620,000 objects): one finds every unreachable cycle, the other four only what finalizers leave.
GC_AT_THE_END = 1


@pytest.hookimpl(hookwrapper=True)
def pytest_collection(session):
    """No cyclic garbage collection while the test modules are imported, then what they imported kept
    out of every later one (gc.freeze): collecting every file imports torch, scipy, textual and all
    of gearlab, and each full collection walked that growing heap again (24 of 0.1-0.5 s per worker
    while it collected), then every one during the tests and pytest's five at its end (0.8 s each).
    Objects the tests make are collected as before, the whole heap less often (FULL_COLLECTION_EVERY)."""
    gc.disable()
    try:
        rewrite_ahead(session)
        yield
    finally:
        gc.enable()
        gc.collect()
        gc.freeze()
        _, middle, _ = gc.get_threshold()
        gc.set_threshold(YOUNG_COLLECTION_AFTER, middle, FULL_COLLECTION_EVERY)


def rewrite_ahead(session) -> None:
    """In a fresh clone each xdist worker rewrote the asserts of every test file it imports (pytest
    keeps the result in tests/__pycache__ only for the next run): 6 s of CPU per worker, twice on 2
    cores. Worker gw0 collects from the first file as usual; every other worker first rewrites the
    files from the last one backwards into that cache, without importing them, until it meets one
    already there (gw0 got that far), then collects reading the cache. Where no bytecode is written
    (PYTHONDONTWRITEBYTECODE) the cache is the session's folder (rewritten_in_shared_folder), which
    gw0 fills from the first file ahead of its collection too. Nothing is done with --assert=plain,
    outside xdist, or with another pytest (its internals differ): collection is then as before."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "gw0")
    config = session.config
    shared = bool(os.environ.get(REWRITTEN))  # no bytecode beside the sources: gw0 writes ahead too
    if (worker == "gw0" and not shared) or (sys.dont_write_bytecode and not shared):
        return
    if config.getoption("assertmode", "plain") != "rewrite":
        return
    try:
        from _pytest.assertion import rewrite

        state = config.stash[rewrite.assertstate_key]
        files = []
        for arg in config.args:
            path = Path(arg.split("::")[0]).resolve()
            files += sorted(path.glob("test_*.py")) if path.is_dir() else [path] if path.suffix == ".py" else []
        for fn in files if worker == "gw0" else reversed(files):
            cache = rewrite.get_cache_dir(fn)
            pyc = cache / (fn.name[:-3] + rewrite.PYC_TAIL)
            if not rewrite.try_makedirs(cache) or rewrite._read_pyc(fn, pyc, state.trace) is not None:
                return
            source_stat, co = rewrite._rewrite_test(fn, config)
            rewrite._write_pyc(state, co, source_stat, pyc)
    except Exception:  # noqa: BLE001 - a head start only: never a reason to fail the run
        return


# A full (oldest-generation) collection after every 100 collections of the middle one, not Python's
# 10: what the tests import lazily and what they keep (Textual's widgets, torch's modules) stays out
# of the frozen heap, so the full collections walked ~500,000 objects (0.27 s apiece). Side by side
# (one process, load ~10): test_tacho_shaft + test_tui_edges 39 full collections 10.5 s of CPU -> 11,
# 3.8 s (tests 58.2 -> 51.6 s of CPU), max RSS 595 -> 593 MB; test_which_gear_parity + test_gap_records
# + test_protocol 12, 1.7 s -> 4, 0.6 s, max RSS 631 -> 638 MB.
FULL_COLLECTION_EVERY = 100
# A young collection after 10,000 new container objects, not 700: the TUI tests make Textual's
# objects by the million. test_tacho_shaft + test_tui_edges (with the above): 8,708 young collections
# -> 580, the tests' CPU 51.7 -> 45.7 s, max RSS 590 -> 634 MB; test_which_gear_parity +
# test_gap_records + test_protocol + test_tui_arrows: 65.0 -> 65.8 s (noise), 640 -> 628 MB.
YOUNG_COLLECTION_AFTER = 10_000


def pytest_collection_modifyitems(config, items):
    rank = {name: i for i, name in enumerate(HEAVY_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(HEAVY_FIRST)))  # stable: the rest as collected


@pytest.fixture
def quiet(monkeypatch):
    """A score's trend PNG not drawn (matplotlib): its words are read from score_trends."""
    monkeypatch.setattr("gearlab.kinds.detection_figures.score_trend", lambda charts, path: path)


@pytest.fixture
def cli(capsys, monkeypatch):
    """Run the gearlab command in-process: returns (exit code, stdout, stderr)."""
    from gearlab.cli import main

    def run(*args: str):
        monkeypatch.setattr(sys, "argv", ["gearlab", *map(str, args)])
        code = 0
        try:
            main()
        except SystemExit as exc:
            code = exc.code or 0
        out = capsys.readouterr()
        return code, out.out, out.err

    return run


@pytest.fixture
def write_scenario(tmp_path):
    def write(text: str, name: str = "s.toml") -> Path:
        path = tmp_path / name
        path.write_text(text)
        return path

    return write


@pytest.fixture
def run_scenario(cli, write_scenario, tmp_path):
    """`gearlab run` of a scenario *text* (written into tmp_path, its runs under tmp_path/runs), which
    must finish: the run directory it printed last."""

    def run(text: str, name: str = "s.toml") -> Path:
        code, out, err = cli("run", write_scenario(text, name), "--out", tmp_path / "runs")
        assert code == 0, err
        return Path(out.strip().splitlines()[-1].removeprefix("run directory: "))

    return run


@pytest.fixture(scope="module")
def module_cache(tmp_path_factory):
    """One dataset cache for the tests of a module that asks for it: GEARLAB_CACHE while the module runs."""
    path = tmp_path_factory.mktemp("cache")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("GEARLAB_CACHE", str(path))
        yield path


@pytest.fixture
def gearlab(cli, monkeypatch, module_cache):
    """`gearlab ARGS` run from a folder, as a user types it there: (exit code, stdout + stderr), the
    datasets in the module's one cache (its runs often simulate the same source: once)."""
    monkeypatch.setenv("COLUMNS", "250")

    def run(folder, *args):
        monkeypatch.chdir(folder)
        code, out, err = cli(*args)
        return code, out + err

    return run


@pytest.fixture(scope="session", autouse=True)
def one_torch_thread():
    """Tiny networks gain nothing from threads, and on a busy machine threads spin against each other:
    every test runs on one torch thread (`pytest -n 2` runs two processes on two cores; measured,
    a 500-step training of the `shapes` network took 3.6 s on one thread, 71 s on two with the
    cores loaded)."""
    import torch

    before = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(before)


@pytest.fixture(scope="session", autouse=True)
def one_blas_thread():
    """numpy's BLAS (OpenBLAS) on one thread in the test processes, as torch (one_torch_thread): by default
    it starts a thread per core, and with `pytest -n 2` on two cores every call large enough to be split
    waited on a thread the other worker's core was busy with, spinning meanwhile. Measured, a 24,000-point
    dot product (signals.fixed_lines.clock_share reads 35 a take): 8 ms of CPU on two threads, 0.02 ms on
    one; test_outside_round14 + test_localise_noise_units in one process, load ~4: 18.1 / 20.6 s of CPU
    -> 12.9 / 13.9 s. The tests of where gearlab itself limits BLAS to one thread
    (blas_threads_as_started) lift it. Child processes (the TUI's, crash safety's, the pools') as before."""
    from threadpoolctl import threadpool_info, threadpool_limits

    BLAS_STARTED.extend(p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas")
    with threadpool_limits(limits=1, user_api="blas"):
        yield


BLAS_STARTED: list[int] = []  # the BLAS threads this process started with (one_blas_thread)


@pytest.fixture
def blas_threads_as_started():
    """numpy's BLAS threads as the process started with (one_blas_thread limits them to one): for the tests
    that check gearlab's own limit to one thread where a step wants it, which one thread would pass anyway."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=max(BLAS_STARTED, default=None), user_api="blas"):
        yield


@pytest.fixture(scope="session", autouse=True)
def no_flush_to_disk():
    """os.fsync in the test processes checks its file descriptor (os.fstat: a bad one fails alike) and
    does not wait for the disk: what it guards, a file that survives a power cut, no test can see, and a
    run's records, summaries, figures and cache entries waited 7-11 ms apiece on a busy machine (20 test
    files: 672 syncs, 5.8 s in all, a worker's core idle meanwhile). A kill, which crash safety tests,
    loses nothing a sync would keep. Tests that watch the syncs patch os.fsync themselves; the
    `gearlab` child processes of the TUI and crash-safety tests sync as they do for a user."""

    def checked(fd: int) -> None:
        os.fstat(fd)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(os, "fsync", checked)
        yield


@pytest.fixture(scope="session", autouse=True)
def pilot_settles_in_short_slices():
    """Textual's pilot waits after every key and pause until the app is idle: it sleeps a slice and
    stops once the process used under a twentieth of it (textual._wait), the slice 20 ms, at least
    one per call and two per key, while the test's core stays idle. The same rule in PILOT_SLICE:
    the TUI test files left a core idle 20.6 -> 9.5 s (test_tui_edges + test_tui_arrows, side by side)."""
    from textual import _wait

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(_wait, "SLEEP_GRANULARITY", PILOT_SLICE)
        mp.setattr(_wait, "SLEEP_IDLE", PILOT_SLICE / 20)
        yield


PILOT_SLICE = 0.005  # s; textual's own is 0.02


@pytest.fixture(scope="session", autouse=True)
def one_local_worker_unless_asked():
    """A scenario run in a test's process that leaves [execution] workers at 0 (all cores) runs its
    units in that process, as `workers = 1` does: `pytest -n` already gives each core a test file,
    and a pool per run started one process per core that imported torch, numba and gearlab again
    (tests/test_gap_records.py, test_recordings.py and test_gearbox_source.py: 56 s of CPU with
    their pools' processes, 31 s of it in the pools). The pool is tested where a test asks for one
    (LocalExecutor(2), `workers = 2`: test_executors, test_protocol, test_run_options) and in every
    `gearlab` child process (the TUI's runs, crash safety), which this does not reach; a run's
    records do not depend on its worker count (test_protocol.test_two_workers_give_the_records_of_one);
    test_executors checks that 0 still means every core."""
    from gearlab import executors

    real = executors.LocalExecutor.__init__

    def init(self, workers=None):
        real(self, 1 if workers is None else workers)

    init.every_core = real  # the real default, for the test that holds it
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(executors.LocalExecutor, "__init__", init)
        yield


@pytest.fixture(scope="session", autouse=True)
def cli_command_built_once():
    """typer builds the click command of the gearlab app anew on every call (the `cli` fixture's
    main(), CliRunner.invoke): every command's signature and type hints read again, 10 ms of CPU a
    call, 70 % of a `gearlab validate` in-process (227 calls in test_cli, test_hardening and five other
    files: 2.4 s). A gearlab process builds it once; here it is built once per app and set of
    registered commands, groups and callback (a Typer app a test makes, or one it changes, is built
    again), and the click command, which parses each call in a fresh context, invoked as before."""
    import typer.main
    import typer.testing

    real, built = typer.main.get_command, {}

    def get_command(app):
        key = (id(app), *map(id, app.registered_commands), None, *map(id, app.registered_groups))
        key += (id(app.registered_callback),)
        if key not in built:
            built[key] = (app, real(app))  # the app held: its id stays its own
        return built[key][1]

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(typer.main, "get_command", get_command)
        mp.setattr(typer.testing, "_get_command", get_command)
        yield


@pytest.fixture(scope="session")
def registry():
    return get_registry()


@pytest.fixture(scope="session")
def pairs():
    return {name: gear_pair(name) for name in PAIR_PRESETS}


@pytest.fixture(scope="session")
def models(pairs):
    """One stiffness model per gear-pair preset (their healthy TVMS caches are shared)."""
    return {name: MeshStiffnessModel(pair) for name, pair in pairs.items()}


@pytest.fixture
def no_figures(monkeypatch) -> None:
    """A detection run's report figures not drawn (detection_scenario.without_figures): for a test
    that reads none."""
    from detection_scenario import without_figures

    without_figures(monkeypatch)


ONE_PIXEL_PNG = base64.b64decode(
    "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNkYPhfDwAChwGA60e6kgAAAABJRU5ErkJggg=="
)


def unrendered(fig, path, dpi=120, **options):
    """gearlab.plots.save without the rendering: each figure is still built, written (one pixel) and
    counted in the run's 'report' stage, so a run's files and events are the engine's; rendering
    was a third of the every-kind runs' CPU (test_tui), for tests that read no figure's pixels."""
    from gearlab import plots

    path = plots.target(path)
    plots.plt.close(fig)
    plots.write_file(path, ONE_PIXEL_PNG)
    plots.figure_written(path.name)
    return path


@pytest.fixture
def unrendered_figures(monkeypatch) -> None:
    """A run's figures built and written as one pixel, not rendered (unrendered): for a test that
    reads no figure's pixels (a detection run's are also built: no_figures leaves them out)."""
    monkeypatch.setattr("gearlab.plots.save", unrendered)


@pytest.fixture(scope="module", autouse=True)
def figures_rendered_where_read(request):
    """Every test module's figures built and written as one pixel, not rendered (unrendered), but
    those of RENDERED, whose tests read a figure's pixels or size, draw reports in a browser or check
    the rendering itself (a new such file goes there). Rendering in the test processes was 30 s of the
    suite's 485 s of test CPU (-n 0), 18 s of it in 30 files of runs whose figures no test looked at
    (test_detection, test_gap_kind, test_crash_safety, test_executors ... 51.8 -> 39.6 s of CPU).
    Module scope: a module's shared runs (its module fixtures) are made after it. The `gearlab` child
    processes (TUI, crash safety, subprocess tests) and the pools' workers render as for a user."""
    if request.path.name in RENDERED:
        yield
        return
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr("gearlab.plots.save", unrendered)
        yield


# every kind's figures are rendered in test_verdict (each kind's report in a browser) or the benchmark
# and noise-study files (theirs); the others read a PNG's size, or patch plots.save around the real one
RENDERED = frozenset(
    {
        "test_verdict.py",
        "test_gap_benchmark.py",
        "test_transfer_benchmark.py",
        "test_noise_study.py",
        "test_cli.py",
        "test_dynamics_cli.py",
        "test_detection_figures_pool.py",
        "test_figure_legends.py",
        "test_hardening.py",  # a full disk: the runs' real PNGs fill it
        "test_your_gearbox.py",  # the guides end to end, as a user runs them
        "test_user_gearbox_e2e.py",
        "test_outside_dk.py",  # the score trend's PNG size
    }
)


@pytest.fixture
def synchronous_only(monkeypatch) -> None:
    """`gearlab inspect --history` without its non-synchronous (bearing-like) reading, said not read: for a
    test that asserts only the synchronous localisation (which shaft, gear, tooth); the call then follows
    the localisation alone, as inspect_history.call_of makes it."""
    monkeypatch.setattr("gearlab.inspect_history.nonsync_lines", nonsync_not_read)


def nonsync_not_read(*args) -> dict:
    """inspect_history.nonsync_lines's answer where it does not read the lines (synchronous_only)."""
    return {"note": "not read: left out (test)"}


@pytest.fixture(scope="module")
def trained_once():
    """The module's trainings of inputs this process already trained on given back, not run again
    (trained_once.trainings_remembered): for the files that train the same network on the same rows
    test after test, not those that test training itself."""
    from trained_once import trainings_remembered

    with trainings_remembered():
        yield


@pytest.fixture
def handed(monkeypatch) -> list:
    """The target rows every training of a detection test is handed (detection_scenario.training_spy)."""
    from detection_scenario import training_spy

    return training_spy(monkeypatch)
