"""Where units of work run: in this process, in a local process pool (default: all cores), or
on a Ray cluster.

An executor maps a picklable top-level function over a list of items and returns the
results in input order, reporting each finished item to an optional callback, so the
results never depend on the order in which workers finish. An exception raised by the
function reaches the caller as itself (a GearlabInputError stays a GearlabInputError).
Its ``counts()`` carry what units count while they run (a gap fit's score evaluations) back
from wherever they run, to say on a progress line: files on this machine, an actor on Ray. So
does ``unit_lines()`` with the units' own progress lines (gearlab.events.UnitProgress): on this
machine they are files in the run directory's progress/ folder, which the engine watches; Ray's
tasks report them to an actor of the session (a cluster's nodes share no disk with the driver).

A value many units of one map take (Shared) is written once to a file of the local pool's, which
its workers map read-only, instead of travelling in every unit's pickle.

Ray is optional: it is imported only when the `ray` executor is asked for.
"""

from __future__ import annotations

import atexit
import contextlib
import io
import logging
import math
import mmap
import multiprocessing
import os
import pickle
import shutil
import sys
import tempfile
import threading
import uuid
import warnings
import weakref
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from multiprocessing.reduction import ForkingPickler
from pathlib import Path

from . import PHYSICS_VERSION, __version__
from .confined import Confined
from .errors import GearlabInputError
from .events import Board, units_report_to
from .files import atomic_write
from .memo import keep_freed_heap

EXECUTORS = ("local", "ray")

OnDone = Callable[[int, object], None]


@contextlib.contextmanager
def one_thread() -> Iterator[None]:
    """torch on one thread within, the caller's count restored after: a unit's result does not depend on how many
    units run side by side (a detector's float32 sums add up in one order, so `gearlab score` of a run's own take
    gives the run's scores bit for bit; on torch's threads likelihood_ratio's revolution units came out up to 4e-6
    off), and an in-process run (the TUI, a notebook, gearlab.api) leaves its caller's torch as it found it."""
    import torch  # here: the executors serve kinds that never load torch

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(threads)


def _check_workers(workers: int | None) -> None:
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise GearlabInputError(f"workers must be a whole number >= 1, got {workers!r}")


def _check_gpu(gpu: bool | float) -> None:
    if not (isinstance(gpu, bool) or (isinstance(gpu, (int, float)) and 0 <= gpu <= 1)):
        raise GearlabInputError(f"gpu must be True, False or a GPU share between 0 and 1, got {gpu!r}")


def _gpu_request(gpu: bool | float, resources: dict) -> float:
    """The GPUs a task asks a Ray cluster for: none where the cluster has none (the task then
    trains on a CPU). gpu=True splits the cluster's GPUs evenly over its CPUs, as each task
    takes one CPU: the small networks here do not fill a GPU, and a whole GPU per task would
    leave all but one CPU per GPU idle. A number asks for that share of one GPU."""
    gpus = resources.get("GPU", 0)
    if not gpu or not gpus:
        return 0.0
    if gpu is not True:
        return float(gpu)
    share = min(1.0, gpus / max(1.0, resources.get("CPU", 1.0)))
    return max(0.0001, math.floor(share * 1e4) / 1e4)  # Ray takes GPU shares to 4 decimals


class Counts:
    """What units count while they run, summed where the map was asked for: each unit reports its
    own count under a key of its own (the latest report replaces its previous one), from whichever
    worker runs it; ``total()`` is the sum so far. Picklable: it travels to the workers with the
    units. A progress line's count of what no unit's end tells (a gap fit's score evaluations,
    gearlab.gap.tally), reported at most a few times a second; a result's count comes back as
    part of the result."""

    def report(self, key: str, n: int) -> None:
        raise NotImplementedError

    def total(self) -> int:
        raise NotImplementedError


class FileCounts(Counts):
    """One small file per key in *folder*, a folder of this machine: this process and the local
    pool's workers write there, and the sum is read off the files."""

    def __init__(self, folder: str):
        self.folder = folder

    def report(self, key: str, n: int) -> None:
        atomic_write(Path(self.folder) / f"{key}.n", str(n))  # written whole: never half a number read

    def total(self) -> int:
        total = 0
        for file in Path(self.folder).glob("*.n"):
            try:
                total += int(file.read_text())
            except (OSError, ValueError):  # a file replaced while read: counted at the next look
                pass
        return total


