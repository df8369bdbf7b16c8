r"""Tasks on forked copies of this process: parallel work whose inputs need no pickling.

A sweep (:func:`~continuation.sweep.run_sweep`) sends each task's inputs to a worker
that rebuilds everything from them. Some parallel work is instead a handful of solves
that share large in-memory state (compiled CasADi functions, a branch of connecting
orbits, factorised Jacobians) which a fresh worker would spend seconds rebuilding.
:class:`ForkedTasks` forks ``children`` copies of the process instead: each inherits
that state as it is at the fork, pulls task indices from one shared pipe (reads of 4
bytes from a pipe are atomic, so no task is taken twice) and appends each result to its
own file as soon as it is finished. The parent may go on with other work meanwhile,
then takes the tasks still queued itself (:meth:`ForkedTasks.run_rest`) and collects
(:meth:`ForkedTasks.results`).

* **Same results whichever process ran a task**: results are returned by task index;
  a task's value must depend only on its inputs and the state at the fork.
* **Nothing lost**: a task whose child died, or raised there, or whose result could
  not be pickled, is run again in the parent (an exception then surfaces there, with
  its traceback).
* **Ctrl-C**: children ignore SIGINT; the parent's ``KeyboardInterrupt`` reaches the
  caller, and :meth:`ForkedTasks.cancel` (or leaving the ``with`` block) stops the
  children and keeps the results they had finished (:attr:`ForkedTasks.finished`).
* **Forks only where safe**: Linux's ``os.fork``, a single thread in the process (a fork
  of a multi-threaded process can deadlock in a lock another thread held), not inside
  a forked child, at most :data:`MAX_TASKS` tasks; otherwise nothing is forked and
  every task runs in the parent.
"""

from __future__ import annotations

import contextlib
import logging
import os
import pickle
import shutil
import signal
import struct
import sys
import tempfile
import threading
from collections import deque
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Generic, TypeVar, cast

T = TypeVar("T")
R = TypeVar("R")

#: Most tasks of one :class:`ForkedTasks` run on children (their indices must fit in
#: the pipe's buffer, 64 KiB on Linux, before any child reads).
MAX_TASKS = 8192

_INDEX = struct.Struct("<I")
_LENGTH = struct.Struct("<Q")
_IN_CHILD = False

log = logging.getLogger(__name__)

#: Names of threads :func:`can_fork` does not count: threads that only wait in a system
#: call on a file descriptor of their own and hold no lock a forked child could need
#: (the command line's Ctrl-C watchdog, waiting on its signal pipe).
FORK_SAFE_THREADS: set[str] = set()


def can_fork() -> bool:
    """True when this process may fork workers (Linux, one thread, not a forked child).

    Threads named in :data:`FORK_SAFE_THREADS` are not counted. Only Linux: on macOS a
    forked child of a process that loaded system frameworks (Accelerate, the GUI
    libraries) may crash, which is why Python's multiprocessing spawns there; other
    systems are untested.
    """
    return (
        sys.platform.startswith("linux")
        and hasattr(os, "fork")
        and not _IN_CHILD
        and sum(t.name not in FORK_SAFE_THREADS for t in threading.enumerate()) == 1
    )


