"""The memo of the expensive estimation steps: a rebuild with one coefficient changed
recomputes only what depends on it (:func:`reuse_hydrostatics`)."""

from __future__ import annotations

import contextlib
import inspect
import pickle
from collections.abc import Callable, Iterator
from contextvars import ContextVar
from typing import Any

import numpy as np

from ..hydro.resistance import fit_resistance


class _Memo:
    """Results of the expensive estimation steps keyed by their exact inputs."""

    def __init__(self) -> None:
        self.store: dict[bytes, Any] = {}
        self.stats = {"hits": 0, "misses": 0}

    def get(self, key: bytes, make: Callable[[], Any]) -> Any:
        if key in self.store:
            self.stats["hits"] += 1
            return self.store[key]
        self.stats["misses"] += 1
        out = self.store[key] = make()
        return out


_MEMO: ContextVar[_Memo | None] = ContextVar("broachkit_estimation_memo", default=None)


@contextlib.contextmanager
def reuse_hydrostatics() -> Iterator[dict[str, int]]:
    """Inside the context, rebuilds reuse the expensive steps with identical inputs.

    :func:`~ship_models.estimation.build_vessel_model` computes the GZ curve
    (``gz_curve``), the IS-Code topside fit (``marginal_topside_height``; together
    about 1.3 s of a 1.5 s build) and the resistance spline (``fit_resistance``)
    through a memo keyed by their exact inputs (the pickled hull form with all its
    arrays, GM and the keywords; for the spline the resistance's values on the fit's
    own sample grid), so a rebuild with one coefficient changed recomputes only what
    depends on it. Yields ``{"hits": .., "misses": ..}`` (updated as the context
    runs). Nested contexts share the outer memo.
    """
    outer = _MEMO.get()
    if outer is not None:
        yield outer.stats
        return
    memo = _Memo()
    token = _MEMO.set(memo)
    try:
        yield memo.stats
    finally:
        _MEMO.reset(token)


def memo_call(name: str, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
    """``fn(*args, **kwargs)`` through the in-process memo (inside
    :func:`reuse_hydrostatics`) and the disk cache (:mod:`ship_models.disk_cache`)."""
    from ..disk_cache import cached_call

    memo = _MEMO.get()
    if memo is None:
        return cached_call(name, fn, *args, **kwargs)
    key = pickle.dumps((name, args, sorted(kwargs.items())), protocol=4)
    return memo.get(key, lambda: cached_call(name, fn, *args, **kwargs))


def memo_fit(fun: Callable[[Any], Any], u_max: float, knot_spacing: float, **kwargs: Any) -> Any:
    """:func:`~ship_models.hydro.resistance.fit_resistance` through the in-process memo,
    keyed by ``fun``'s values on the fit's own sample grid."""
    memo = _MEMO.get()
    if memo is None:
        return fit_resistance(fun, u_max, knot_spacing, **kwargs)
    n_default = inspect.signature(fit_resistance).parameters["n_samples"].default
    u = np.linspace(0.0, u_max, int(kwargs.get("n_samples", n_default)))
    R = np.asarray(fun(u), dtype=float)  # the fit depends on ``fun`` only through these
    key = pickle.dumps(("fit_resistance", R, float(u_max), float(knot_spacing),
                        sorted(kwargs.items())), protocol=4)  # fmt: skip
    return memo.get(key, lambda: fit_resistance(fun, u_max, knot_spacing, **kwargs))