@contextlib.contextmanager
def file_counts() -> Iterator[FileCounts]:
    """Counts in a temporary folder of this machine's, removed at the end."""
    with tempfile.TemporaryDirectory(prefix="gearlab-counts-") as folder:
        yield FileCounts(folder)


def counts_of(executor) -> contextlib.AbstractContextManager[Counts]:
    """*executor*'s counts (Executor.counts); an executor with a ``map`` alone (a test's stand-in,
    mapping in this process) gets this machine's files."""
    return executor.counts() if isinstance(executor, Executor) else file_counts()


class Executor:
    """What every executor has: ``map`` (below, per executor), ``counts``, ``unit_lines`` and
    ``close``, also as a ``with`` block."""

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Release what the executor holds between maps (nothing by default)."""

    def counts(self) -> contextlib.AbstractContextManager[Counts]:
        """A Counts for the units of the maps inside the ``with`` block: by default files in a
        temporary folder, which this process and workers on this machine reach."""
        return file_counts()

    def warm(self, modules: Sequence[str]) -> None:
        """Have the workers import *modules* now, not waited for (nothing by default)."""

    def unit_lines(self, space: str) -> UnitLines | None:
        """The progress lines of the units in progress of the run whose directory is *space*, where
        they do not come through its progress/ folder: None here (this machine's workers write the
        folder, and the engine watches it)."""
        return None


class UnitLines:
    """The lines of a run's units in progress, as the driver reads them ({unit: line}; a unit gone
    has ended); ``close`` forgets the run's lines once it ended."""

    def __call__(self, final: bool = False) -> dict[str, str]:
        raise NotImplementedError

    def close(self) -> None:
        pass


class Shared:
    """A value that many units of a map take (detection: a condition's training arrays and the units
    every training scores), put in the items as ``Shared(value)``, the same object in each. A local
    pool's workers read it from a file the executor writes once, memory-mapped, where it travelled
    in every unit's pickle before (phm09_chip: 3.45 GB through the pool's pipes for 112 units, ~16 s
    of CPU). In this process and on Ray it travels as itself. A unit takes ``unshared(x)``."""

    def __init__(self, value):
        self.value = value


def unshared(x):
    """*x*'s value when it is Shared, else *x*."""
    return x.value if isinstance(x, Shared) else x


_ALIGN = 64  # bytes: each array of a shared file starts at a multiple (numpy's and the CPU's alignment)