class ForkedTasks(Generic[T, R]):
    """Run ``fn(task)`` for every task, on forked children and in the parent.

    Parameters
    ----------
    fn : callable
        ``task -> result``; the result must be picklable to come back from a child.
    tasks : sequence, shape (n,)
        The tasks, run in index order by whichever process takes them.
    children : int
        Child processes to fork now (0: none; at most ``n``); none when
        :func:`can_fork` is False.

    Examples
    --------
    >>> with ForkedTasks(lambda k: k * k, range(5), children=1) as run:
    ...     run.results()
    {0: 0, 1: 1, 2: 4, 3: 9, 4: 16}
    """

    def __init__(self, fn: Callable[[T], R], tasks: Sequence[T], *, children: int) -> None:
        if isinstance(children, bool) or not isinstance(children, int) or children < 0:
            raise ValueError(f"`children` must be an integer >= 0, got {children!r}")
        self._fn = fn
        self._tasks = list(tasks)
        self.finished: dict[int, R] = {}
        self._kids: list[tuple[int, Path]] = []
        self._dir: str | None = None
        self._pipe: int | None = None
        self._queue: deque[int] = deque()
        n = len(self._tasks)
        children = min(children, n)
        if children == 0 or n > MAX_TASKS or not can_fork():
            if children and n > 1:
                others = [t.name for t in threading.enumerate() if t is not threading.main_thread()]
                log.info("%d tasks run in this process, not on %d forked children (%s)", n,
                         children, f"other threads alive: {others}" if others
                         else "forking is not possible here")  # fmt: skip
            self._queue.extend(range(n))
            return
        read, write = os.pipe()
        try:
            os.write(write, b"".join(_INDEX.pack(i) for i in range(n)))
        finally:
            os.close(write)
        self._pipe = read
        self._dir = tempfile.mkdtemp(prefix="broachkit-forked-")
        for stream in (sys.stdout, sys.stderr):  # nothing buffered is written twice
            with contextlib.suppress(Exception):
                stream.flush()
        for c in range(children):
            path = Path(self._dir) / f"{c}.results"
            pid = os.fork()
            if pid == 0:  # pragma: no cover (runs in the child, which never returns)
                self._child(path)
            self._kids.append((pid, path))

    @property
    def n_children(self) -> int:
        """Child processes forked (0 when everything runs in the parent)."""
        return len(self._kids)

    # ---- the child
    def _child(self, path: Path) -> None:  # pragma: no cover (measured in tests by effect)
        global _IN_CHILD
        _IN_CHILD = True
        code = 0
        try:
            signal.signal(signal.SIGINT, signal.SIG_IGN)
            with open(path, "wb") as out:
                while (i := self._take()) is not None:
                    try:
                        record = pickle.dumps((i, self._fn(self._tasks[i])), protocol=5)
                    except BaseException:  # the parent runs it again
                        continue
                    out.write(_LENGTH.pack(len(record)) + record)
                    out.flush()
        except BaseException:  # the parent reruns what is missing
            code = 1
        finally:
            os._exit(code)

    # ---- the queue
    def _take(self) -> int | None:
        if self._pipe is None:
            return self._queue.popleft() if self._queue else None
        data = os.read(self._pipe, _INDEX.size)
        if len(data) < _INDEX.size:
            return None
        return int(_INDEX.unpack(data)[0])

    def run_rest(self) -> None:
        """Run the tasks still queued in this (the parent) process, one after another."""
        while (i := self._take()) is not None:
            self.finished[i] = self._fn(self._tasks[i])

    def results(self) -> dict[int, R]:
        """Every task's result by index: the queue drained here, the children collected.

        Tasks lost by a child (it died, the task raised, its result did not pickle) are
        run again here.
        """
        self.run_rest()
        self._reap(kill=False)
        for i in range(len(self._tasks)):
            if i not in self.finished:
                self.finished[i] = self._fn(self._tasks[i])
        self._cleanup()
        return dict(sorted(self.finished.items()))

    def cancel(self) -> dict[int, R]:
        """Stop the children; the results finished so far (by index), nothing rerun."""
        self._reap(kill=True)
        self._cleanup()
        return dict(sorted(self.finished.items()))

    def _reap(self, *, kill: bool) -> None:
        for pid, _ in self._kids:
            if kill:
                with contextlib.suppress(ProcessLookupError):
                    os.kill(pid, signal.SIGKILL)
        for pid, path in self._kids:
            with contextlib.suppress(ChildProcessError):
                os.waitpid(pid, 0)
            self.finished.update(cast("dict[int, R]", _read_records(path)))
        self._kids = []

    def _cleanup(self) -> None:
        if self._pipe is not None:
            os.close(self._pipe)
            self._pipe = None
        if self._dir is not None:
            shutil.rmtree(self._dir, ignore_errors=True)
            self._dir = None

    def __enter__(self) -> ForkedTasks[T, R]:
        return self

    def __exit__(self, *exc: object) -> None:
        if self._kids or self._pipe is not None:
            self.cancel()


def _read_records(path: Path) -> dict[int, object]:
    """The complete ``(index, result)`` records of a child's file (a cut-off tail is dropped)."""
    out: dict[int, object] = {}
    try:
        data = path.read_bytes()
    except OSError:
        return out
    pos = 0
    while pos + _LENGTH.size <= len(data):
        (size,) = _LENGTH.unpack_from(data, pos)
        start, end = pos + _LENGTH.size, pos + _LENGTH.size + size
        if end > len(data):
            break
        try:
            i, value = pickle.loads(data[start:end])
        except Exception:  # a damaged record: the task is rerun
            break
        out[int(i)] = value
        pos = end
    return out


__all__ = ["FORK_SAFE_THREADS", "MAX_TASKS", "ForkedTasks", "can_fork"]
