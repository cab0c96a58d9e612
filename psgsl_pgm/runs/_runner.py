"""One resumable grid runner: jobs → one result file each, on a local pool or a dask.distributed cluster.

Used by ``psgsl experiment`` (:func:`psgsl_pgm.experiment.run_experiment`) and ``psgsl search``. A *job* is a
pure, picklable task descriptor (:class:`GridJob`: the file its result goes to, a module-level function and its
arguments — world, config, source, seed, estimator/policy/variant); the result is returned to this process (the
*client*), which writes it atomically (:func:`atomic_write`) as it arrives. Hence:

* **resumable** — a job whose file exists is finished and never redone; ``check_done`` lets the caller refuse
  a stored result computed with another configuration;
* **nothing lost or written twice** — a file appears complete or not at all, and only the client writes it, once;
* **the same results everywhere** — the same function runs on the same arguments with one BLAS thread per worker
  process on every backend, so the local pool and a dask cluster give bit-identical results.

An output folder holds the runs of one configuration and one process at a time (:func:`grid_folder`): stored runs
whose run key (:mod:`psgsl_pgm.runs._key`) differs from the grid's are refused before anything is created, and
``OUT/.lock`` (``flock``, released by the operating system when the process ends, however it ends) refuses a
second process on the same folder. Temporary files left by a killed process are removed on the next start.

Backends (``scheduler``):

* ``None`` — a local pool of ``workers`` spawned processes (no extra install); ``workers=1`` runs in this process;
* ``"local"`` — a dask ``LocalCluster`` of ``workers`` single-threaded worker processes;
* ``"tcp://HOST:PORT"`` (any dask address) — a running ``dask scheduler`` with its workers, which must have the
  same psgsl-pgm installed. A run whose worker dies is retried on another worker (by dask; by a fresh pool
  locally, up to :data:`MAX_ATTEMPTS` times).

Ctrl-C (SIGINT, from the main thread): the first one stops submitting; queued runs are dropped and no worker
starts a new run (on dask a stop event is checked by every run before it starts); the runs in progress finish and
are written; then :class:`GridInterrupted` is raised. A second Ctrl-C stops at once: workers are killed (on a
remote cluster the unfinished runs are cancelled), runs in progress are lost, finished files are untouched.
The CLI turns :class:`GridInterrupted` into one line and exit code 130 (:func:`psgsl_pgm.cli._grid.interrupted`).

SIGTERM (``kill``, a batch system, ``timeout``; from the main thread) stops at once, as a second Ctrl-C does:
workers are killed, runs in progress are lost, finished files are untouched, and :class:`GridInterrupted` is
raised with ``signum = SIGTERM`` (the CLI's exit code is 143). Should the client die without cleaning up
(SIGKILL, or SIGTERM while a grid runs outside the main thread), its workers end by themselves: a local pool's
worker checks that the client is still its parent (:func:`_exit_with_parent`), a LocalCluster's worker is ended
by dask when its parent is gone.

Minimal use::

    from psgsl_pgm.runs._runner import GridJob, run_grid

    jobs = [GridJob(out / f"seed{s}.npz", run_one, (world, config, s)) for s in seeds]
    report = run_grid(jobs, write=write_result, scheduler=None, workers=2)   # write(result, binary_file)
"""

from __future__ import annotations

import contextvars
import logging
import os
import signal
import threading
import time
import uuid
from collections.abc import Callable, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["CONNECT_TIMEOUT", "GridInterrupted", "GridJob", "GridReport", "MAX_ATTEMPTS", "PARENT_POLL",
           "WORKER_ENVIRON", "atomic_write", "command_label", "grid_folder", "run_grid"]

#: A job is given up (RuntimeError) after its worker process died this many times (dask's default
#: ``distributed.scheduler.allowed-failures`` + 1 for the local pool; dask applies its own setting).
MAX_ATTEMPTS = 4

#: Environment of every worker process: one BLAS/OpenMP thread (the parallelism is over processes; this is also
#: what dask's nanny sets, which keeps the floating-point summation order — hence the results — identical).
WORKER_ENVIRON = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}

_POLL = 0.05  # s between checks of the running jobs (runs take seconds to minutes)

#: Seconds to wait for a dask scheduler at an address to answer.
CONNECT_TIMEOUT = 10.0


