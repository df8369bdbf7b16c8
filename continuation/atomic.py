"""Files written atomically: the one place the project renames a finished file into place.

A file is first written under a temporary name in the same folder and then renamed
onto its final name (:func:`os.replace` is atomic on POSIX and Windows), so a reader, a
concurrent process or an interrupted run never sees a truncated file under a final
name. Used by the sweep checkpoints, the compiled-function cache, the studies and the
command line (which import it from here: no package imports upwards for it).

- :func:`atomic_path` -- a temporary path, renamed onto the final one on success.
- :func:`replace` -- rename a finished file onto its final name.
- :func:`write_atomic` / :func:`write_atomic_group` -- a writer's file(s), atomically.
- :func:`write_text` / :func:`write_json` -- text and strict JSON (NaN -> ``null``).
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import secrets
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any


def replace(src: str | os.PathLike[str], dst: str | os.PathLike[str]) -> None:
    """Rename the finished file ``src`` onto ``dst`` atomically (same file system)."""
    os.replace(src, dst)


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str], *, fsync: bool = False) -> Iterator[Path]:
    """A temporary path next to ``path`` (same suffix), renamed onto ``path`` on success.

    On an exception (Ctrl-C included) the temporary file is removed and ``path`` is
    left as it was. ``fsync=True`` flushes the file to disk before the rename (for
    records that must survive a machine crash, e.g. sweep checkpoints).
    """
    final = Path(path)
    final.parent.mkdir(parents=True, exist_ok=True)
    token = f"{os.getpid()}-{secrets.token_hex(4)}"
    tmp = final.with_name(f".{final.stem}.tmp-{token}{final.suffix}")
    try:
        yield tmp
        if fsync:
            with tmp.open("rb+") as fh:
                os.fsync(fh.fileno())
        replace(tmp, final)
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
            replace(f, dest / f.name)
            moved.append(dest / f.name)
    return moved


def write_text(path: str | os.PathLike[str], text: str, *, fsync: bool = False) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    with atomic_path(path, fsync=fsync) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def json_safe(obj: Any) -> Any:
    """``obj`` with every non-finite float replaced by ``None`` (strict JSON has no NaN).

    NumPy arrays and scalars (anything with ``tolist``) become lists and Python numbers.
    """
    if hasattr(obj, "tolist"):
        obj = obj.tolist()
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: json_safe(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [json_safe(v) for v in obj]
    return obj


def write_json(
    path: str | os.PathLike[str],
    obj: Any,
    *,
    default: Callable[[Any], Any] | None = None,
    indent: int = 2,
) -> Path:
    """Write ``obj`` as indented strict JSON atomically.

    Non-finite floats become ``null``; ``default`` converts other objects (as in
    :func:`json.dumps`).
    """
    text = json.dumps(json_safe(obj), indent=indent, allow_nan=False, default=default)
    return write_text(path, text + "\n")


__all__ = [
    "atomic_path",
    "json_safe",
    "replace",
    "write_atomic",
    "write_atomic_group",
    "write_json",
    "write_text",
]
