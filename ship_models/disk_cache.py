"""Results of expensive, deterministic estimation steps kept on disk between processes.

Building a vessel model computes its GZ curve by direct integration at some 460 heel
angles (about 0.6 s): every ``broachkit`` query paid it again. :func:`cached_call`
keeps such a result on disk under a key made of everything it depends on: the step's
name, its pickled arguments and the source code of ``ship_models/hydro`` (where the
hydrostatics are computed) and of the function's own module (a code change is a new
key, never a stale hit). A damaged or unreadable entry is
recomputed. The directory is ``$BROACHKIT_CACHE_DIR/estimation`` (default
``~/.cache/broachkit/estimation``); ``BROACHKIT_CACHE=0`` switches the cache off.
"""

from __future__ import annotations

import contextlib
import hashlib
import inspect
import logging
import os
import pickle
from collections.abc import Callable
from functools import lru_cache
from pathlib import Path
from typing import Any, TypeVar

from continuation.atomic import atomic_path

log = logging.getLogger(__name__)

R = TypeVar("R")


def cache_root() -> Path:
    """``$BROACHKIT_CACHE_DIR/estimation`` or ``~/.cache/broachkit/estimation``."""
    base = os.environ.get("BROACHKIT_CACHE_DIR") or str(Path.home() / ".cache" / "broachkit")
    return Path(base) / "estimation"


@lru_cache(maxsize=64)
def _source_digest(module: str) -> str:
    import sys

    h = hashlib.sha256()
    for f in sorted((Path(__file__).parent / "hydro").glob("*.py")):
        h.update(f.read_bytes())
    mod = sys.modules.get(module)
    try:
        h.update(inspect.getsource(mod).encode() if mod is not None else module.encode())
    except (OSError, TypeError):
        h.update(module.encode())
    return h.hexdigest()[:16]


def cached_call(name: str, fn: Callable[..., R], *args: Any, **kwargs: Any) -> R:
    """``fn(*args, **kwargs)``, from the disk cache when the same inputs were seen.

    Parameters
    ----------
    name : str
        Name of the step (part of the key).
    fn : callable
        A deterministic function of picklable arguments with a picklable result.
    *args, **kwargs
        Its arguments.

    Returns
    -------
    object
        The result (a fresh unpickled copy on a hit).
    """
    if os.environ.get("BROACHKIT_CACHE", "1") == "0":
        return fn(*args, **kwargs)
    try:
        blob = pickle.dumps((name, args, sorted(kwargs.items())), protocol=4)
    except (pickle.PicklingError, TypeError, AttributeError):
        return fn(*args, **kwargs)
    key = hashlib.sha256(blob + _source_digest(fn.__module__).encode()).hexdigest()
    path = cache_root() / f"{name}-{key[:32]}.pkl"
    if path.is_file():
        try:
            with open(path, "rb") as fh:
                return pickle.load(fh)
        except Exception:  # noqa: BLE001 - a damaged entry is recomputed
            log.debug("cache entry %s unreadable; recomputed", path)
    out = fn(*args, **kwargs)
    with contextlib.suppress(OSError):
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(path) as tmp, open(tmp, "wb") as fh:  # readers see all or nothing
            pickle.dump(out, fh, protocol=4)
    return out


__all__ = ["cache_root", "cached_call"]