@dataclass(frozen=True, eq=False)
class GridJob:
    """One run of a grid: ``fn(*args, **kwargs)`` → a result written to ``path``.

    Attributes
    ----------
    path : pathlib.Path
        The result file. Its existence means "finished".
    fn : callable
        A module-level (picklable) function, pure in its arguments: the same arguments give the same result on
        any worker.
    args : tuple
    kwargs : mapping
        Picklable arguments (configs, seeds, names; not open files or live objects).
    """

    path: Path
    fn: Callable
    args: tuple = ()
    kwargs: Mapping = field(default_factory=dict)

    def __post_init__(self):
        object.__setattr__(self, "path", Path(self.path))
        if not callable(self.fn):
            raise TypeError(f"fn must be callable, got {type(self.fn).__name__}")
        object.__setattr__(self, "args", tuple(self.args))
        object.__setattr__(self, "kwargs", dict(self.kwargs))


@dataclass(frozen=True)
class GridReport:
    """What :func:`run_grid` did: ``total`` jobs, ``done_before`` found on disk, ``computed`` now."""

    total: int
    done_before: int
    computed: int

    @property
    def done(self) -> int:
        return self.done_before + self.computed


class GridInterrupted(KeyboardInterrupt):
    """Ctrl-C or SIGTERM stopped the grid; every finished run is on disk.

    Attributes
    ----------
    done, total : int
        Jobs whose result file exists now, and jobs in the grid.
    immediate : bool
        True after a second Ctrl-C or a SIGTERM (runs in progress were abandoned), False when they were let finish.
    signum : int
        The signal that stopped the grid: :data:`signal.SIGINT` (Ctrl-C) or :data:`signal.SIGTERM`.
    """

    def __init__(self, done: int, total: int, *, immediate: bool, signum: int = signal.SIGINT):
        what = "interrupted" if signum == signal.SIGINT else f"stopped by {signal.Signals(signum).name}"
        super().__init__(f"{what}: {done} of {total} runs done")
        self.done, self.total, self.immediate, self.signum = done, total, immediate, int(signum)


