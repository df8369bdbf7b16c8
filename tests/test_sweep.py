"""The generic sweep layer (continuation.sweep): checkpoints, resume, retries, backends.

Real worker processes throughout: a ProcessPoolExecutor and a Dask ``LocalCluster``
(processes, 2 workers, as on this 2-core machine), with workers killed mid-sweep.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
import sweep_tasks as T

from continuation.status import Status
from continuation.sweep import (
    CheckpointStore,
    canonical_json,
    run_sweep,
    source_version,
    task_id,
)

pytest.importorskip("distributed")


def keys(log: Path, xs, **extra):
    return [{"x": x, "log": str(log), **extra} for x in xs]


def expected_rows(log: Path, xs):
    return [
        {"x": x, "log": str(log), "y": x * x, "third": x / 3.0, "pid_free": [x, "a"],
         "task_status": "done", "task_error": ""}
        for x in sorted(xs)
    ]  # fmt: skip


# ----------------------------------------------------------------- identity, store
def test_task_id_depends_on_every_input():
    k = {"a": 1, "b": [1.5, "z"]}
    base = task_id("m:f", k, "ctx", "v1")
    assert task_id("m:f", {"b": [1.5, "z"], "a": 1}, "ctx", "v1") == base  # order-free
    for other in (
        task_id("m:g", k, "ctx", "v1"),
        task_id("m:f", {**k, "a": 2}, "ctx", "v1"),
        task_id("m:f", k, "ctx2", "v1"),
        task_id("m:f", k, "ctx", "v2"),
    ):
        assert other != base
    assert canonical_json(k) == '{"a":1,"b":[1.5,"z"]}'


def test_source_version_is_a_digest_of_the_package():
    v = source_version(T.square, "continuation")
    assert v.startswith("continuation=") and ";sweep_tasks=" in v
    assert v == source_version(T.square, "continuation")


def test_store_writes_atomically_and_skips_garbage(tmp_path):
    st = CheckpointStore(tmp_path / "ck")
    p = st.save({"id": "abc", "key": {"x": 1}, "status": "done", "value": 2})
    assert p.name == "abc.json"
    assert list((tmp_path / "ck").glob(".*tmp")) == []  # no temporary left behind
    (tmp_path / "ck" / "half.json").write_text('{"id": "half", "key"')  # a torn write
    (tmp_path / "ck" / "other.json").write_text('{"id": "not-other"}')
    assert list(st.load()) == ["abc"]
    with pytest.raises(ValueError, match="`store` must be a directory"):
        CheckpointStore(p)


def test_bad_input_is_a_one_line_value_error(tmp_path):
    with pytest.raises(ValueError, match="module-level function"):
        run_sweep(lambda k: k, [{"x": 1}], backend="serial")
    with pytest.raises(ValueError, match=r"`keys\[1\]` must be a non-empty dict"):
        run_sweep(T.square, [{"x": 1}, {}], backend="serial")
    with pytest.raises(ValueError, match=r"`keys\[0\].x` must be finite"):
        run_sweep(T.square, [{"x": float("nan")}], backend="serial")
    with pytest.raises(ValueError, match="must all be different"):
        run_sweep(T.square, [{"x": 1}, {"x": 1}], backend="serial")
    with pytest.raises(ValueError, match="`backend` must be one of"):
        run_sweep(T.square, keys(tmp_path, [1]), backend="threads")
    with pytest.raises(ValueError, match="`workers` must be a positive integer"):
        run_sweep(T.square, keys(tmp_path, [1]), workers=0)
    with pytest.raises(ValueError, match="`retries`"):
        run_sweep(T.square, keys(tmp_path, [1]), retries=-1)


# ----------------------------------------------------------------- serial semantics
def test_table_is_sorted_by_key_numerically(tmp_path):
    xs = [10, 2, 33, 1, 5]
    r = run_sweep(T.square, keys(tmp_path, xs), backend="serial")
    assert r.success and r.status is Status.SUCCESS
    assert r.rows() == expected_rows(tmp_path, xs)
    assert [rec.key["x"] for rec in r.records] == [1, 2, 5, 10, 33]


def test_resume_redoes_no_finished_task(tmp_path):
    log, ck = tmp_path / "log", tmp_path / "ck"
    first = run_sweep(T.square, keys(log, range(4)), store=ck, backend="serial")
    assert first.n_executed == 4 and first.n_reused == 0
    again = run_sweep(T.square, keys(log, range(7)), store=ck, backend="serial")
    assert again.n_reused == 4 and again.n_executed == 3
    assert all(T.runs(log, x) == 1 for x in range(7))
    assert again.rows() == expected_rows(log, range(7))
    # another context (e.g. an edited input file) or code version: nothing reused
    other = run_sweep(T.square, keys(log, range(2)), store=ck, backend="serial", context="v2")
    assert other.n_reused == 0 and T.runs(log, 0) == 2
    newer = run_sweep(T.square, keys(log, range(2)), store=ck, backend="serial", code_version="x")
    assert newer.n_reused == 0 and T.runs(log, 0) == 3


def test_failure_is_retried_once_and_never_stops_the_others(tmp_path):
    log, ck = tmp_path / "log", tmp_path / "ck"
    ks = [{"x": 0, "log": str(log)}, {"x": 1, "log": str(log), "fail": 1},
          {"x": 2, "log": str(log), "fail": 2}, {"x": 3, "log": str(log)}]  # fmt: skip
    r = run_sweep(T.fail_once, ks, store=ck, backend="serial")
    assert r.status is Status.SUCCESS and not r.success and r.n_failed == 1
    by_x = {rec.key["x"]: rec for rec in r.records}
    assert by_x[1].done and by_x[1].attempts == 2 and "planned failure" in by_x[1].errors[0]
    assert not by_x[2].done and by_x[2].attempts == 2 and len(by_x[2].errors) == 2
    assert by_x[2].row()["task_error"] == "ArithmeticError: planned failure of x = 2"
    assert by_x[0].done and by_x[3].done
    # the failure is recorded: a resume keeps it unless asked to retry failed tasks
    assert run_sweep(T.fail_once, ks, store=ck, backend="serial").n_executed == 0
    again = run_sweep(T.fail_once, ks, store=ck, backend="serial", retry_failed=True)
    assert again.n_executed == 2 and again.n_failed == 1
    rec = json.loads(CheckpointStore(ck).path(by_x[2].id).read_text())
    assert rec["status"] == "failed" and rec["errors"][0].startswith("ArithmeticError")


def test_keyboard_interrupt_keeps_finished_tasks(tmp_path):
    log, ck = tmp_path / "log", tmp_path / "ck"
    ks = keys(log, range(6))
    ks[3]["stop"] = True
    r = run_sweep(T.interrupt_at, ks, store=ck, backend="serial")
    assert r.status is Status.INTERRUPTED and not r.success
    assert [rec.key["x"] for rec in r.records] == [0, 1, 2]
    assert [k["x"] for k in r.pending] == [3, 4, 5]
    del ks[3]["stop"]  # another key now: the interrupted task is simply a new one
    resumed = run_sweep(T.interrupt_at, ks, store=ck, backend="serial")
    assert resumed.n_reused == 3 and resumed.n_executed == 3
    assert all(T.runs(log, x) == 1 for x in range(6))


# ----------------------------------------------------------------- real processes
def test_process_pool_survives_a_killed_worker(tmp_path):
    log = tmp_path / "log"
    ks = keys(log, range(6))
    ks[2]["crash"] = True
    r = run_sweep(T.crash_once, ks, store=tmp_path / "ck", backend="processes", workers=2)
    assert r.success, r.message
    rec = {x.key["x"]: x for x in r.records}
    assert rec[2].attempts == 2 and "BrokenProcessPool" in rec[2].errors[0]
    assert len({x.worker for x in r.records}) >= 2  # ran on more than one process
    assert [row["y"] for row in r.rows()] == [x * x for x in range(6)]


@pytest.fixture(scope="module")
def cluster():
    from distributed import LocalCluster

    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
    ) as c:
        yield c


def test_identical_tables_across_backends(tmp_path, cluster):
    log = tmp_path / "log"
    xs = [7, 3, 11, 0, 5, 1, 9, 2]
    ks = [{**k, "sleep": 0.05 * (k["x"] % 3)} for k in keys(log, xs)]  # shuffles completion
    tables = {}
    for name, opts in (
        ("serial", {"backend": "serial"}),
        ("processes", {"backend": "processes", "workers": 2}),
        ("scheduler", {"scheduler": cluster.scheduler_address}),
    ):
        r = run_sweep(T.square, ks, store=tmp_path / name, **opts)
        assert r.success, (name, r.message)
        tables[name] = r.rows()
        csv = r.write_csv(tmp_path / f"{name}.csv").read_text()
        tables[name + ".csv"] = csv
    assert tables["serial"] == tables["processes"] == tables["scheduler"]
    assert tables["serial.csv"] == tables["processes.csv"] == tables["scheduler.csv"]
    assert [row["x"] for row in tables["serial"]] == sorted(xs)


def test_dask_local_cluster_worker_killed_mid_sweep_then_resume(tmp_path):
    log, ck = tmp_path / "log", tmp_path / "ck"
    ks = [{**k, "sleep": 0.1} for k in keys(log, range(8))]
    for k in ks[1::3]:
        k["crash"] = True  # x = 1, 4, 7 kill their worker on the first try
    r = run_sweep(T.crash_once, ks, store=ck, backend="dask", workers=2)
    assert r.success, r.message
    assert r.backend == "dask"
    for rec in r.records:
        if rec.key.get("crash"):
            assert rec.attempts == 2 and rec.errors, rec
    assert [row["y"] for row in r.rows()] == [x * x for x in range(8)]
    # the same table as in the calling process (the crash markers exist now)
    serial = run_sweep(T.crash_once, ks, backend="serial")
    assert serial.rows() == r.rows()
    n_before = {x: T.runs(log, x) for x in range(8)}
    resumed = run_sweep(T.crash_once, ks, store=ck, backend="dask", workers=2)
    assert resumed.n_executed == 0 and resumed.n_reused == 8 and resumed.backend == "none"
    assert {x: T.runs(log, x) for x in range(8)} == n_before
    assert resumed.rows() == r.rows()


# The child restores Python's SIGINT handler: a test run started in the background by a
# non-interactive shell (`cmd &`) inherits SIGINT ignored, and Python then installs no
# handler, so the Ctrl-C this test sends would never arrive (seen in a CI-like run).
_CHILD = """
import signal, sys, json
signal.signal(signal.SIGINT, signal.default_int_handler)
sys.path[:0] = {paths!r}
import sweep_tasks as T
from continuation.sweep import run_sweep
ks = [{{"x": x, "log": {log!r}, "sleep": 0.4}} for x in range(12)]
r = run_sweep(T.square, ks, store={ck!r}, backend="processes", workers=2)
print(json.dumps({{"status": r.status.name, "done": len(r.records), "pending": len(r.pending)}}))
"""


def test_ctrl_c_cancels_pending_and_a_resume_redoes_nothing(tmp_path):
    log, ck = tmp_path / "log", tmp_path / "ck"
    here = str(Path(__file__).parent)
    code = textwrap.dedent(_CHILD.format(paths=[here, os.getcwd()], log=str(log), ck=str(ck)))
    proc = subprocess.Popen(
        [sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    t0 = time.monotonic()

    def finished() -> int:  # checkpoints written (not the temporary ".name.tmp-*" files)
        return sum(not f.name.startswith(".") for f in ck.glob("*.json"))

    while time.monotonic() - t0 < 60 and finished() < 3:
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
    summary = json.loads(out.strip().splitlines()[-1])
    assert summary["status"] == "INTERRUPTED"
    assert 3 <= summary["done"] < 12 and summary["done"] + summary["pending"] == 12
    saved = CheckpointStore(ck).load()
    assert len(saved) == summary["done"]
    finished = {rec["key"]["x"] for rec in saved.values()}
    ks = [{"x": x, "log": str(log), "sleep": 0.4} for x in range(12)]
    resumed = run_sweep(T.square, ks, store=ck, backend="processes", workers=2)
    assert resumed.success and resumed.n_reused == len(finished)
    assert resumed.n_executed == 12 - len(finished)
    for x in finished:  # zero finished tasks redone
        assert T.runs(log, x) == 1
    assert [row["y"] for row in resumed.rows()] == [x * x for x in range(12)]


def test_a_cancelled_process_pool_leaves_no_thread_behind():
    """``close(cancel=True)`` returns with the pool's processes and threads gone (its
    manager and queue-feeder threads), so a process that was single-threaded before
    can fork right after (``ForkedTasks`` refuses with other threads alive). Threads
    of earlier tests (Dask's, which live as long as the process) are not counted."""
    import threading

    from continuation.sweep import open_backend

    before = set(threading.enumerate())
    be = open_backend("processes", workers=2)
    futures = [be.submit(time.sleep, 30.0) for _ in range(5)]
    time.sleep(0.5)
    t0 = time.monotonic()
    be.close(cancel=True)
    assert time.monotonic() - t0 < 20.0
    left = [t.name for t in set(threading.enumerate()) - before]
    assert not left, left
    assert all(f.done() for f in futures)


def test_a_sigint_whose_keyboard_interrupt_was_lost_still_stops_the_sweep(tmp_path):
    """A SIGINT is counted (continuation.sigint) even when its ``KeyboardInterrupt`` is
    lost (raised in a weakref callback, say: only printed): the sweep then stops with
    INTERRUPTED at its next check (every 0.5 s at most) instead of running to the end.
    The lost exception is imitated by counting a SIGINT without raising anything."""
    import threading

    from continuation.sigint import _Sigints

    log = tmp_path / "log"
    ks = [{"x": x, "log": str(log), "sleep": 0.3} for x in range(20)]
    timer = threading.Timer(1.0, lambda: setattr(_Sigints, "count", _Sigints.count + 1))
    timer.start()
    try:
        t0 = time.monotonic()
        r = run_sweep(T.square, ks, store=tmp_path / "ck", backend="processes", workers=2)
    finally:
        timer.cancel()
    # without the count the 20 tasks (3 s on two workers) would all run: SUCCESS
    assert r.status.name == "INTERRUPTED", r.message
    assert len(r.pending) > 0
    assert time.monotonic() - t0 < 1.0 + 0.5 + 5.0  # the check interval and the pool's stop