def _write_shared(folder: str, name: str, value) -> tuple:
    """*value* pickled into *folder*/*name* with its arrays' bytes out of band, each aligned, after
    the pickle: (folder, name, pickle length, [(offset, length) of each array's bytes])."""
    buffers: list[pickle.PickleBuffer] = []
    head = pickle.dumps(value, protocol=5, buffer_callback=buffers.append)
    spans, end = [], len(head)
    for buffer in buffers:
        start = -(-end // _ALIGN) * _ALIGN
        spans.append((start, buffer.raw().nbytes))
        end = start + spans[-1][1]
    fd = Confined(Path(folder), (name,)).open_own(os.O_WRONLY | os.O_CREAT | os.O_EXCL)
    with os.fdopen(fd, "wb") as f:
        f.write(head)
        for buffer, (start, _) in zip(buffers, spans):
            f.seek(start)
            f.write(buffer.raw())
    return folder, name, len(head), spans


def _read_shared(pid: tuple) -> Shared:
    """A Shared value from its file, mapped copy-on-write: its arrays are the unit's own to change,
    as a pickled copy's were, and the pages it does not change are the file's, shared by the workers."""
    folder, name, head, spans = pid
    fd = Confined(Path(folder), (name,)).open_own(os.O_RDONLY)
    try:
        view = memoryview(mmap.mmap(fd, 0, access=mmap.ACCESS_COPY))
    finally:
        os.close(fd)
    return Shared(pickle.loads(view[:head], buffers=[view[start : start + n] for start, n in spans]))


class _Packer(ForkingPickler):
    """An item pickled as the pool would pickle it, each Shared value as the name of its file."""

    def __init__(self, file, executor: LocalExecutor):
        super().__init__(file, pickle.HIGHEST_PROTOCOL)
        self.executor = executor

    def persistent_id(self, obj):
        return self.executor._shared_file(obj) if type(obj) is Shared else None


class _Unpacker(pickle.Unpickler):
    """An item unpickled in a worker, each of its Shared values read from its file once."""

    def __init__(self, file):
        super().__init__(file)
        self.read: dict[tuple, Shared] = {}

    def persistent_load(self, pid):
        key = tuple(pid[:2])
        if key not in self.read:
            self.read[key] = _read_shared(pid)
        return self.read[key]


def warning_line(message, category, filename, lineno, file=None, line=None) -> None:
    """A worker's warnings as the command line's (gearlab.cli's _warning_line): one line on stderr,
    without Python's category, file and source-line echo (in the worker for what no unit raised, in
    the parent for the units' own, each message once)."""
    sys.stderr.write(f"warning: {message}\n")


_raised: list[str] | None = None  # in a worker: the warnings' messages of the unit it runs (None: none runs)


def _worker_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """A worker's showwarning: a unit's warning kept for the parent, which shows each message once a run
    (shown here, each worker showed it: the simulator's step warning at a record's rate once per worker);
    any other shown here (warning_line). The filters stay the worker's own: a module a unit imports keeps
    the ones it sets (a catch_warnings per unit would undo them)."""
    if _raised is None:
        warning_line(message, category, filename, lineno)
    else:
        _raised.append(str(message))


def _worker_started() -> None:
    warnings.showwarning = _worker_warning
    keep_freed_heap()


def _imported(modules: tuple[str, ...]) -> None:
    import importlib

    for module in modules:
        importlib.import_module(module)


def _warnings_kept(unit: Callable[[], object]) -> tuple[object, list[str]]:
    """A worker's unit run: (its result, the messages of the warnings it raised, each once), the parent
    shows them (_show_once); a unit that fails shows its own here, before its error reaches the parent."""
    global _raised
    _raised = []
    try:
        result = unit()
    except BaseException:
        for message in dict.fromkeys(_raised):
            warning_line(message, None, None, None)
        raise
    finally:
        raised, _raised = _raised, None
    return result, list(dict.fromkeys(raised))


def _show_once(raised: list[str], shown: set[str]) -> None:
    """The messages of a unit's warnings not *shown* yet this run (one executor a run), each as one line."""
    for message in raised:
        if message not in shown:
            shown.add(message)
            warning_line(message, None, None, None)


def _unpacked(fn: Callable, item: bytes) -> tuple[object, list[str]]:
    """A worker's call: the item unpickled, its Shared values read from their files (_warnings_kept)."""
    return _warnings_kept(lambda: fn(_Unpacker(io.BytesIO(item)).load()))


# The forkserver is one per process, started with the first pool's first worker and kept: the modules
# it imports are those of a warm before then (a run that trains: torch once, not 2-3 s of CPU in each
# worker; a run that never trains loads no torch). A later run in the process (the TUI, a test session)
# finds it as the first left it; its warm's tasks load what it lacks in each worker.
_server = {"started": False}


class LocalExecutor(Executor):
    """A process pool on this machine (default: one worker per core).

    The pool is started on the first map that needs it and kept for the next ones: a worker
    pays its start-up (imports, numba's compiled loops, per-process caches such as the gap
    search's clean revolutions) once per run, not once per map. `close()` — or leaving a
    `with` block — stops it; a failed unit or Ctrl-C stops it at once. The Shared values of its
    maps are files of a temporary folder of its own, written at their first map and kept for
    the next ones until `close()`.
    """

    def __init__(self, workers: int | None = None):
        _check_workers(workers)
        self.workers = workers or os.cpu_count() or 1
        self._pool: ProcessPoolExecutor | None = None
        self._folder: str | None = None  # the Shared values' files
        self._files: dict[int, tuple[Shared, tuple]] = {}  # id -> (the value, kept alive; its file)
        self._warned: set[str] = set()  # the workers' warnings shown so far (one executor a run)
        self._modules: tuple[str, ...] = ()  # what warm() asked each worker to load before its first unit

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown()
            self._pool = None
        self._forget_shared()

    def _forget_shared(self) -> None:
        if self._folder is not None:
            shutil.rmtree(self._folder, ignore_errors=True)
        self._folder, self._files = None, {}

    def _shared_file(self, shared: Shared) -> tuple:
        """Where *shared*'s value lies, written at its first use."""
        known = self._files.get(id(shared))
        if known is None:
            if self._folder is None:
                self._folder = tempfile.mkdtemp(prefix="gearlab-shared-")
                weakref.finalize(self, shutil.rmtree, self._folder, True)  # an executor dropped without close()
            known = self._files[id(shared)] = (shared, _write_shared(self._folder, f"{len(self._files)}", shared.value))
        return known[1]

    def _packed(self, item) -> bytes:
        out = io.BytesIO()
        _Packer(out, self).dump(item)
        return out.getvalue()

    def _stop(self) -> None:
        """Stop the pool without waiting for its queued or running units."""
        # (Python 3.11 has no public way to stop running workers; 3.14 adds terminate_workers.)
        running = list((getattr(self._pool, "_processes", None) or {}).values())
        self._pool.shutdown(wait=False, cancel_futures=True)
        for process in running:
            process.terminate()
        self._pool = None
        self._forget_shared()

    def _start(self) -> None:
        if self._pool is None:
            # forkserver: each worker is forked from a server process that ran nothing but imports (those of
            # the first warm, _server): no torch thread pool to inherit (torch starts it at its first op), nor
            # half of a BLAS one (numpy's OpenBLAS starts one at import and stops it before each fork), so a
            # worker starts as a fresh process would. Workers are started as units are submitted, never more
            # than there are units.
            _server["started"] = True
            context = multiprocessing.get_context("forkserver" if os.name == "posix" else "spawn")
            self._pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=context, initializer=_worker_started)
            weakref.finalize(self, self._pool.shutdown)  # an executor dropped without close()
            if self._modules:  # queued before any unit: a worker loads them first (at once where forked with them)
                for _ in range(self.workers):
                    self._pool.submit(_imported, self._modules)

    def warm(self, modules: Sequence[str]) -> None:
        """Each worker loads *modules* before its first unit (a run's start: gearlab.kinds.common.executor_for;
        detection: torch and scipy.stats, 2.7 s of CPU a worker). Before the process's first pool the
        forkserver imports them itself, once, and each worker is forked with them loaded (_server); after it,
        one task per worker imports them, queued ahead of the units (at once where the pool runs). Starts no
        pool: a run that maps nothing on it (a gap run of one candidate) loads nothing. Nothing with one worker."""
        if self.workers > 1:
            if os.name == "posix" and not _server["started"]:
                multiprocessing.get_context("forkserver").set_forkserver_preload(["__main__", *modules])
            self._modules = tuple(modules)
            if self._pool is not None:
                for _ in range(self.workers):
                    self._pool.submit(_imported, self._modules)

    def map(self, fn: Callable, items: Sequence, on_done: OnDone | None = None, gpu: bool | float = False) -> list:
        """`gpu` is accepted for the executors' common interface and ignored: a local unit
        trains on the scenario's device itself."""
        _check_gpu(gpu)  # still checked, so that a bad value fails alike on every executor
        items = list(items)
        results: list = [None] * len(items)
        if self.workers == 1 or len(items) <= 1:
            for i, item in enumerate(items):
                results[i] = fn(item)
                if on_done:
                    on_done(i, results[i])
            return results
        self._start()
        try:
            # each item pickled here, its Shared values written once (before the first unit that takes them)
            futures = {self._pool.submit(_unpacked, fn, self._packed(item)): i for i, item in enumerate(items)}
            for future in as_completed(futures):
                i = futures[future]
                results[i], raised = future.result()
                _show_once(raised, self._warned)
                if on_done:
                    on_done(i, results[i])
        except BaseException:
            self._stop()  # Ctrl-C, or a unit failed: stop now instead of waiting for every queued unit
            raise
        return results