class _Abort(BaseException):
    """Raised in the main thread by the second Ctrl-C (``signum`` SIGINT) or by SIGTERM."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


class _Skipped:
    """Returned by a dask task that saw the stop event before starting its run."""


def atomic_write(path, write: Callable, result) -> Path:
    """Write ``write(result, fh)`` to ``path`` atomically: a temporary file in the same directory, fsync'ed,
    then ``os.replace``. An interruption at any point leaves either no file or the complete one."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex[:8]}.part")  # unique; created with the umask's mode
    try:
        with open(tmp, "xb") as fh:
            write(result, fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    return path


def _refuse_other_keys(out: Path, key: dict, read_key: Callable, pattern: str, option: str) -> None:
    """ValueError naming each differing setting when a run stored in ``out/runs`` has another key."""
    from ._key import digest, key_differences

    runs = out / "runs"
    if not runs.is_dir():
        return
    want = digest(key)
    files = sorted(runs.glob(pattern))
    for path in files:
        stored = read_key(path)
        if stored is None:
            raise ValueError(f"{option} {out}: {path.name} was stored without a run key (by an older psgsl-pgm), "
                             f"so its settings cannot be checked; use another {option}, or delete {runs} to "
                             "recompute the runs")
        if digest(stored) == want:
            continue
        diff = key_differences(stored, key) or ["(key format)"]
        raise ValueError(f"{option} {out} holds runs computed with other settings ({len(files)} stored; "
                         f"{path.name}: {'; '.join(diff)}); use another {option}, or delete {runs} to recompute "
                         "them")


def _lock(out: Path, option: str):
    """An exclusive ``flock`` on ``out/.lock`` (its file descriptor), or ValueError when another process holds it."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX: no lock
        return None
    fd = os.open(out / ".lock", os.O_RDWR | os.O_CREAT, 0o666)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        try:
            pid = os.read(fd, 32).decode("ascii", "replace").strip()
        except OSError:
            pid = ""
        os.close(fd)
        who = f" (pid {pid})" if pid.isdigit() else ""
        raise ValueError(f"{option} {out} is in use by another psgsl process{who}; wait for it to end, or use "
                         f"another {option}") from None
    os.ftruncate(fd, 0)
    os.write(fd, f"{os.getpid()}\n".encode("ascii"))
    return fd


def _remove_temporaries(out: Path) -> None:
    """Temporary files of writers killed mid-write (atomic_write's ``runs/.NAME.XXXX.part``, the summaries'
    ``NAME.part``, the writability probe): never part of a result, removed under the lock."""
    for pattern in ("runs/.*.part", "*.part", "*/*.part", ".psgsl-probe-*"):
        for path in out.glob(pattern):
            if path.is_file():
                try:
                    path.unlink()
                except FileNotFoundError:
                    pass


@contextmanager
def grid_folder(out, key: dict, *, read_key: Callable, pattern: str = "*.npz", option: str = "--out"):
    """Open the output folder of a grid for this process; yields ``Path(out)``.

    In this order: the folder is checked without creating anything (:func:`psgsl_pgm.io._output.check_output_dir`);
    every run stored in ``out/runs`` (files matching ``pattern``) must carry ``key`` — else ValueError naming
    each differing setting with both values, and nothing is created; then ``out/runs`` is created,
    ``out/.lock`` locked (another process holding it: ValueError, one line), the stored runs checked again
    (another process may have written before the lock was taken), and temporary files of killed writers removed.
    The lock is held until the ``with`` block ends; the operating system releases it when the process dies.

    Parameters
    ----------
    out : path
    key : dict
        The grid's run key (:func:`psgsl_pgm.runs._key.run_key`).
    read_key : callable, keyword-only
        ``read_key(path)`` -> the key stored in a run file (None: a file without one); ValueError for a file
        that is not a run file.
    pattern : str, keyword-only
        Run files in ``out/runs``.
    option : str, keyword-only
        The folder's option name in messages.
    """
    from ..io._output import check_output_dir, prepare_output_dir

    out = check_output_dir(out, option=option, subdirs=("runs",))
    _refuse_other_keys(out, key, read_key, pattern, option)
    prepare_output_dir(out, option=option, subdirs=("runs",))
    fd = _lock(out, option)
    try:
        _refuse_other_keys(out, key, read_key, pattern, option)
        _remove_temporaries(out)
        yield out
    finally:
        if fd is not None:
            os.close(fd)


def _call(fn, args, kwargs):
    return fn(*args, **kwargs)


def _dask_call(stop_event: str, fn, args, kwargs):
    """A dask task: check the grid's stop event (set by the first Ctrl-C), then run."""
    from distributed import Event

    if Event(stop_event).is_set():
        return _Skipped()
    return fn(*args, **kwargs)


def _ignore_sigint():
    """Worker processes ignore SIGINT: a terminal's Ctrl-C reaches the whole process group, and the client decides."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)


#: Seconds between a pool worker's checks that its client is alive (:func:`_exit_with_parent`).
PARENT_POLL = 0.5


def _exit_with_parent(client_pid: int, interval: float = PARENT_POLL) -> threading.Thread:
    """End this worker process (``os._exit``) as soon as its parent is no longer ``client_pid``.

    The client kills its workers on Ctrl-C, SIGTERM and errors; this covers the client dying without a word
    (SIGKILL, the OOM killer, a crash), after which the workers are re-parented and would compute on, then wait
    for work forever (:class:`concurrent.futures.ProcessPoolExecutor` has no parent-death check of its own: its
    workers block on the call queue, whose write end they hold themselves). Why a thread polling
    :func:`os.getppid`:

    * it stops the run in progress too (a run takes minutes), not only between runs;
    * a re-parented process's parent id changes on every POSIX system (to init or a subreaper), so no Linux-only
      ``prctl(PR_SET_PDEATHSIG)``, which would also fire when the client *thread* that spawned the pool exits;
    * ``client_pid`` is the client's pid passed in (not read here), so a client that died before the worker
      started is noticed too;
    * nothing is shared with the client: a pipe whose end-of-file tells the worker (what dask does for its
      LocalCluster workers) stays open as long as any process holds its write end, e.g. one forked from the
      client.

    Cost: one thread asleep but for a ``getppid`` call every ``interval`` seconds; results are unaffected. It
    needs the GIL to run, so a compiled call that holds the GIL delays the exit until it returns.
    """
    def watch():
        while os.getppid() == client_pid:
            time.sleep(interval)
        os._exit(1)

    thread = threading.Thread(target=watch, name="psgsl-parent-watch", daemon=True)
    thread.start()
    return thread


def _init_worker(client_pid: int):
    """Initializer of the local pool's workers: ignore SIGINT, end with the client (:func:`_exit_with_parent`)."""
    _ignore_sigint()
    _exit_with_parent(client_pid)


def dask_setup(worker=None):  # noqa: D401 - dask preload hook (LocalCluster workers load this module)
    """dask preload hook: the worker process ignores SIGINT (see :func:`_ignore_sigint`)."""
    _ignore_sigint()


@contextmanager
def _environ(extra: Mapping):
    old = {k: os.environ.get(k) for k in extra}
    os.environ.update(extra)
    try:
        yield
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


@contextmanager
def _ignored(*signums):
    """The signals ignored for the duration of the block (main thread only; elsewhere nothing changes)."""
    main = threading.current_thread() is threading.main_thread()
    old = {s: signal.signal(s, signal.SIG_IGN) for s in signums} if main else {}
    try:
        yield
    finally:
        for s, handler in old.items():
            signal.signal(s, handler)


def _sigint_ignored():
    """SIGINT ignored while worker processes are spawned (they inherit the disposition; Python keeps it). SIGTERM
    is left alone there: workers that ignored it could not be terminated."""
    return _ignored(signal.SIGINT)


def _signals_ignored():
    """SIGINT and SIGTERM ignored while the workers are being killed: a repeated signal cannot cut that short."""
    return _ignored(signal.SIGINT, signal.SIGTERM)


class _Interrupts:
    """Signal handlers for the duration of a grid, in the main thread: the first SIGINT → flag, the second →
    :class:`_Abort`; SIGTERM → :class:`_Abort` at once."""

    def __init__(self):
        self.count = 0
        self.installed = threading.current_thread() is threading.main_thread()
        self._old = {}
        self._holding = False  # inside held(): an abort waits until the block ends
        self._held = None  # the signal number of an abort that arrived inside held()

    def __enter__(self):
        if self.installed:
            self._old = {signal.SIGINT: signal.signal(signal.SIGINT, self._handle),
                         signal.SIGTERM: signal.signal(signal.SIGTERM, self._terminate)}
        return self

    def __exit__(self, *exc):
        for s, handler in self._old.items():
            signal.signal(s, handler)
        self._old = {}
        return False

    def _handle(self, signum, frame):
        self.count += 1
        if self.count >= 2:
            self._abort(signal.SIGINT)

    def _terminate(self, signum, frame):
        self._abort(signal.SIGTERM)

    def _abort(self, signum: int):
        if self._holding:
            self._held = self._held or signum
        else:
            raise _Abort(signum)

    @contextmanager
    def held(self):
        """Hold an abort (second Ctrl-C, SIGTERM) until the block ends, then raise it: a finished run is written
        *and* counted, or neither, so the count a :class:`GridInterrupted` reports is the files on disk."""
        self._holding = True
        try:
            yield
        finally:
            self._holding = False
            if self._held is not None:
                signum, self._held = self._held, None
                raise _Abort(signum)

    @property
    def stop(self) -> bool:
        return self.count > 0


# ---------------------------------------------------------------------------------------------------- backends


class _InProcess:
    """``workers=1`` without a scheduler: run each job here (first Ctrl-C lets the current run finish), with BLAS
    and OpenMP held to one thread as in a worker (:data:`WORKER_ENVIRON`): a threaded BLAS splits its sums
    differently, so a run would not be the one a worker computes, and its two threads spinning on sums of ~10⁴
    numbers cost several times the CPU. The limit needs threadpoolctl (the ``sim`` extra; this process's BLAS is
    loaded already, so environment variables come too late): without it the jobs run on the process's BLAS threads
    as they are, and a run may differ in its last bits from a worker's.
    """

    def __init__(self):
        try:
            from threadpoolctl import threadpool_limits
        except ImportError:
            self._limits = None
        else:
            self._limits = threadpool_limits

    def slots(self):
        return 1

    def submit(self, job):
        return job

    def poll(self, handles):
        return list(handles)  # "done" when asked: the run happens in result()

    def result(self, job):
        if self._limits is None:
            return job.fn(*job.args, **job.kwargs)
        with self._limits(limits=1):
            return job.fn(*job.args, **job.kwargs)

    def is_worker_death(self, exc) -> bool:
        return False

    def gate(self):
        pass

    def abort(self):
        pass

    def close(self):
        pass


class _Pool:
    """A spawn ProcessPoolExecutor; a dead worker breaks the pool, which is replaced and the job resubmitted."""

    def __init__(self, workers: int):
        self.workers = workers
        self.pool = None

    def _ensure(self):
        if self.pool is None:
            import multiprocessing as mp
            from concurrent.futures import ProcessPoolExecutor

            self.pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=mp.get_context("spawn"),
                                            initializer=_init_worker, initargs=(os.getpid(),))
        return self.pool

    def slots(self):
        return self.workers

    def submit(self, job):
        with _environ(WORKER_ENVIRON), _sigint_ignored():  # processes are spawned inside submit
            return self._ensure().submit(_call, job.fn, job.args, job.kwargs)

    def poll(self, handles):
        return [h for h in handles if h.done()]

    def result(self, handle):
        return handle.result()

    def is_worker_death(self, exc) -> bool:
        from concurrent.futures.process import BrokenProcessPool

        if isinstance(exc, BrokenProcessPool):
            self.abort()  # the broken pool is useless; the next submit makes a new one
            return True
        return False

    def gate(self):
        pass  # nothing is queued in the pool: at most one job per worker is submitted

    def abort(self):
        pool, self.pool = self.pool, None
        if pool is None:
            return
        for proc in list(getattr(pool, "_processes", {}).values()):
            try:
                proc.kill()
            except (OSError, ValueError, AttributeError):
                pass
        pool.shutdown(wait=False, cancel_futures=True)

    def close(self):
        pool, self.pool = self.pool, None
        if pool is not None:
            pool.shutdown(wait=True)


