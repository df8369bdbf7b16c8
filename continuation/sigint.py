"""SIGINTs counted while a block runs, so that an interrupt is never lost.

Python runs a SIGINT handler between bytecodes of the main thread, and the default
handler raises ``KeyboardInterrupt`` there. That exception can be lost: raised inside a
weakref callback or a ``__del__`` it is only printed ("Exception ignored in ..."), and
a native call (CasADi's CVODES, its argument conversion) may clear it. Long work then
runs on as if nothing had happened. :func:`sigint_recorded` counts every SIGINT that
arrives while its block runs and still hands it to the handler installed before (so
``KeyboardInterrupt`` is raised as usual); the long-running loops (the simulator, the
fate classifier, :func:`continuation.sweep.run_sweep`) compare :func:`sigints_counted`
with their reading at the start and stop on a difference: a counted SIGINT always
stops them, at worst one step late.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any


class _Sigints:
    """SIGINTs seen while :func:`sigint_recorded` blocks run (``count``), and their depth."""

    count = 0
    depth = 0
    previous: Any = None


def _record_sigint(signum: int, frame: Any) -> Any:
    """Count the signal, then hand it to the handler that was installed before."""
    _Sigints.count += 1
    return _Sigints.previous(signum, frame)


@contextmanager
def sigint_recorded() -> Iterator[None]:
    """Count every SIGINT that arrives while the block runs, then handle it as before.

    The previous handler still runs (Python's default raises ``KeyboardInterrupt``);
    the count only lets a native call that failed tell that a SIGINT arrived while it
    ran (module notes). Re-entrant; a no-op outside the main thread (where no signal
    handler can be set) and when the current handler is not a Python callable
    (``SIG_IGN``, ``SIG_DFL``).
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    if _Sigints.depth > 0:
        _Sigints.depth += 1
        try:
            yield
        finally:
            _Sigints.depth -= 1
        return
    previous = signal.getsignal(signal.SIGINT)
    if not callable(previous):
        yield
        return
    _Sigints.previous = previous
    _Sigints.depth = 1
    signal.signal(signal.SIGINT, _record_sigint)
    try:
        yield
    finally:
        _Sigints.depth = 0
        signal.signal(signal.SIGINT, previous)
        _Sigints.previous = None


def sigints_counted() -> int:
    """SIGINTs counted by :func:`sigint_recorded` so far.

    Compare two readings taken inside one block: a difference is an interrupt, even one a
    CasADi call lost.
    """
    return _Sigints.count


__all__ = ["sigint_recorded", "sigints_counted"]
