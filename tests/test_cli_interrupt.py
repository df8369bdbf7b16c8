"""Ctrl-C stops the whole command even when library code keeps partial results.

``broachkit_cli.interrupt.sticky_interrupt`` re-raises ``KeyboardInterrupt`` until the
command acknowledges it; these tests swallow the first interrupt the way the engine does
(``INTERRUPTED`` status with the part computed so far) and check that the next
computation is stopped within a few repeat periods, and that the handler is restored.
"""

from __future__ import annotations

import os
import signal
import threading
import time

import pytest

from broachkit_cli.interrupt import acknowledge, sticky_interrupt


def _library_call(seconds: float) -> str:
    """A long computation that turns Ctrl-C into a status, as the engine does."""
    t_end = time.monotonic() + seconds
    try:
        while time.monotonic() < t_end:
            time.sleep(0.005)
    except KeyboardInterrupt:
        return "INTERRUPTED"
    return "SUCCESS"


def _send_sigint_after(delay: float) -> threading.Timer:
    timer = threading.Timer(delay, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    return timer


@pytest.mark.skipif(os.name != "posix", reason="POSIX signals")
def test_a_swallowed_interrupt_is_raised_again_in_the_next_computation():
    before = signal.getsignal(signal.SIGINT)
    statuses: list[str] = []
    _send_sigint_after(0.2)
    t0 = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        with sticky_interrupt(repeat=0.1):
            statuses.append(_library_call(30.0))  # swallows the user's Ctrl-C
            while True:  # the study goes on: an unprotected 30-s computation
                time.sleep(0.005)
                if time.monotonic() - t0 > 30.0:
                    break
    acknowledge()
    elapsed = time.monotonic() - t0
    assert statuses == ["INTERRUPTED"]
    # 0.2 s until the signal, then at most a few 0.1-s repeats (generous for a loaded CI)
    assert elapsed < 5.0
    assert signal.getsignal(signal.SIGINT) is before


@pytest.mark.skipif(os.name != "posix", reason="POSIX signals")
def test_without_an_interrupt_the_block_runs_to_its_end_and_restores_the_handler():
    before = signal.getsignal(signal.SIGINT)
    with sticky_interrupt(repeat=0.05):
        assert _library_call(0.3) == "SUCCESS"
    assert signal.getsignal(signal.SIGINT) is before


def test_outside_the_main_thread_it_does_nothing():
    seen: list[object] = []

    def work() -> None:
        with sticky_interrupt(repeat=0.05):
            seen.append(signal.getsignal(signal.SIGINT))

    before = signal.getsignal(signal.SIGINT)
    t = threading.Thread(target=work)
    t.start()
    t.join()
    assert seen == [before]