class _Dask:
    """A dask.distributed client (to a LocalCluster it owns, or to a running scheduler)."""

    def __init__(self, scheduler: str, workers: int):
        try:
            from distributed import Client, Event, LocalCluster
        except ImportError:
            raise ValueError(f"scheduler={scheduler!r} needs dask.distributed: pip install 'psgsl-pgm[dask]'") from None
        self.cluster = None
        if scheduler == "local":
            with _sigint_ignored():
                # no dashboard; the scheduler's HTTP server (health checks) on a free port of this host: its
                # default, 8787, may be taken (another cluster), which distributed reports on stderr
                self.cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                            dashboard_address=None, preload=[__name__],
                                            scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})
            self.client = Client(self.cluster)
        else:
            try:
                self.client = Client(scheduler, timeout=CONNECT_TIMEOUT)
            except (OSError, ValueError, TypeError) as exc:
                raise ValueError(f"scheduler: cannot connect to a dask scheduler at {scheduler!r} ({exc})") from None
        self.token = uuid.uuid4().hex[:12]
        self.event = Event(f"psgsl-stop-{self.token}", client=self.client)
        self._n = 0

    def slots(self):
        return max(1, sum(self.client.nthreads().values()))

    def submit(self, job):
        self._n += 1
        key = f"psgsl-{job.path.stem}-{self.token}-{self._n}"
        return self.client.submit(_dask_call, self.event.name, job.fn, job.args, job.kwargs, key=key, pure=False)

    def poll(self, handles):
        return [h for h in handles if h.done()]

    def result(self, handle):
        try:
            return handle.result()
        finally:
            handle.release()

    def is_worker_death(self, exc) -> bool:
        return False  # dask reschedules runs of dead workers itself (KilledWorker after allowed-failures)

    def gate(self):
        self.event.set()

    def abort(self):
        try:
            self.event.set()
        except Exception:  # noqa: BLE001 - best effort on the way out
            pass
        with _quiet_distributed():  # the nannies report the killed workers (and restart them) before the close
            if self.cluster is not None:  # our own workers: kill them now (their nannies are closed right after)
                for proc in _worker_processes(self.cluster):
                    if proc.pid:
                        try:
                            os.kill(proc.pid, signal.SIGKILL)
                        except OSError:
                            pass
            self.close(timeout=2)

    def close(self, timeout=10):
        """Close the client and our own cluster, quietly and within about ``timeout`` seconds each.

        distributed's shutdown chatter (a nanny's "Worker process still alive after 4.0 seconds, killing" on a
        loaded machine, "Event loop was unresponsive", a killed worker's restart notice) is held back: the CLI
        promises one line after Ctrl-C or SIGTERM (:func:`_quiet_distributed`). Worker processes of our
        cluster still alive after the close (it timed out) are killed: nothing of theirs is needed any more.
        """
        client, self.client = getattr(self, "client", None), None
        cluster, self.cluster = self.cluster, None
        procs = _worker_processes(cluster) if cluster is not None else []
        with _quiet_distributed():
            for obj in (client, cluster):
                if obj is not None:
                    try:
                        obj.close(timeout=timeout)
                    except Exception:  # noqa: BLE001 - closing a cluster whose workers were killed may complain
                        pass
            for proc in procs:
                if proc.exitcode is None and proc.pid:
                    try:
                        os.kill(proc.pid, signal.SIGKILL)
                    except OSError:
                        pass


