"""Embarrassingly parallel sweeps: checkpointed, resumable, on any executor.

:func:`run_sweep` runs ``fn(key)`` for many JSON keys on local processes, a Dask
``LocalCluster`` or a Dask scheduler; each finished task is checkpointed atomically,
keyed by a hash of its inputs, a caller-supplied context and the code version, so an
interrupted sweep resumes without redoing any finished task. Knows nothing of the
application.

Public names: :func:`run_sweep`, :class:`SweepResult`, :class:`TaskRecord`,
:func:`open_backend`, :func:`check_workers` (the one check of a worker count, at most
:data:`MAX_WORKERS`), :class:`CheckpointStore`, :func:`file_digest`,
:func:`source_version`, :func:`task_id`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:  # for type checkers; _EXPORTS is what runs (names imported on first use)
    from .backends import (
        BACKENDS,
        MAX_WORKERS,
        Backend,
        SerialExecutor,
        check_workers,
        default_workers,
        open_backend,
    )
    from .keys import canonical_json, file_digest, source_version, table_order, task_id
    from .run import DONE, FAILED, SweepResult, TaskRecord, execute_task, run_sweep
    from .store import CheckpointStore

#: Sub-module -> the public names it defines (imported on first use: issue 27).
_EXPORTS: dict[str, tuple[str, ...]] = {
    "backends": (
        "BACKENDS",
        "MAX_WORKERS",
        "Backend",
        "SerialExecutor",
        "check_workers",
        "default_workers",
        "open_backend",
    ),
    "keys": ("canonical_json", "file_digest", "source_version", "table_order", "task_id"),
    "run": ("DONE", "FAILED", "SweepResult", "TaskRecord", "execute_task", "run_sweep"),
    "store": ("CheckpointStore",),
}

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
del TYPE_CHECKING, lazy_exports

__all__ = [
    "BACKENDS",
    "DONE",
    "MAX_WORKERS",
    "FAILED",
    "Backend",
    "CheckpointStore",
    "SerialExecutor",
    "SweepResult",
    "TaskRecord",
    "canonical_json",
    "check_workers",
    "default_workers",
    "execute_task",
    "file_digest",
    "open_backend",
    "run_sweep",
    "source_version",
    "table_order",
    "task_id",
]
