"""Result files written atomically, and the marker of an unfinished step.

A result file is first written under a temporary name in the same folder and then
renamed onto its final name (:func:`os.replace` is atomic on POSIX and Windows), so
an interrupted run never leaves a truncated file under a final name.

A step folder holds :data:`INCOMPLETE_MARKER` from the moment its step starts until
its ``summary.json`` is written: a folder with the marker (or without
``summary.json``) is redone by the next run.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

#: File present in a step folder while the step runs (removed when it finished).
INCOMPLETE_MARKER = ".incomplete"


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """A temporary path next to ``path`` (same suffix); renamed onto ``path`` on success.

    On an exception (Ctrl-C included) the temporary file is removed and ``path`` is
    left as it was.
    """
    final = Path(path)
    final.parent.mkdir(parents=True, exist_ok=True)
    tmp = final.with_name(f".{final.stem}.tmp-{os.getpid()}{final.suffix}")
    try:
        yield tmp
        os.replace(tmp, final)
    finally:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()


def write_atomic(path: str | os.PathLike[str], writer: Callable[[Path], Any]) -> Path:
    """Call ``writer(tmp_path)`` and rename the file it wrote onto ``path``; return ``path``."""
    with atomic_path(path) as tmp:
        writer(tmp)
    return Path(path)


def write_atomic_group(folder: str | os.PathLike[str], writer: Callable[[Path], Any]) -> list[Path]:
    """Call ``writer(tmp_folder)``; move every file it wrote there into ``folder``.

    For writers that produce several files from one name (``Branch.save`` writes an
    ``.npz`` and a ``.json`` beside it): each file appears complete or not at all.
    """
    dest = Path(folder)
    dest.mkdir(parents=True, exist_ok=True)
    moved: list[Path] = []
    with tempfile.TemporaryDirectory(prefix=".tmp-", dir=dest) as tmp:
        writer(Path(tmp))
        for f in sorted(Path(tmp).iterdir()):
            os.replace(f, dest / f.name)
            moved.append(dest / f.name)
    return moved


def write_text(path: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` to ``path`` atomically."""
    return write_atomic(path, lambda p: p.write_text(text, encoding="utf-8"))


def write_json(
    path: str | os.PathLike[str], obj: Any, *, default: Callable[[Any], Any] | None = None
) -> Path:
    """Write ``obj`` as indented strict JSON atomically.

    Non-finite floats become ``null``; ``default`` converts other objects (as in
    :func:`json.dumps`).
    """
    from .options import json_safe

    text = json.dumps(json_safe(obj), indent=2, allow_nan=False, default=default)
    return write_text(path, text + "\n")


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


__all__ = [
    "INCOMPLETE_MARKER",
    "atomic_path",
    "is_complete",
    "mark_complete",
    "mark_incomplete",
    "write_atomic",
    "write_atomic_group",
    "write_json",
    "write_text",
]