class Aside(threading.Thread):
    """Steps of this process that no unit waits for, run in order in a thread of their own while the
    pool's units run (detection: the classical indicators, the sources' bounds, the localisation,
    22 s of the main process's CPU that stood before and after phm09_chip's trainings with one core
    idle). With one BLAS thread, set here in the caller's thread before any step starts (not while
    another thread is inside a BLAS call) until ``close()``: a worker is busy on each core, and
    OpenBLAS's second thread spins (phm09_chip's classical indicators took 15 s of CPU with two,
    5.7 with one; the same numbers). ``ready(name)``: the step has ended; ``get(name)``: its value,
    waited for (its error raised)."""

    def __init__(self, steps: dict[str, Callable]):
        from threadpoolctl import threadpool_limits  # (start-up time)

        super().__init__(daemon=True, name="gearlab-aside")  # a cancelled run does not wait for it
        self.steps, self.values, self.error = steps, {}, None
        self.ended = {name: threading.Event() for name in steps}
        self.blas = threadpool_limits(1, user_api="blas")
        self.start()

    def run(self) -> None:
        try:
            for name, step in self.steps.items():
                self.values[name] = step()
                self.ended[name].set()
        except BaseException as exc:  # raised where its value is asked for
            self.error = exc
        finally:
            for ended in self.ended.values():
                ended.set()

    def ready(self, name: str) -> bool:
        return self.ended[name].is_set()

    def get(self, name: str):
        self.ended[name].wait()
        if name not in self.values:
            raise self.error
        return self.values[name]

    def close(self) -> None:
        """Every step ended: the BLAS threads of before (a run that fails keeps one: no step may be
        inside a BLAS call when they change)."""
        self.join()
        self.blas.restore_original_limits()


