"""The marker of an unfinished step; the atomic writes of :mod:`continuation.atomic`.

Result files are written atomically by the library's one implementation
(:mod:`continuation.atomic`, re-exported here for the commands).

A step folder holds :data:`INCOMPLETE_MARKER` from the moment its step starts until
its ``summary.json`` is written: a folder with the marker (or without
``summary.json``) is redone by the next run.
"""

from __future__ import annotations

import contextlib
import csv
import io
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from continuation.atomic import (
        atomic_path,
        write_atomic,
        write_atomic_group,
        write_json,
        write_text,
    )

#: Names re-exported from :mod:`continuation.atomic` (imported on first use, so the
#: command line starts without importing the engine).
_ATOMIC = ("atomic_path", "write_atomic", "write_atomic_group", "write_json", "write_text")


def __getattr__(name: str) -> Any:
    if name in _ATOMIC:
        from continuation import atomic

        return getattr(atomic, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


#: File present in a step folder while the step runs (removed when it finished).
INCOMPLETE_MARKER = ".incomplete"


def mark_incomplete(folder: Path) -> None:
    """Put the unfinished-step marker into ``folder`` (created)."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / INCOMPLETE_MARKER).write_text("this step did not finish; a rerun redoes it\n")


def mark_complete(folder: Path) -> None:
    """Remove the marker of :func:`mark_incomplete`."""
    with contextlib.suppress(FileNotFoundError):
        (folder / INCOMPLETE_MARKER).unlink()


def is_complete(folder: Path, summary: str = "summary.json") -> bool:
    """Whether the step in ``folder`` finished: its summary exists and no marker."""
    return (folder / summary).is_file() and not (folder / INCOMPLETE_MARKER).exists()


def csv_text(columns: Mapping[str, Any], meta: Mapping[str, Any]) -> str:
    """CSV text of equal-length ``columns`` (header = their names), after one
    ``# key: value`` line per entry of ``meta``; values as ``repr(float)`` (exact)."""
    buf = io.StringIO()
    for k, v in meta.items():
        buf.write(f"# {k}: {v}\n")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(list(columns))
    for row in zip(*columns.values(), strict=True):
        w.writerow([repr(float(v)) for v in row])
    return buf.getvalue()


__all__ = [
    "INCOMPLETE_MARKER",
    "atomic_path",
    "csv_text",
    "is_complete",
    "mark_complete",
    "mark_incomplete",
    "write_atomic",
    "write_atomic_group",
    "write_json",
    "write_text",
]
