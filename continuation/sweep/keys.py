r"""Task identity: canonical JSON of a task's inputs, its hash, the table order.

A task is ``fn(key)`` with ``fn`` a module-level (picklable) function and ``key`` a
JSON-able dict of its inputs. Its identity is

.. math::

    \mathrm{id} = \mathrm{sha256}\big(\mathrm{json}(\{fn, key, context, code\})\big),

with ``context`` a caller-supplied hash of everything outside the key that the result
depends on (e.g. the content of an input file) and ``code`` the code version
(:func:`source_version` by default): a finished task is reused only when all four match.
"""

from __future__ import annotations

import hashlib
import importlib
import json
import math
import sys
from collections.abc import Callable, Mapping, Sequence
from functools import lru_cache
from pathlib import Path
from typing import Any


def function_name(fn: Callable[..., Any]) -> str:
    """``module:qualname`` of a module-level function.

    Raises
    ------
    ValueError
        If ``fn`` is not callable or is a lambda / nested function (not picklable by
        reference, so not runnable on another process or machine).
    """
    if not callable(fn):
        raise ValueError(f"`fn` must be a callable, got {type(fn).__name__}")
    mod = getattr(fn, "__module__", None)
    qual = getattr(fn, "__qualname__", None)
    if not mod or not qual or "<lambda>" in qual or "<locals>" in qual:
        raise ValueError(
            f"`fn` must be a module-level function (picklable by reference), got {fn!r}"
        )
    return f"{mod}:{qual}"


def _check_json(value: Any, where: str) -> None:
    if value is None or isinstance(value, (bool, str)):
        return
    if isinstance(value, int):
        return
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"`{where}` must be finite, got {value!r}")
        return
    if isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            _check_json(v, f"{where}[{i}]")
        return
    if isinstance(value, Mapping):
        for k, v in value.items():
            if not isinstance(k, str):
                raise ValueError(f"`{where}` keys must be strings, got {k!r}")
            _check_json(v, f"{where}.{k}")
        return
    raise ValueError(
        f"`{where}` must hold only JSON values (str, int, float, bool, None, list, dict), "
        f"got {type(value).__name__}"
    )


def check_key(key: Any, where: str = "key") -> dict[str, Any]:
    """Validate a task key: a non-empty dict of finite JSON values; returns a plain copy.

    Raises
    ------
    ValueError
        Naming the offending field.
    """
    if not isinstance(key, Mapping) or not key:
        raise ValueError(f"`{where}` must be a non-empty dict of JSON values, got {key!r}")
    _check_json(key, where)
    return json.loads(json.dumps(key, allow_nan=False))  # plain types, the caller's order


def canonical_json(value: Any) -> str:
    """Compact JSON with sorted keys (one text for one value)."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), allow_nan=False)


def task_id(fn_name: str, key: Mapping[str, Any], context: str, code_version: str) -> str:
    """Hex digest (32 chars) of the task's inputs, context and code version."""
    text = canonical_json({"fn": fn_name, "key": key, "context": context, "code": code_version})
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def _rank(v: Any) -> tuple[Any, ...]:
    if v is None:
        return (0,)
    if isinstance(v, bool):
        return (1, int(v))
    if isinstance(v, (int, float)):
        return (2, float(v))
    if isinstance(v, str):
        return (3, v)
    if isinstance(v, (list, tuple)):
        return (4, tuple(_rank(x) for x in v))
    return (5, canonical_json(v))


def table_order(keys: Sequence[Mapping[str, Any]]) -> Callable[[Mapping[str, Any]], tuple]:
    """Sort key for task keys: their fields in first-appearance order, numbers numerically.

    A field missing from a key sorts first; ties are broken by the canonical JSON, so
    the order depends on the keys only (never on completion order).
    """
    fields: list[str] = []
    for k in keys:
        for name in k:
            if name not in fields:
                fields.append(name)

    def order(key: Mapping[str, Any]) -> tuple:
        return (
            tuple((0,) if f not in key else (1, _rank(key[f])) for f in fields),
            canonical_json(key),
        )

    return order


@lru_cache(maxsize=64)
def _package_digest(name: str) -> str:
    mod = sys.modules.get(name) or importlib.import_module(name)
    file = getattr(mod, "__file__", None)
    if file is None:
        return "nofile"
    path = Path(file)
    files = sorted(path.parent.rglob("*.py")) if path.name == "__init__.py" else [path]
    h = hashlib.sha256()
    for f in files:
        h.update(str(f.relative_to(path.parent)).encode())
        h.update(f.read_bytes())
    return h.hexdigest()[:16]


def source_version(fn: Callable[..., Any], *packages: str) -> str:
    """Code version: a digest of the source of ``fn``'s top-level package and ``packages``.

    Every ``.py`` file of the package that defines ``fn`` (the file itself for a
    top-level module), and of each further package named, is hashed: any edit of that
    code gives a new version, so no stale result is reused.

    Returns
    -------
    str
        ``"name=digest;..."`` in a fixed order.
    """
    top = function_name(fn).split(":")[0].split(".")[0]
    names = sorted({top, *packages})
    return ";".join(f"{n}={_package_digest(n)}" for n in names)


def file_digest(path: str | Path) -> str:
    """sha256 of a file's content (a ``context`` for tasks that read it)."""
    p = Path(path)
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise ValueError(f"`path` cannot be read: {p} ({exc.strerror})") from None
    return hashlib.sha256(data).hexdigest()


__all__ = [
    "canonical_json",
    "check_key",
    "file_digest",
    "function_name",
    "source_version",
    "table_order",
    "task_id",
]
