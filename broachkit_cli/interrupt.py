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
import sys
import threading
from collections.abc import Iterator
from typing import Any

_state: dict[str, Any] = {
    "requested": threading.Event(),
    "done": threading.Event(),
    "seen": False,
    "verbose": False,
}


def show_teardown(verbose: bool) -> None:
    """Whether the noise of a stopped command's threads is shown (``--verbose``).

    After a Ctrl-C the command's other threads (a Dask cluster's event loop, a cluster
    start abandoned in a background thread) may die with an exception while the
    process ends; without ``--verbose`` such exceptions are not printed
    (:func:`sticky_interrupt`), the command's one line says what happened.
    """
    _state["verbose"] = bool(verbose)


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


#: The line a stopped command ends with when it did not say more itself.
INTERRUPTED_LINE = "interrupted; finished results are kept on disk"


#: Name of the watchdog thread (a thread :func:`continuation.sweep.forked.can_fork`
#: does not count: it only waits on its own pipe).
WATCHDOG_THREAD = "broachkit-ctrl-c-watchdog"


class _Watchdog:
    """Ends the process ``deadline`` s after a SIGINT arrived, if it still runs.

    A native call (building a CasADi function, a factorisation) returns to Python only
    when it is done: neither Python's SIGINT handler nor the repeated interrupts run
    inside it. The C-level handler still writes the signal's number to the wakeup pipe
    (:func:`signal.set_wakeup_fd`) at once; this thread waits on that pipe, and such
    calls release the GIL, so it can end the process (:func:`end_process`) on time.
    Nothing finished is lost: results are written atomically as they finish, and an
    interrupted step is marked to be redone.
    """

    def __init__(self, deadline: float, code: int) -> None:
        import os

        from continuation.sweep.forked import FORK_SAFE_THREADS

        FORK_SAFE_THREADS.add(WATCHDOG_THREAD)
        self.deadline, self.code = deadline, code
        self._read, self._write = os.pipe()
        os.set_blocking(self._write, False)
        self._old = signal.set_wakeup_fd(self._write, warn_on_full_buffer=False)
        self._thread = threading.Thread(target=self._run, name=WATCHDOG_THREAD, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        import os
        import sys
        import time

        while True:
            try:
                data = os.read(self._read, 64)
            except OSError:
                return
            if not data:  # closed: the command ended
                return
            if signal.SIGINT in data:
                break
        time.sleep(self.deadline)
        if not _state["done"].is_set():  # the command did not handle it (nor say so)
            with contextlib.suppress(Exception):
                sys.stderr.write(INTERRUPTED_LINE + "\n")
        end_process(self.code, timeout=0.3)

    def close(self) -> None:
        """Stop watching (the previous wakeup descriptor is restored)."""
        import os

        with contextlib.suppress(ValueError, OSError):
            signal.set_wakeup_fd(self._old)
        with contextlib.suppress(OSError):
            os.close(self._write)  # the thread reads end-of-file and ends
        self._thread.join(timeout=1.0)
        with contextlib.suppress(OSError):
            os.close(self._read)


@contextlib.contextmanager
def sticky_interrupt(
    repeat: float = 0.5, deadline: float | None = None, code: int = 130
) -> Iterator[None]:
    """Inside: Ctrl-C raises ``KeyboardInterrupt`` and keeps raising it until handled.

    Only in the main thread (elsewhere it does nothing); the previous SIGINT handler is
    restored on exit.

    Parameters
    ----------
    repeat : float
        Seconds between the repeated interrupts.
    deadline : float, optional
        For a command-line process only: if it still runs ``deadline`` seconds after
        the first Ctrl-C (stuck in a long native call), a watchdog thread ends it with
        exit status ``code`` (:class:`_Watchdog`, :func:`end_process`). ``None``: no
        watchdog.
    code : int
        Exit status of that end.
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
        if not _state["seen"] and not _state["verbose"]:
            # the process is ending: a thread that dies of it is not the user's concern
            threading.excepthook = _quiet_thread_exception
        _state["seen"] = True
        if not _state["done"].is_set():
            _state["requested"].set()
            if not watcher:
                watcher.append(threading.Thread(target=_repeat, args=(repeat,), daemon=True))
                watcher[0].start()
            raise KeyboardInterrupt

    previous = signal.signal(signal.SIGINT, handler)
    previous_hook, previous_thread_hook = sys.unraisablehook, threading.excepthook
    sys.unraisablehook = _quiet_unraisable_interrupt(previous_hook)
    dog: _Watchdog | None = None
    try:
        if deadline is not None:
            dog = _Watchdog(deadline, code)
        yield
    finally:
        _state["done"].set()
        _state["requested"].set()  # let the watcher end
        signal.signal(signal.SIGINT, previous)
        sys.unraisablehook = previous_hook
        if not _state["seen"] or deadline is None:
            # a command-line process keeps the quiet hook after a Ctrl-C: it is ending
            threading.excepthook = previous_thread_hook
        if dog is not None and not _state["seen"]:
            dog.close()  # after a Ctrl-C it stays: the process is ending


def _quiet_thread_exception(args: Any) -> None:
    """``threading.excepthook`` after a Ctrl-C: a thread's exception is not printed."""
    del args


def _quiet_unraisable_interrupt(previous: Any) -> Any:
    """An unraisable-exception hook that drops a ``KeyboardInterrupt``.

    The SIGINT handler raises in whatever Python code runs at that moment; when that is
    a weakref callback, a ``__del__`` or a garbage-collector callback, Python cannot
    propagate the exception and prints "Exception ignored in ..." with a traceback.
    Nothing is lost by dropping it: the handler has already set the request, and the
    repeated interrupt (:func:`_repeat`) raises it again where it can propagate. Every
    other unraisable exception goes to ``previous``.
    """

    def hook(unraisable: Any) -> None:
        if isinstance(unraisable.exc_value, KeyboardInterrupt):
            return
        previous(unraisable)

    return hook


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


__all__ = [
    "INTERRUPTED_LINE",
    "acknowledge",
    "end_process",
    "show_teardown",
    "sticky_interrupt",
    "was_interrupted",
]
