"""Checkpoints of finished tasks: one JSON file per task, written atomically.

Each record is written to a temporary file in the same directory and moved into place
(:mod:`continuation.atomic`, atomic on POSIX and Windows), so a sweep killed at any moment
leaves every checkpoint either complete or absent -- never half written. Records are
written by the process that runs the sweep (not by the workers), so remote workers
need no shared file system.
"""

from __future__ import annotations

import json
import logging
import os
from pathlib import Path
from typing import Any

from ..atomic import write_text

log = logging.getLogger(__name__)

#: Version of the record layout.
RECORD_FORMAT = 1


class CheckpointStore:
    """A directory of task records ``<task_id>.json``.

    Parameters
    ----------
    directory : str or Path
        Created if missing.

    Raises
    ------
    ValueError
        If ``directory`` exists and is not a directory, or cannot be created.
    """

    def __init__(self, directory: str | os.PathLike[str]) -> None:
        self.directory = Path(directory)
        try:
            self.directory.mkdir(parents=True, exist_ok=True)
        except (FileExistsError, NotADirectoryError):
            raise ValueError(
                f"`store` must be a directory, got the file {self.directory}"
            ) from None
        except OSError as exc:
            raise ValueError(f"`store` cannot be created: {self.directory} ({exc})") from None

    def path(self, task_id: str) -> Path:
        """File of one task's record."""
        return self.directory / f"{task_id}.json"

    def load(self) -> dict[str, dict[str, Any]]:
        """Every readable record, by task id (unreadable files are skipped with a warning)."""
        out: dict[str, dict[str, Any]] = {}
        for f in sorted(self.directory.glob("*.json")):
            if f.name.startswith("."):  # a temporary file being written
                continue
            try:
                rec = json.loads(f.read_text())
            except (OSError, ValueError) as exc:
                log.warning("skipping unreadable checkpoint %s: %s", f, exc)
                continue
            if not isinstance(rec, dict) or rec.get("id") != f.stem:
                log.warning("skipping checkpoint %s: not a task record", f)
                continue
            out[f.stem] = rec
        return out

    def save(self, record: dict[str, Any]) -> Path:
        """Write one record atomically (:func:`continuation.atomic.write_text`, fsynced)."""
        target = self.path(record["id"])
        text = json.dumps({"format": RECORD_FORMAT, **record}, indent=1)
        write_text(target, text, fsync=True)
        return target


__all__ = ["RECORD_FORMAT", "CheckpointStore"]
