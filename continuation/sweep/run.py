r"""Run a sweep of independent tasks ``fn(key)`` on any executor, checkpointed and resumable.

:func:`run_sweep` submits every task whose checkpoint is missing, keeping at most
``backend.slots`` in flight, and writes each result to the store as it arrives. A task
that raises, or whose worker dies, is retried ``retries`` times (once by default) and
then recorded as failed with its errors; it never stops the others. The final table is
the records sorted by key (:func:`~continuation.sweep.keys.table_order`), values
round-tripped through JSON, so it is the same whichever backend ran it and in whatever
order the tasks finished. ``KeyboardInterrupt`` cancels what is pending, stops the
workers the sweep started, and returns the finished part (``Status.INTERRUPTED``);
running the same sweep again resumes it.
"""

from __future__ import annotations

import concurrent.futures as cf
import csv
import dataclasses
import json
import logging
import math
import os
import socket
import sys
import time
import traceback
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..sigint import sigint_recorded, sigints_counted
from ..status import Status
from .backends import Backend, configure_worker_logging, open_backend
from .keys import check_key, function_name, source_version, table_order, task_id
from .store import CheckpointStore

log = logging.getLogger(__name__)

DONE, FAILED = "done", "failed"


def execute_task(fn: Callable[[dict[str, Any]], Any], key: dict[str, Any]) -> dict[str, Any]:
    """Run one task in a worker; exceptions become a failed outcome, never escape.

    The value must be JSON-serialisable (NaN allowed); it is returned round-tripped
    through JSON, so every backend hands back exactly the same value.

    Returns
    -------
    dict
        ``{"ok", "value" | "error" + "traceback", "elapsed_s", "worker"}``.
    """
    configure_worker_logging()  # a Dask worker has no pool initializer to do it
    t0 = time.perf_counter()
    worker = f"{socket.gethostname()}:{os.getpid()}"
    try:
        value = json.loads(json.dumps(fn(dict(key))))
    except Exception as exc:
        return {
            "ok": False,
            "error": f"{type(exc).__name__}: {exc}",
            "traceback": traceback.format_exc(limit=20),
            "elapsed_s": time.perf_counter() - t0,
            "worker": worker,
        }
    return {"ok": True, "value": value, "elapsed_s": time.perf_counter() - t0, "worker": worker}


@dataclass(frozen=True)
class TaskRecord:
    """The outcome of one task.

    Attributes
    ----------
    id : str
        Hash of function, key, context and code version.
    key : dict
        The task's inputs.
    status : str
        ``"done"`` or ``"failed"``.
    value : Any
        The task's JSON value (``None`` when failed).
    errors : tuple of str
        One line per failed attempt (exception or dead worker).
    attempts : int
    elapsed_s : float
        Run time of the successful (or last) attempt.
    worker : str
        ``host:pid`` of that attempt.
    reused : bool
        Loaded from a checkpoint instead of run in this call.
    """

    id: str
    key: dict[str, Any]
    status: str
    value: Any
    errors: tuple[str, ...]
    attempts: int
    elapsed_s: float = math.nan
    worker: str = ""
    reused: bool = False

    @property
    def done(self) -> bool:
        """The task finished with a value."""
        return self.status == DONE

    def row(self) -> dict[str, Any]:
        """Table row: key fields, value fields (a dict value is spread), status, error."""
        v = self.value
        vals = dict(v) if isinstance(v, Mapping) else ({"value": v} if self.done else {})
        return {
            **self.key,
            **vals,
            "task_status": self.status,
            "task_error": "" if self.done else (self.errors[-1] if self.errors else ""),
        }

    def to_json(self) -> dict[str, Any]:
        """JSON-ready record (as stored): every field but ``reused``, in field order."""
        rec = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        del rec["reused"]
        rec["errors"] = list(self.errors)
        return rec