def _worker_processes(cluster) -> list:
    """The worker processes (distributed's ``AsyncProcess``: ``pid``, ``exitcode``) of a LocalCluster's nannies."""
    procs = []
    for nanny in list(getattr(cluster, "workers", {}).values()):
        proc = getattr(getattr(nanny, "process", None), "process", None)
        if proc is not None:
            procs.append(proc)
    return procs


#: Loggers held back by :func:`_quiet_distributed` (distributed's loggers are all named ``distributed.*``).
_DISTRIBUTED_LOGGER = "distributed"


@contextmanager
def _quiet_distributed(level: int = logging.ERROR):
    """distributed's loggers in this process show only records of ``level`` and above for the duration of the block.

    The ``distributed`` logger and every ``distributed.*`` logger with a level of its own below ``level`` are
    raised to it (the others inherit it); every level is restored on exit. Used while a cluster is closed: its
    warnings then are shutdown chatter, not news for the user.
    """
    manager = logging.Logger.manager
    names = [_DISTRIBUTED_LOGGER] + [n for n, lg in list(manager.loggerDict.items())
                                     if n.startswith(_DISTRIBUTED_LOGGER + ".") and isinstance(lg, logging.Logger)]
    old = {}
    for name in names:
        logger = logging.getLogger(name)
        if name == _DISTRIBUTED_LOGGER or logger.level != logging.NOTSET:
            old[name] = logger.level
            if logger.level < level:
                logger.setLevel(level)
    try:
        yield
    finally:
        for name, lvl in old.items():
            logging.getLogger(name).setLevel(lvl)


