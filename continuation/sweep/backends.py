"""Where the tasks run: any ``concurrent.futures`` executor, chosen by :func:`open_backend`.

- ``"processes"`` (default): a :class:`concurrent.futures.ProcessPoolExecutor`, one
  worker per core (``workers`` to change); rebuilt when a worker dies.
- ``"dask"``: a Dask distributed ``LocalCluster`` started for the run (``workers``
  processes, one thread each), closed at the end.
- ``scheduler="tcp://HOST:PORT"``: a Dask ``Client`` of a running cluster.
- a ``distributed.Client`` or any ``concurrent.futures.Executor`` passed in (left open).
- ``"serial"``: in the calling process, one task after another (debugging).

Nothing here schedules: Dask's scheduler or the process pool does. A worker that dies
is charged to every task running on it. The ``LocalCluster`` started here has Dask's
own resubmission switched off (``allowed-failures = 0``), so the sweep's single retry
is the only one; a running cluster keeps its own setting (Dask's default: 3 silent
resubmissions before ``KilledWorker``), then the sweep retries once more.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import logging
import multiprocessing
import os
import signal
from collections.abc import Callable
from typing import Any

log = logging.getLogger(__name__)

BACKENDS = ("processes", "dask", "serial")


class SerialExecutor(cf.Executor):
    """Runs each task at ``submit`` in the calling process (a finished future back)."""

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> cf.Future:
        """Run ``fn(*args, **kwargs)`` now; a finished future with its result or error."""
        fut: cf.Future = cf.Future()
        fut.set_running_or_notify_cancel()
        try:
            fut.set_result(fn(*args, **kwargs))
        except Exception as exc:
            fut.set_exception(exc)
        return fut


#: Environment variable naming the lowest level a worker process logs (e.g. ``ERROR``):
#: set by a front end that keeps library messages quiet (the ``broachkit`` command
#: without ``--verbose``); worker processes inherit it. Unset: Python's default (a
#: process without logging configured prints warnings and errors to stderr).
WORKER_LOG_ENV = "CONTINUATION_WORKER_LOG_LEVEL"

_worker_logging_done = False


def configure_worker_logging() -> None:
    """In a worker process: log at :data:`WORKER_LOG_ENV`'s level or above, to stderr.

    A spawned worker (process pool, Dask) starts with logging unconfigured, so every
    library warning would reach stderr through Python's last-resort handler whatever
    the front end chose; this gives it one handler at the level the front end set. Runs
    once per process, only in a child process (``multiprocessing.parent_process()``),
    and only when the variable names a level; elsewhere it does nothing.
    """
    global _worker_logging_done
    if _worker_logging_done or multiprocessing.parent_process() is None:
        return
    _worker_logging_done = True
    name = os.environ.get(WORKER_LOG_ENV, "").strip().upper()
    level = logging.getLevelName(name) if name else None
    if not isinstance(level, int):
        return
    handler = logging.StreamHandler()
    handler.setLevel(level)
    handler.setFormatter(logging.Formatter("%(levelname)s %(name)s: %(message)s"))
    logging.getLogger().addHandler(handler)


def _ignore_sigint() -> None:
    # the sweep's process handles Ctrl-C (cancels, then stops the workers); the worker
    # logs only what the front end asked for (WORKER_LOG_ENV)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    configure_worker_logging()


@contextlib.contextmanager
def sigint_blocked() -> Any:
    """Inside: SIGINT blocked in the calling (main) thread; pending Ctrl-C delivered after.

    Processes and threads started inside inherit the blocked signal, so a Ctrl-C at the
    terminal (sent to the whole process group) reaches only this process, which stops
    its workers itself; without it, a worker still importing its modules prints a
    ``KeyboardInterrupt`` traceback of its own. A no-op outside the main thread or on
    platforms without ``pthread_sigmask``.
    """
    import threading

    mask = getattr(signal, "pthread_sigmask", None)
    if mask is None or threading.current_thread() is not threading.main_thread():
        yield
        return
    _start_resource_tracker()
    old = mask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        mask(signal.SIG_SETMASK, old)


def _start_resource_tracker() -> None:
    """Start multiprocessing's resource tracker now, before SIGINT is blocked.

    Its first start (at the first process or semaphore) *unblocks* SIGINT in the calling
    thread (CPython's ``resource_tracker.ensure_running``), so every process started
    after it would take the terminal's Ctrl-C again.
    """
    from multiprocessing import resource_tracker

    with contextlib.suppress(Exception):
        resource_tracker.ensure_running()


class _QuietProcessPool(cf.ProcessPoolExecutor):
    """A process pool whose workers are started with SIGINT blocked (:func:`sigint_blocked`).

    The pool starts its processes inside ``submit`` (in the submitting thread), so that
    is where the signal is blocked.
    """

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> cf.Future:
        with sigint_blocked():
            return super().submit(fn, *args, **kwargs)


class Backend:
    """An executor plus what the sweep needs to know about it.

    Attributes
    ----------
    name : str
        ``"processes"``, ``"dask"``, ``"dask-scheduler"``, ``"executor"`` or ``"serial"``.
    slots : int
        Tasks that can run at once (the sweep keeps at most this many in flight, so a
        dead worker is charged only to the tasks that were running).
    """

    def __init__(
        self,
        name: str,
        executor: cf.Executor,
        slots: int,
        *,
        rebuild: Callable[[], cf.Executor] | None = None,
        owned: tuple[Any, ...] = (),
        alive: Callable[[], int] | None = None,
    ) -> None:
        self.name, self.executor, self.slots = name, executor, max(int(slots), 1)
        self._rebuild, self._owned, self._alive = rebuild, owned, alive
        #: Process ids this backend started (a LocalCluster's nannies and workers).
        self.pids: tuple[int, ...] = ()
        #: Incremented each time the executor is replaced.
        self.generation = 0

    def capacity(self) -> int:
        """Tasks that can run at once now: ``slots``, or fewer while workers are down.

        For a Dask cluster this is the number of worker threads the scheduler has now.
        While a dead worker is being replaced, a task submitted beyond that number would
        wait on a surviving worker and be charged if that one dies too; keeping no more
        in flight than can run means a worker's death is charged only to the task it was
        running.
        """
        if self._alive is None:
            return self.slots
        try:
            return max(min(int(self._alive()), self.slots), 0)
        except Exception as exc:  # the scheduler is unreachable: let submit report it
            log.debug("could not ask for the live workers: %s", exc)
            return self.slots

    def submit(self, fn: Callable[..., Any], *args: Any) -> cf.Future:
        """Submit ``fn(*args)``; a broken process pool is replaced first."""
        try:
            return self.executor.submit(fn, *args)
        except cf.BrokenExecutor:
            self.recover()
            return self.executor.submit(fn, *args)

    def recover(self) -> None:
        """Replace a broken executor (a worker died) by a fresh one, if it can be rebuilt."""
        if self._rebuild is None:
            raise RuntimeError(f"the {self.name} executor broke and cannot be rebuilt")
        log.warning("a worker died: starting a new %s pool", self.name)
        self._stop_executor(cancel=True)
        self.executor = self._rebuild()
        self.generation += 1

    def _stop_executor(self, cancel: bool) -> None:
        ex = self.executor
        if isinstance(ex, cf.ProcessPoolExecutor):
            if not cancel:
                ex.shutdown(wait=True)
            else:
                _stop_process_pool(ex)
        elif self._rebuild is not None or self.name == "serial":
            ex.shutdown(wait=not cancel, cancel_futures=cancel)

    def close(self, cancel: bool = False) -> None:
        """Shut down what the sweep started (a passed-in executor or client stays open).

        With ``cancel`` (Ctrl-C) the processes this backend started are killed first, so
        closing a ``LocalCluster`` does not wait for its running tasks; a repeated Ctrl-C
        during the shutdown does not cut it short (the sweep is already interrupted).
        """
        if cancel and self.pids:
            _kill_processes(self.pids)
        if self._rebuild is not None or self.name == "serial":
            self._stop_executor(cancel)
        elif cancel and self.name.startswith("dask"):
            with contextlib.suppress(Exception):
                self.executor.shutdown(wait=False)
        for obj in self._owned:
            try:
                if cancel and hasattr(obj, "close"):
                    try:
                        obj.close(timeout=2)
                    except TypeError:
                        obj.close()
                else:
                    obj.close()
            except KeyboardInterrupt:
                log.debug("a repeated interrupt while closing %s", type(obj).__name__)
            except Exception as exc:  # pragma: no cover - best effort at shutdown
                log.warning("closing %s failed: %s", type(obj).__name__, exc)


def _child_pids() -> set[int]:
    try:
        import psutil
    except ImportError:  # pragma: no cover - psutil comes with distributed
        return set()
    return {c.pid for c in psutil.Process().children(recursive=True)}


def _helper_pids() -> set[int]:
    """Helper processes of ``multiprocessing`` (the resource tracker), never killed."""
    from multiprocessing import resource_tracker

    pid = getattr(resource_tracker._resource_tracker, "_pid", None)
    return {pid} if pid else set()


def _kill_processes(pids: tuple[int, ...], timeout: float = 1.0) -> None:
    """Kill processes (and their children) this backend started; gone ones are skipped."""
    import psutil

    procs = []
    for pid in pids:
        with contextlib.suppress(psutil.Error):
            p = psutil.Process(pid)
            procs += [*p.children(recursive=True), p]
    for p in procs:
        with contextlib.suppress(psutil.Error):
            p.kill()
    psutil.wait_procs(procs, timeout=timeout)


def _stop_process_pool(ex: cf.ProcessPoolExecutor, timeout: float = 10.0) -> None:
    """Cancel a process pool's tasks, stop its processes, and wait for its threads.

    ``shutdown(wait=False)`` alone returns while the pool's manager thread and its
    call queue's feeder thread still run; they normally end soon after, but a feeder
    left behind (seen on a loaded 2-core machine) keeps the process multi-threaded for
    good, and a multi-threaded process must not fork. So the stop is synchronous: the
    processes are terminated, the manager thread joined, and the call queue closed
    (its feeder ends once its buffer is written or, with the reading end closed, fails).
    """
    procs = list((getattr(ex, "_processes", None) or {}).values())
    manager = getattr(ex, "_executor_manager_thread", None)
    calls = getattr(ex, "_call_queue", None)
    ex.shutdown(wait=False, cancel_futures=True)
    for p in procs:  # running tasks are abandoned: stop their processes now
        if p.is_alive():
            p.terminate()
    for p in procs:
        p.join(timeout=timeout)
    if manager is not None:
        manager.join(timeout=timeout)
    if calls is None:
        return
    calls.close()  # idempotent: the feeder ends after what it holds
    feeder = getattr(calls, "_thread", None)
    if feeder is None:
        return
    feeder.join(timeout=timeout / 2)
    if feeder.is_alive():  # blocked writing to a pipe no process reads any more
        with contextlib.suppress(OSError):
            calls._reader.close()
        feeder.join(timeout=timeout / 2)
    if feeder.is_alive():
        log.warning("a process pool's queue thread did not end; this process cannot fork")


#: Most local worker processes a sweep starts (each holds its own copy of the model and
#: its compiled functions, a few hundred MB): one definition for every check.
MAX_WORKERS = 64


def check_workers(workers: Any, name: str = "`workers`") -> int | None:
    """The one check of a count of local worker processes.

    Parameters
    ----------
    workers : int or None
        ``None`` (the caller's default, e.g. one per core) or an integer in
        ``[1, MAX_WORKERS]``.
    name : str
        How the count is named in the message (``"--workers"`` on the command line).

    Returns
    -------
    int or None
        ``workers`` unchanged.

    Raises
    ------
    ValueError
        Naming ``name``, for anything else (booleans, floats, 0, negative, or more than
        :data:`MAX_WORKERS`).
    """
    if workers is None:
        return None
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ValueError(f"{name} must be a positive integer, got {workers!r}")
    if workers > MAX_WORKERS:
        raise ValueError(
            f"{name} must be at most {MAX_WORKERS} (each worker process holds its own "
            f"copy of the model), got {workers}"
        )
    return workers


def default_workers() -> int:
    """One worker process per core, at most :data:`MAX_WORKERS`."""
    return max(1, min(os.cpu_count() or 1, MAX_WORKERS))


def _process_pool(workers: int, start_method: str) -> cf.ProcessPoolExecutor:
    ctx = multiprocessing.get_context(start_method)
    return _QuietProcessPool(max_workers=workers, mp_context=ctx, initializer=_ignore_sigint)


def _client_backend(
    client: Any, name: str, owned: tuple[Any, ...], slots: int | None = None
) -> Backend:
    def alive() -> int:
        return sum(client.nthreads().values())

    return Backend(
        name, client.get_executor(pure=False), slots or alive() or 1, owned=owned, alive=alive
    )


def _is_client(obj: Any) -> bool:
    return type(obj).__name__ == "Client" and hasattr(obj, "get_executor")


def _start_local_cluster(k: int, poll: float = 0.05) -> tuple[Any, Any, tuple[int, ...]]:
    """A Dask ``LocalCluster`` of ``k`` one-thread worker processes and its ``Client``.

    The start (several seconds: each worker process imports its modules) runs in a
    daemon thread with SIGINT blocked, so the processes and threads it starts inherit
    the block and a Ctrl-C at the terminal (sent to the whole process group) reaches
    only this process. This (the main) thread waits for it in short slices, so a
    Ctrl-C during the start raises ``KeyboardInterrupt`` here at once; the start is then
    abandoned: the processes it has started so far, and any it starts in the next
    moments, are killed, and the thread closes what it built if it still returns.

    Returns
    -------
    cluster, client, pids
        ``pids``: the processes the cluster started (its worker processes).
    """
    import threading

    import dask
    from distributed import Client, LocalCluster

    box: dict[str, Any] = {}
    ready, abandoned = threading.Event(), threading.Event()

    _start_resource_tracker()
    before = _child_pids() | _helper_pids()

    def start() -> None:
        mask = getattr(signal, "pthread_sigmask", None)
        if mask is not None:
            mask(signal.SIG_BLOCK, {signal.SIGINT})
        made: list[Any] = []
        try:
            # the sweep retries a task once itself: Dask must not resubmit it on its own
            with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
                made.append(
                    LocalCluster(
                        n_workers=k,
                        threads_per_worker=1,
                        processes=True,
                        dashboard_address=":0",
                        silence_logs=logging.ERROR,
                    )
                )
                made.append(Client(made[0]))
            box["made"] = made
        except BaseException as exc:  # reported by the waiting thread
            box["error"] = exc
        finally:
            if abandoned.is_set() or "error" in box:
                for obj in reversed(made):  # nobody will use them
                    with contextlib.suppress(BaseException):
                        obj.close(timeout=1)
            ready.set()

    thread = threading.Thread(target=start, name="sweep-dask-start", daemon=True)
    thread.start()
    try:
        while not ready.wait(poll):
            pass
    except BaseException:  # Ctrl-C during the start: give it up, stop what it started
        abandoned.set()
        _kill_new_processes(before, settle=0.3)
        raise
    if "error" in box:
        raise box["error"]
    cluster, client = box["made"]
    pids = tuple(sorted(_child_pids() - before - _helper_pids()))
    return cluster, client, pids


def _kill_new_processes(before: set[int], settle: float) -> None:
    """Kill this process's descendants not in ``before``, repeatedly for ``settle`` s.

    A start abandoned in another thread may still be starting some.
    """
    import time

    t_end = time.monotonic() + settle
    while True:
        new = tuple(sorted(_child_pids() - before - _helper_pids()))
        if new:
            _kill_processes(new, timeout=0.3)
        if time.monotonic() >= t_end:
            return
        time.sleep(0.05)


def open_backend(
    backend: str | cf.Executor | Any = "processes",
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    start_method: str = "spawn",
) -> Backend:
    """Resolve the user's choice of executor.

    Parameters
    ----------
    backend : {"processes", "dask", "serial"}, Executor or distributed.Client
        See the module docstring.
    workers : int, optional
        Workers of a process pool or of the ``LocalCluster`` (default: one per core).
    scheduler : str, optional
        Address of a running Dask scheduler (overrides ``backend``).
    start_method : str
        Multiprocessing start method of the process pool.

    Returns
    -------
    Backend

    Raises
    ------
    ValueError
        For an unknown backend, bad ``workers`` or an unreachable scheduler.
    """
    n = check_workers(workers)
    cores = default_workers()
    if scheduler is not None:
        if not isinstance(scheduler, str) or not scheduler:
            raise ValueError(
                f"`scheduler` must be an address like tcp://HOST:PORT, got {scheduler!r}"
            )
        from distributed import Client

        try:
            client = Client(scheduler, timeout="10s")
        except (OSError, TimeoutError) as exc:
            raise ValueError(f"`scheduler`: cannot connect to {scheduler} ({exc})") from None
        return _client_backend(client, "dask-scheduler", (client,))
    if _is_client(backend):
        return _client_backend(backend, "dask-scheduler", ())
    if isinstance(backend, cf.Executor):
        slots = getattr(backend, "_max_workers", None) or n or cores
        return Backend("executor", backend, slots)
    if backend == "processes":
        k = n or cores
        return Backend(
            "processes", _process_pool(k, start_method), k,
            rebuild=lambda: _process_pool(k, start_method),
        )  # fmt: skip
    if backend == "serial":
        return Backend("serial", SerialExecutor(), 1)
    if backend == "dask":
        k = n or cores
        cluster, client, pids = _start_local_cluster(k)
        be = _client_backend(client, "dask", (client, cluster), slots=k)
        be.pids = pids
        return be
    raise ValueError(
        f"`backend` must be one of {', '.join(BACKENDS)}, a concurrent.futures.Executor or a "
        f"distributed.Client, got {backend!r}"
    )


__all__ = [
    "BACKENDS",
    "MAX_WORKERS",
    "WORKER_LOG_ENV",
    "Backend",
    "SerialExecutor",
    "check_workers",
    "default_workers",
    "configure_worker_logging",
    "open_backend",
]
