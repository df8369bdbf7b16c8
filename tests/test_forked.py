"""Forked tasks (continuation.sweep.forked): same results as in one process, nothing lost.

References: the tasks run one after another in this process (``children=0``).
"""

from __future__ import annotations

import logging
import os
import sys
import threading
import time

import pytest

from continuation.sweep import forked
from continuation.sweep.forked import ForkedTasks, can_fork

pytestmark = [
    pytest.mark.skipif(not sys.platform.startswith("linux"), reason="forks only on Linux"),
    pytest.mark.usefixtures("single_threaded"),
]

PARENT = os.getpid()


def _square(k: int) -> tuple[int, int]:
    # slower here than in the children, so that children started late still get tasks
    time.sleep(0.05 if os.getpid() == PARENT else 0.01)
    return k * k, os.getpid()


def _no_zombies(pids: list[int]) -> None:
    for pid in pids:
        with pytest.raises(ChildProcessError):
            os.waitpid(pid, os.WNOHANG)


def test_can_fork_here():
    # the other tests of this file would only test the one-process path otherwise
    assert can_fork(), [t.name for t in threading.enumerate()]


@pytest.mark.parametrize("children", [0, 1, 2, 5])
def test_results_by_index_whoever_ran_them(children):
    with ForkedTasks(_square, range(40), children=children) as run:
        assert run.n_children == min(children, 40)
        pids = [pid for pid, _ in run._kids]
        out = run.results()
    assert {k: v[0] for k, v in out.items()} == {k: k * k for k in range(40)}
    if children:  # the children took some of the tasks
        assert {v[1] for v in out.values()} - {PARENT}
    _no_zombies(pids)


def test_parent_works_meanwhile_and_takes_the_rest():
    def task(k: int) -> tuple[int, int]:
        time.sleep(0.02)
        return k * k, os.getpid()

    with ForkedTasks(task, range(100), children=1) as run:
        time.sleep(0.05)  # the parent's own work; the child has started meanwhile
        out = run.results()
    owners = [out[k][1] for k in range(100)]
    assert PARENT in owners and len(set(owners)) == 2
    assert [out[k][0] for k in range(100)] == [k * k for k in range(100)]


def test_a_child_that_dies_loses_nothing():
    def task(k: int) -> int:
        if k == 3 and os.getpid() != PARENT:
            os._exit(9)  # the child dies in the middle of the task list
        return k + 100

    with ForkedTasks(task, range(8), children=2) as run:
        out = run.results()
    assert out == {k: k + 100 for k in range(8)}


def test_an_error_in_a_child_surfaces_in_the_parent():
    def task(k: int) -> int:
        if k == 2:
            raise ArithmeticError(f"task {k} failed in {os.getpid()}")
        return k

    with ForkedTasks(task, range(6), children=2) as run:
        with pytest.raises(ArithmeticError, match=f"task 2 failed in {PARENT}"):
            run.results()


def test_unpicklable_results_are_computed_in_the_parent():
    with ForkedTasks(lambda k: lambda: k, range(4), children=2) as run:
        out = run.results()
    assert [out[k]() for k in range(4)] == [0, 1, 2, 3]


def test_cancel_stops_children_and_keeps_finished():
    def task(k: int) -> int:
        if os.getpid() != PARENT:
            time.sleep(0.02 if k < 4 else 60.0)
        return k

    t0 = time.perf_counter()
    run = ForkedTasks(task, range(10), children=2)
    pids = [pid for pid, _ in run._kids]
    files = [path for _, path in run._kids]
    while sum(len(forked._read_records(f)) for f in files) < 4 and time.perf_counter() - t0 < 20:
        time.sleep(0.02)  # until the children have finished the 4 quick tasks
    done = run.cancel()
    assert time.perf_counter() - t0 < 30.0
    assert set(range(4)) <= set(done) and set(done) < set(range(10))
    assert all(done[k] == k for k in done)
    _no_zombies(pids)


def test_keyboard_interrupt_in_the_parent_leaves_no_children():
    def task(k: int) -> int:
        if os.getpid() == PARENT:
            raise KeyboardInterrupt
        time.sleep(60.0)
        return k

    with pytest.raises(KeyboardInterrupt):
        with ForkedTasks(task, range(4), children=1) as run:
            pids = [pid for pid, _ in run._kids]
            run.results()
    _no_zombies(pids)


def test_no_fork_with_other_threads(caplog):
    stop = threading.Event()
    t = threading.Thread(target=stop.wait, daemon=True, name="a-stray-thread")
    t.start()
    try:
        assert not can_fork()
        with caplog.at_level(logging.INFO, logger="continuation.sweep.forked"):
            with ForkedTasks(_square, range(5), children=2) as run:
                assert run.n_children == 0
                out = run.results()
        assert {v[1] for v in out.values()} == {PARENT}
        # the fallback is logged with the thread that caused it
        assert any("a-stray-thread" in r.getMessage() for r in caplog.records)
    finally:
        stop.set()
        t.join()


def test_bad_children_named():
    with pytest.raises(ValueError, match="`children`"):
        ForkedTasks(_square, range(3), children=-1)