# ----------------------------------------------------------------------------- Ray

RAY_MISSING = "executor 'ray' needs the optional extra: pip install 'gearlab[ray]'"

# One Ray session per process: the address it was opened with (None until opened) and
# whether this module started it (then it also shuts it down at exit).
_session: dict = {"address": None, "started": False, "board": None}


def import_ray():
    try:
        import ray
    except ImportError:
        raise GearlabInputError(RAY_MISSING) from None
    return ray


def ray_address(explicit: str | None = None, scenario: str | None = None) -> str | None:
    """Where the Ray cluster is: the explicit address (CLI --ray-address), else RAY_ADDRESS,
    else the scenario's [execution] address; None means: start a local Ray instance."""
    return explicit or os.environ.get("RAY_ADDRESS") or scenario or None


def _open_session(address: str | None, workers: int | None):
    """Connect to the cluster at `address`, or start a local instance; once per process."""
    ray = import_ray()
    wanted = address or "local"
    if ray.is_initialized():
        if _session["address"] is None:
            return ray  # someone (a user's script, a notebook) opened it before us: use theirs
        if _session["address"] != wanted:
            raise GearlabInputError(
                f"this process already uses the Ray cluster '{_session['address']}'; "
                f"it cannot also connect to '{wanted}'"
            )
        return ray
    quiet = {"logging_level": logging.ERROR, "log_to_driver": False, "include_dashboard": False}
    if address is None:
        # "local" always starts a fresh instance here rather than joining one found on this machine
        ray.init(address="local", num_cpus=workers or os.cpu_count() or 1, **quiet)
    else:
        try:
            ray.init(address=address, **quiet)
        except (ConnectionError, ValueError) as exc:
            raise GearlabInputError(f"cannot connect to the Ray cluster at '{address}': {exc}") from None
    _session.update(address=wanted, started=True)
    atexit.register(_close_session)
    if address is not None:
        try:
            _check_cluster_runs_our_gearlab(ray, address)
        except GearlabInputError:
            _close_session()  # so that a corrected address can be tried in this process
            raise
    return ray


def _close_session() -> None:
    if _session["started"]:
        import ray

        ray.shutdown()
        _session.update(address=None, started=False, board=None)


def _board(ray):
    """The session's board of unit lines (a _Lines actor, no CPU of its own), started on first use;
    one for every executor of the session, so that the engine's reader and the kind's tasks meet.
    Kept with the session's job: a session someone else opened, closed and opened again gets its own."""
    job = ray.get_runtime_context().get_job_id()
    if _session["board"] is None or _session["board"][0] != job:
        _session["board"] = (job, ray.remote(num_cpus=0)(_Lines).remote())
    return _session["board"][1]


def _gearlab_version() -> str:
    return f"{__version__} (physics {PHYSICS_VERSION})"


def _check_cluster_runs_our_gearlab(ray, address: str) -> None:
    """A cluster's workers import gearlab from their own environment: refuse one that has none,
    or another version, before any work is sent (one short task)."""
    ours = _gearlab_version()
    try:
        theirs = ray.get(ray.remote(num_cpus=0)(_gearlab_version).remote())
    except ray.exceptions.RayError as exc:  # e.g. a worker's ModuleNotFoundError: no gearlab there
        raise GearlabInputError(
            f"the Ray cluster at '{address}' cannot run gearlab: {exc}; install gearlab "
            f"{ours} on its nodes, or submit the run as a Ray job whose runtime_env "
            "installs it (docs/scenarios.md)"
        ) from None
    if theirs != ours:
        raise GearlabInputError(f"the Ray cluster at '{address}' runs gearlab {theirs}, this driver {ours}")