def _backend(scheduler, workers, n_jobs):
    if scheduler is None:
        n = min(workers, n_jobs)
        return _Pool(n) if n > 1 else _InProcess()
    if not isinstance(scheduler, str) or not scheduler.strip():
        raise ValueError(f"scheduler must be 'local' or a dask scheduler address such as 'tcp://127.0.0.1:8786', "
                         f"got {scheduler!r}")
    return _Dask(scheduler.strip(), workers)


# ---------------------------------------------------------------------------------------------------- the loop


class _NoBar:
    """Stands in for tqdm's bar when no bar is shown, or tqdm (the sim extra) is not installed: the runner is core."""

    def update(self, n=1):
        pass

    def close(self):
        pass


#: The command whose grid this is (``"psgsl experiment"``), set by the CLI: the progress bar names it.
_COMMAND: contextvars.ContextVar = contextvars.ContextVar("psgsl_command", default=None)


@contextmanager
def command_label(command: str):
    """Label the progress bars of the grids run inside the block with ``command`` (``"psgsl search: ..."``)."""
    token = _COMMAND.set(command)
    try:
        yield
    finally:
        _COMMAND.reset(token)


def _progress_bar(total: int, desc: str, progress: bool, unit: str = "run"):
    if not progress:
        return _NoBar()
    try:
        from tqdm.auto import tqdm
    except ModuleNotFoundError:  # a core-only install: the grid runs, without a bar
        return _NoBar()
    command = _COMMAND.get()
    return tqdm(total=total, desc=desc if command is None else f"{command}: {desc}", unit=unit)