@dataclass(frozen=True, eq=False)
class SweepResult:
    """All tasks of a sweep, in table order.

    Attributes
    ----------
    records : tuple of TaskRecord
        Finished tasks (done or failed), sorted by key.
    pending : tuple of dict
        Keys not finished (only after an interruption), sorted by key.
    status : Status
        ``SUCCESS`` when every task finished (done *or* failed: see :attr:`success`),
        ``INTERRUPTED`` otherwise.
    n_tasks : int
    n_reused : int
        Tasks taken from checkpoints.
    n_executed : int
        Task attempts run in this call (retries included).
    backend : str
    elapsed_s : float
    """

    records: tuple[TaskRecord, ...]
    pending: tuple[dict[str, Any], ...]
    status: Status
    n_tasks: int
    n_reused: int
    n_executed: int
    backend: str
    elapsed_s: float = 0.0
    message: str = field(default="")

    @property
    def n_failed(self) -> int:
        """Tasks that failed after their retries."""
        return sum(not r.done for r in self.records)

    @property
    def success(self) -> bool:
        """Every task finished with a value."""
        return self.status is Status.SUCCESS and self.n_failed == 0

    def rows(self) -> list[dict[str, Any]]:
        """The table: :meth:`TaskRecord.row` of every finished task, in key order."""
        return [r.row() for r in self.records]

    def values(self) -> list[Any]:
        """Values of the finished tasks in key order (``None`` for failed ones)."""
        return [r.value for r in self.records]

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary with every record."""
        return {
            "status": self.status.name,
            "message": self.message,
            "n_tasks": self.n_tasks,
            "n_done": len(self.records) - self.n_failed,
            "n_failed": self.n_failed,
            "n_reused": self.n_reused,
            "n_executed": self.n_executed,
            "backend": self.backend,
            "elapsed_s": self.elapsed_s,
            "records": [r.to_json() for r in self.records],
            "pending": list(self.pending),
        }

    def write_csv(self, path: str | os.PathLike[str]) -> Path:
        """Write :meth:`rows` as CSV, atomically (columns in first-appearance order)."""
        from ..atomic import atomic_path

        rows = self.rows()
        cols: list[str] = []
        for r in rows:
            cols.extend(c for c in r if c not in cols)
        p = Path(path)
        with atomic_path(p) as tmp, tmp.open("w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(cols)
            for r in rows:
                w.writerow([_cell(r.get(c, "")) for c in cols])
        return p


def _cell(v: Any) -> Any:
    if isinstance(v, (list, dict)):
        return json.dumps(v, sort_keys=True)
    if v is None:
        return ""
    if isinstance(v, float):
        return repr(v)
    return v


class _NoBar:
    """The progress bar when it is off.

    No tqdm object, hence no tqdm monitor thread left running in the caller's process
    (a process that forks later must have one thread).
    """

    def update(self, n: int = 1) -> None:
        """Nothing to show."""

    def close(self) -> None:
        """Nothing to close."""


def _progress_bar(enabled: bool | None, total: int, initial: int, desc: str) -> Any:
    if enabled is None:
        enabled = sys.stderr.isatty()
    if not enabled:
        return _NoBar()
    from tqdm.auto import tqdm

    return tqdm(
        total=total, initial=initial, desc=desc, unit="task", disable=not enabled,
        file=sys.stderr, dynamic_ncols=True, smoothing=0.1,
    )  # fmt: skip


def _from_json(rec: Mapping[str, Any], key: dict[str, Any]) -> TaskRecord:
    return TaskRecord(
        rec["id"], key, rec["status"], rec.get("value"),
        tuple(rec.get("errors", ())), int(rec.get("attempts", 1)),
        float(rec.get("elapsed_s", math.nan)), str(rec.get("worker", "")), True,
    )  # fmt: skip


def run_sweep(
    fn: Callable[[dict[str, Any]], Any],
    keys: Iterable[Mapping[str, Any]],
    *,
    store: str | os.PathLike[str] | None = None,
    context: str = "",
    code_version: str | None = None,
    backend: str | cf.Executor | Any = "processes",
    workers: int | None = None,
    scheduler: str | None = None,
    retries: int = 1,
    retry_failed: bool = False,
    progress: bool | None = None,
    desc: str = "sweep",
) -> SweepResult:
    """Run ``fn(key)`` for every key, in parallel, checkpointed, resumable.

    Parameters
    ----------
    fn : callable
        A module-level function ``fn(key: dict) -> JSON value`` (picklable by
        reference: it runs in other processes or on other machines). Return ``None``
        rather than NaN for a missing number: NaN is kept, but ``nan != nan`` makes
        equal tables compare unequal.
    keys : iterable of dict
        The tasks' inputs: non-empty dicts of finite JSON values, all different.
    store : path, optional
        Checkpoint directory (:class:`~continuation.sweep.store.CheckpointStore`);
        without it nothing is saved or resumed.
    context : str
        A hash of everything else the results depend on (e.g.
        :func:`~continuation.sweep.keys.file_digest` of an input file).
    code_version : str, optional
        Default :func:`~continuation.sweep.keys.source_version` of ``fn``'s package and
        ``continuation``.
    backend, workers, scheduler
        Where to run (:func:`~continuation.sweep.backends.open_backend`).
    retries : int
        Further attempts of a task that failed (exception or dead worker).
    retry_failed : bool
        Also rerun tasks whose checkpoint records a failure (default: keep them).
    progress : bool, optional
        tqdm bar (done/total, rate, time left) on stderr; default only on a terminal.
    desc : str
        Label of the bar and of log messages.

    Returns
    -------
    SweepResult

    Raises
    ------
    ValueError
        For a bad ``fn``, key, duplicate keys, ``retries``, backend or store.
    """
    t_start = time.perf_counter()
    name = function_name(fn)
    if isinstance(retries, bool) or not isinstance(retries, int) or retries < 0:
        raise ValueError(f"`retries` must be a non-negative integer, got {retries!r}")
    if not isinstance(context, str):
        raise ValueError(f"`context` must be a string (a hash), got {type(context).__name__}")
    key_list = [check_key(k, f"keys[{i}]") for i, k in enumerate(keys)]
    code = source_version(fn, "continuation") if code_version is None else str(code_version)
    ids = [task_id(name, k, context, code) for k in key_list]
    if len(set(ids)) != len(ids):
        raise ValueError("`keys` must all be different (two tasks have the same inputs)")
    order = table_order(key_list)
    st = CheckpointStore(store) if store is not None else None
    saved = st.load() if st is not None else {}
    finished: dict[str, TaskRecord] = {}
    for tid, k in zip(ids, key_list, strict=True):
        rec = saved.get(tid)
        if rec is None or rec.get("key") != k or rec.get("status") not in (DONE, FAILED):
            continue
        if rec["status"] == FAILED and retry_failed:
            continue
        finished[tid] = _from_json(rec, k)  # the caller's field order
    todo = [(tid, k) for tid, k in zip(ids, key_list, strict=True) if tid not in finished]
    n_reused = len(finished)
    log.info("%s: %d tasks, %d from checkpoints, %d to run", desc, len(ids), n_reused, len(todo))
    n_executed = 0
    status = Status.SUCCESS
    bar = _progress_bar(progress, len(ids), n_reused, desc)
    be: Backend | None = None
    clean = False
    try:
        # every SIGINT is counted: one whose KeyboardInterrupt is lost (raised in a
        # weakref callback of the pool, say) still stops the sweep (continuation.sigint)
        with sigint_recorded():
            n_sigint = sigints_counted()
            if todo:
                be = open_backend(backend, workers=workers, scheduler=scheduler)
                n_executed = _drive(
                    be, fn, todo, retries, name, code, context, st, finished, bar, n_sigint
                )
        clean = True
    except KeyboardInterrupt:
        status = Status.INTERRUPTED
        log.warning("%s interrupted: %d of %d tasks finished", desc, len(finished), len(ids))
    finally:
        bar.close()
        if be is not None:  # on an interruption or error: cancel, stop the workers
            be.close(cancel=not clean)
    records = tuple(sorted(finished.values(), key=lambda r: order(r.key)))
    pending = tuple(sorted((k for t, k in todo if t not in finished), key=order))
    n_failed = sum(not r.done for r in records)
    msg = (
        f"{len(records) - n_failed}/{len(ids)} done, {n_failed} failed, {len(pending)} pending; "
        f"{n_reused} from checkpoints, {n_executed} attempts run"
    )
    return SweepResult(
        records, pending, status, len(ids), n_reused, n_executed,
        be.name if be is not None else "none", time.perf_counter() - t_start, msg,
    )  # fmt: skip


def _drive(
    be: Backend,
    fn: Callable[..., Any],
    todo: list[tuple[str, dict[str, Any]]],
    retries: int,
    name: str,
    code: str,
    context: str,
    st: CheckpointStore | None,
    finished: dict[str, TaskRecord],
    bar: Any,
    n_sigint: int | None = None,
) -> int:
    """Keep ``be.slots`` tasks in flight until all finished; returns the attempts run.

    Raises ``KeyboardInterrupt`` when :func:`~continuation.sigint.sigints_counted` has
    moved from ``n_sigint`` (a SIGINT whose own exception was lost).
    """
    queue = [tid for tid, _ in reversed(todo)]  # pop() from the end: first key first
    errors: dict[str, list[str]] = {tid: [] for tid, _ in todo}
    keys = dict(todo)
    flight: dict[cf.Future, tuple[str, int]] = {}
    n_exec = 0
    try:
        while queue or flight:
            # no more in flight than can run now (fewer while a dead worker is replaced;
            # one when none is up, which then waits in the executor as before)
            room = max(be.capacity(), 0 if flight else 1) if queue else 0
            while queue and len(flight) < room:
                tid = queue.pop()
                fut = be.submit(execute_task, fn, keys[tid])
                flight[fut] = (tid, be.generation)
                n_exec += 1
            done, _ = cf.wait(list(flight), timeout=0.5, return_when=cf.FIRST_COMPLETED)
            if n_sigint is not None and sigints_counted() != n_sigint:
                raise KeyboardInterrupt
            broken = False
            for fut in done:
                tid, gen = flight.pop(fut)
                try:
                    out = fut.result()
                except cf.CancelledError:
                    out = {"ok": False, "error": "CancelledError: the task was cancelled"}
                except Exception as exc:  # a dead worker, a task that cannot be sent, ...
                    # the pool these tasks ran on died: replace it (once, not per task)
                    broken |= isinstance(exc, cf.BrokenExecutor) and gen == be.generation
                    out = {"ok": False, "error": f"worker failure: {type(exc).__name__}: {exc}"}
                if out["ok"]:
                    rec = TaskRecord(
                        tid, keys[tid], DONE, out["value"], tuple(errors[tid]),
                        len(errors[tid]) + 1, out["elapsed_s"], out["worker"],
                    )  # fmt: skip
                else:
                    errors[tid].append(out["error"])
                    log.warning("task %s failed: %s", keys[tid], out["error"])
                    if len(errors[tid]) <= retries:
                        queue.append(tid)  # next to be submitted
                        continue
                    rec = TaskRecord(
                        tid, keys[tid], FAILED, None, tuple(errors[tid]), len(errors[tid]),
                        out.get("elapsed_s", math.nan), out.get("worker", ""),
                    )  # fmt: skip
                if st is not None:
                    st.save({**rec.to_json(), "fn": name, "code": code, "context": context})
                finished[tid] = rec
                bar.update(1)
            if broken:
                be.recover()
    except BaseException:
        for fut in flight:
            fut.cancel()
        raise
    return n_exec


__all__ = ["DONE", "FAILED", "SweepResult", "TaskRecord", "execute_task", "run_sweep"]