class RayExecutor(Executor):
    """Each item is one Ray task (one CPU; with gpu=..., also a GPU share when the cluster has
    GPUs). `workers` sizes a local instance this executor starts; a cluster's own resources
    decide how many tasks run there at once. The Ray session stays open for the process (the
    next run in it reuses the workers) and is closed at exit."""

    def __init__(self, address: str | None = None, workers: int | None = None):
        _check_workers(workers)
        import_ray()  # fail now, before any work, when Ray is not installed
        self.address = None if address in (None, "", "local") else address
        self.workers = workers
        self._counter = None  # the actor behind counts(), started on the first
        self._warned: set[str] = set()  # the tasks' warnings shown so far (one executor a run)

    def open(self) -> None:
        """Start the local Ray instance, or connect to the cluster, now (else at the first map)."""
        _open_session(self.address, self.workers)

    def close(self) -> None:
        ray = import_ray()
        if self._counter is not None and ray.is_initialized():  # (a session shut down took it along)
            ray.kill(self._counter)
        self._counter = None

    def unit_lines(self, space: str) -> UnitLines:
        """The lines the session's tasks report to its board (RayBoard) for the run at *space*."""
        return RayLines(_board(_open_session(self.address, self.workers)), space)

    @contextlib.contextmanager
    def counts(self) -> Iterator[Counts]:
        """Counts held by an actor of the Ray session (one per executor, no CPU of its own): a task
        on any node of a cluster reports to it, where a file it wrote would stay on its node's disk."""
        ray = _open_session(self.address, self.workers)
        if self._counter is None:
            self._counter = ray.remote(num_cpus=0)(_Counter).remote()
        space = uuid.uuid4().hex
        try:
            yield RayCounts(self._counter, space)
        finally:
            self._counter.drop.remote(space)

    def map(self, fn: Callable, items: Sequence, on_done: OnDone | None = None, gpu: bool | float = False) -> list:
        _check_gpu(gpu)
        items = list(items)
        if not items:
            return []
        ray = _open_session(self.address, self.workers)
        task = ray.remote(_call).options(num_cpus=1, num_gpus=_gpu_request(gpu, ray.cluster_resources()))
        board = _board(ray)  # the units' progress lines: a node's files would stay on its disk
        refs = [task.remote(fn, item, board) for item in items]
        index = {ref: i for i, ref in enumerate(refs)}
        results: list = [None] * len(items)
        pending = list(refs)
        try:
            while pending:
                done, pending = ray.wait(pending, num_returns=1)
                for ref in done:
                    i = index[ref]
                    results[i], raised = _get(ray, ref)
                    _show_once(raised, self._warned)
                    if on_done:
                        on_done(i, results[i])
        finally:
            # an error, a cancelled run (KeyboardInterrupt), or a failing callback: the rest is not wanted
            for ref in pending:
                ray.cancel(ref)
        return results


class _Counter:
    """The Ray actor behind RayCounts: each counts space's latest count per key."""

    def __init__(self):
        self.spaces: dict[str, dict[str, int]] = {}

    def report(self, space: str, key: str, n: int) -> None:
        self.spaces.setdefault(space, {})[key] = n

    def total(self, space: str) -> int:
        return sum(self.spaces.get(space, {}).values())

    def drop(self, space: str) -> None:
        self.spaces.pop(space, None)


ANSWER_S = 0.2  # s a RayCounts.total() waits for the actor's answer


def _answer(reader, method, timeout: float, afresh: bool = False):
    """A driver-side reader's (RayCounts, RayLines) answer from its actor's `method` for its space,
    waited for `timeout` s at most: else the previous answer, and the question stays asked (asked
    again when `afresh`). An actor gone with its session leaves the last answer standing."""
    ray = import_ray()
    if reader._asked is None or afresh:
        reader._asked = method.remote(reader.space)
    if ray.wait([reader._asked], timeout=timeout)[0]:
        try:
            reader._known = ray.get(reader._asked)
        except ray.exceptions.RayError:
            pass
        reader._asked = None
    return reader._known