def run_grid(jobs: Sequence[GridJob], *, write: Callable, check_done: Callable | None = None,
             scheduler: str | None = None, workers: int = 2, progress: bool = False,
             desc: str = "runs") -> GridReport:
    """Run every job whose result file does not exist yet; write each result as it arrives.

    Parameters
    ----------
    jobs : sequence of GridJob
        Distinct result paths.
    write : callable, keyword-only
        ``write(result, fh)`` writes one result to a binary file object (made atomic by :func:`atomic_write`).
    check_done : callable, optional, keyword-only
        ``check_done(job)`` for each job already on disk; raise ValueError to refuse it (e.g. it was computed
        with another configuration). Called before anything runs.
    scheduler : None, "local" or str, keyword-only
        Backend (module docstring): None = local process pool, "local" = dask LocalCluster, else the address of
        a running dask scheduler.
    workers : int, keyword-only
        Processes of the local pool or the LocalCluster (ignored with a scheduler address).
    progress : bool, keyword-only
        tqdm progress bar on stderr.
    desc : str, keyword-only
        Label of the progress bar.

    Returns
    -------
    GridReport

    Raises
    ------
    GridInterrupted
        On Ctrl-C or SIGTERM (see the module docstring); finished runs are on disk.
    ValueError
        Duplicate paths, a refused stored result, a bad ``scheduler`` or ``workers``.
    RuntimeError
        A job whose worker died :data:`MAX_ATTEMPTS` times (local pool).
    Exception
        The first exception a run raised (after the other runs in progress were finished and written).
    """
    jobs = list(jobs)
    for j in jobs:
        if not isinstance(j, GridJob):
            raise TypeError(f"jobs must be GridJob instances, got {type(j).__name__}")
    if len({j.path.resolve() for j in jobs}) != len(jobs):
        raise ValueError("jobs must write distinct result paths; got duplicates")
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers must be a positive integer, got {workers!r}")
    done_before = [j for j in jobs if j.path.exists()]
    if check_done is not None:
        for j in done_before:
            check_done(j)
    pending = [j for j in jobs if not j.path.exists()]
    total, computed = len(jobs), 0
    if not pending:
        return GridReport(total, len(done_before), 0)

    bar = _progress_bar(len(pending), desc, progress)
    backend = None
    inflight: dict = {}  # handle -> job
    attempts: dict = {}
    error = None
    queue = list(reversed(pending))  # pop() from the end = submission order
    interrupts = _Interrupts()
    try:
        with interrupts:
            backend = _backend(scheduler, workers, len(pending))
            while queue or inflight:
                if interrupts.stop or error is not None:
                    if queue:
                        queue.clear()
                        backend.gate()
                else:
                    while queue and len(inflight) < backend.slots():
                        job = queue.pop()
                        inflight[backend.submit(job)] = job
                finished = backend.poll(list(inflight))
                if not finished:
                    time.sleep(_POLL)
                    continue
                for handle in finished:
                    if handle not in inflight:  # already requeued with the rest of a broken pool
                        continue
                    job = inflight.pop(handle)
                    try:
                        result = backend.result(handle)
                    except Exception as exc:  # noqa: BLE001 - sorted below
                        if not backend.is_worker_death(exc):
                            error = error or exc
                            continue
                        lost = [job] + [inflight.pop(h) for h in list(inflight)]  # the pool lost all its runs
                        for j in lost:
                            attempts[j.path] = attempts.get(j.path, 0) + 1
                            if attempts[j.path] >= MAX_ATTEMPTS:
                                error = error or RuntimeError(
                                    f"the worker process running {j.path.name} died {attempts[j.path]} times; "
                                    "giving up (finished runs are kept)")
                        if not (interrupts.stop or error is not None):
                            queue.extend(reversed(lost))  # retried first, on a fresh pool
                        continue
                    if isinstance(result, _Skipped):
                        continue
                    with interrupts.held():  # the file and the count agree whenever the abort comes
                        atomic_write(job.path, write, result)
                        computed += 1
                    bar.update()
            if interrupts.stop:
                raise GridInterrupted(len(done_before) + computed, total, immediate=False)
    except _Abort as stop:
        with _signals_ignored():
            if backend is not None:
                backend.abort()
                backend = None
        raise GridInterrupted(len(done_before) + computed, total, immediate=True, signum=stop.signum) from None
    finally:
        bar.close()
        if backend is not None:
            try:
                with interrupts:  # waiting for the workers to finish: a second Ctrl-C or SIGTERM abandons them
                    backend.close()
            except _Abort as stop:
                with _signals_ignored():
                    backend.abort()
                raise GridInterrupted(len(done_before) + computed, total, immediate=True,
                                      signum=stop.signum) from None
    if error is not None:
        raise error
    return GridReport(total, len(done_before), computed)
