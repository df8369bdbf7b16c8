"""Ctrl-C that stops the command, even through library code that keeps partial results.

The engine turns a ``KeyboardInterrupt`` inside a long computation into an
``INTERRUPTED`` status with the part computed so far (a branch, a trajectory), which is
right for a library but lets a study go on to its next computation. The command line
wants the whole command to stop: :func:`sticky_interrupt` installs a SIGINT handler that
raises ``KeyboardInterrupt`` as usual and, from then on, raises it again in the main
thread every ``repeat`` seconds (a real SIGINT sent to the main thread, which also
ends a blocking wait such as a future's ``result()``) until the command
acknowledges it (:func:`acknowledge`, called where the interrupt is handled), so the
command ends within about ``repeat`` seconds of the last computation that swallowed it.
"""

from __future__ import annotations

import _thread
import contextlib
import signal
import threading
from collections.abc import Iterator
from typing import Any

_state: dict[str, Any] = {
    "requested": threading.Event(),
    "done": threading.Event(),
    "seen": False,
}


def was_interrupted() -> bool:
    """A Ctrl-C arrived during the last (or current) :func:`sticky_interrupt` block."""
    return bool(_state["seen"])


def acknowledge() -> None:
    """The interrupt has reached the command's handler: stop repeating it."""
    _state["done"].set()


def _repeat(repeat: float) -> None:
    requested, done = _state["requested"], _state["done"]
    requested.wait()
    main_id = threading.main_thread().ident
    while not done.wait(repeat):
        if hasattr(signal, "pthread_kill") and main_id is not None:
            # a real signal: it also wakes the main thread from a blocking wait (a
            # future's result, a lock), which interrupt_main's flag alone does not
            signal.pthread_kill(main_id, signal.SIGINT)
        else:  # pragma: no cover - platforms without pthread_kill
            _thread.interrupt_main(signal.SIGINT)


@contextlib.contextmanager
def sticky_interrupt(repeat: float = 0.5) -> Iterator[None]:
    """Inside: Ctrl-C raises ``KeyboardInterrupt`` and keeps raising it until handled.

    Only in the main thread (elsewhere it does nothing); the previous SIGINT handler is
    restored on exit.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _state["requested"], _state["done"] = threading.Event(), threading.Event()
    _state["seen"] = False

    # the watcher thread starts with the first Ctrl-C: until then the process has one
    # thread, so library code may fork workers (continuation.sweep.forked.can_fork)
    watcher: list[threading.Thread] = []

    def handler(signum: int, frame: Any) -> None:
        _state["seen"] = True
        if not _state["done"].is_set():
            _state["requested"].set()
            if not watcher:
                watcher.append(threading.Thread(target=_repeat, args=(repeat,), daemon=True))
                watcher[0].start()
            raise KeyboardInterrupt

    previous = signal.signal(signal.SIGINT, handler)
    try:
        yield
    finally:
        _state["done"].set()
        _state["requested"].set()  # let the watcher end
        signal.signal(signal.SIGINT, previous)


def end_process(code: int, timeout: float = 0.5) -> None:
    """End this process now with ``code``, after stopping the processes it started.

    For the command line after an interrupt, once the command has written what it
    keeps: every descendant process still running (worker processes, a Dask cluster's
    workers, forked children; multiprocessing's resource tracker excepted, which cleans
    up after this process) is killed and waited for at most ``timeout`` seconds, the
    standard streams are flushed, and the process exits without running the
    interpreter's exit handlers (Dask's wait up to 10 s for a cluster to close, and a
    cluster start abandoned by the interrupt may still be running in a thread).
    """
    import os
    import sys

    with contextlib.suppress(Exception):
        _kill_descendants(timeout)
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    os._exit(code)


def _kill_descendants(timeout: float) -> None:
    import psutil

    procs = []
    for p in psutil.Process().children(recursive=True):
        with contextlib.suppress(psutil.Error):
            if "resource_tracker" not in " ".join(p.cmdline()):
                procs.append(p)
    for p in procs:
        with contextlib.suppress(psutil.Error):
            p.kill()
    psutil.wait_procs(procs, timeout=timeout)


__all__ = ["acknowledge", "end_process", "sticky_interrupt", "was_interrupted"]