class RayCounts(Counts):
    """Counts of one ``counts()`` block, reported to a _Counter actor (not waited for)."""

    def __init__(self, actor, space: str):
        self.actor, self.space = actor, space
        self._asked, self._known = None, 0

    def __reduce__(self):
        return (RayCounts, (self.actor, self.space))  # a worker reports: no question of the driver's travels

    def report(self, key: str, n: int) -> None:
        self.actor.report.remote(self.space, key, n)

    def total(self) -> int:
        """The actor's answer, waited for ANSWER_S at most (a progress line asks each second, and the
        actor may still be starting): else the previous answer, and the question stays asked."""
        return _answer(self, self.actor.total, ANSWER_S)


class _Lines:
    """The Ray actor behind RayBoard and RayLines: each run's (space's) latest line per unit."""

    def __init__(self):
        self.spaces: dict[str, dict[str, str]] = {}

    def say(self, space: str, unit: str, text: str) -> None:
        self.spaces.setdefault(space, {})[unit] = text

    def end(self, space: str, unit: str) -> None:
        self.spaces.get(space, {}).pop(unit, None)

    def lines(self, space: str) -> dict[str, str]:
        return dict(self.spaces.get(space, {}))

    def drop(self, space: str) -> None:
        self.spaces.pop(space, None)


ENDED_S = 5.0  # s a unit's end waits for the board to hold it (a round trip: milliseconds)


class RayBoard(Board):
    """A Ray task's units report their lines to the session's _Lines actor (not waited for, but
    in order: one caller's calls to an actor run in the order made); a unit's end is waited for."""

    def __init__(self, actor):
        self.actor = actor

    def say(self, space: str, unit: str, text: str) -> None:
        self.actor.say.remote(space, unit, text)

    def end(self, space: str, unit: str) -> None:
        ray = import_ray()
        ray.wait([self.actor.end.remote(space, unit)], timeout=ENDED_S)


class RayLines(UnitLines):
    """The driver's reader of one run's lines on the board: the actor's answer, waited for
    ANSWER_S at most (the watcher asks twice a second), else the previous answer while the
    question stays asked; the final look asks afresh (a question asked before the last units ended
    would still show them) and waits for the answer (ENDED_S)."""

    def __init__(self, actor, space: str):
        self.actor, self.space = actor, space
        self._asked, self._known = None, {}

    def __call__(self, final: bool = False) -> dict[str, str]:
        return _answer(self, self.actor.lines, ENDED_S if final else ANSWER_S, afresh=final)

    def close(self) -> None:
        ray = import_ray()
        if ray.is_initialized() and (_session["board"] or (None, None))[1] is self.actor:  # else gone with it
            self.actor.drop.remote(self.space)


def _call(fn: Callable, item, board=None) -> tuple[object, list[str]]:
    """The Ray task: `fn` travels as an argument, so any picklable callable works (ray.remote
    itself takes only Python functions), as with the local process pool. Its units report their
    progress lines to *board* (the session's _Lines actor), not to files. Its warnings come back
    with its result, as a pool worker's do (_warnings_kept): the session keeps the workers' output
    from the driver (log_to_driver), and a warning each worker raised would show once per worker."""
    if warnings.showwarning is not _worker_warning:  # a Ray worker serves many tasks: set once a process
        _worker_started()
    with units_report_to(None if board is None else RayBoard(board)):
        return _warnings_kept(lambda: fn(item))


def _get(ray, ref):
    """The task's result, or its exception as the task raised it (not wrapped in a RayTaskError),
    so the caller's error handling (GearlabInputError -> exit 2) works as with local workers."""
    try:
        return ray.get(ref)
    except ray.exceptions.RayTaskError as exc:
        cause = exc.cause
        if isinstance(cause, Exception) and not isinstance(cause, ray.exceptions.RayError):
            cause.add_note(f"raised in a Ray task: {exc}")  # str() holds the worker and its traceback
            raise cause from None
        raise


def make_executor(
    name: str = "local", workers: int | None = None, address: str | None = None, scenario_address: str | None = None
):
    """The executor called `name`. For `ray`, the cluster address is `address` (CLI --ray-address),
    else RAY_ADDRESS, else `scenario_address` ([execution] address), else a local instance."""
    if name == "local":
        return LocalExecutor(workers)
    if name == "ray":
        return RayExecutor(ray_address(address, scenario_address), workers)
    raise GearlabInputError(f"unknown executor '{name}'; known: {', '.join(EXECUTORS)}")
