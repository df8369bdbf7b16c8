"""The 4-DOF model rebuilt with some coefficients and factors changed, cheaply."""

from __future__ import annotations

import contextlib
import inspect
import pickle
from collections.abc import Callable, Iterator, Mapping
from typing import Any

import numpy as np

from continuation.typing import FloatArray

from ... import estimation as _estimation
from ...estimation import build_vessel_model
from ...umeda_4dof import Umeda4DOF
from ...vessel import Coefficient, VesselData
from .factors import _KT, _with_factors

#: Hydrostatic computations of the estimation that dominate a rebuild (the GZ curve and
#: the IS-Code topside fit: about 1.3 s of 1.5 s); most coefficients leave their inputs
#: (hull, GM, heel step) unchanged, so a rebuild at theta +- h reuses them.
_HYDROSTATIC_CALLS = ("gz_curve", "marginal_topside_height")


@contextlib.contextmanager
def reuse_hydrostatics() -> Iterator[dict[str, int]]:
    """Memoise the estimation's hydrostatic calls on their exact arguments.

    Inside the context, :func:`ship_models.estimation.build_vessel_model` calls
    ``gz_curve`` and ``marginal_topside_height`` through a cache keyed by the pickled
    arguments (the hull form with all its arrays, ``GM`` and the keywords), so a call
    with bit-identical inputs returns the earlier result and any changed input (a
    hull dimension, GM, the heel step) recomputes; likewise ``fit_resistance``, keyed
    by the resistance's values on the fit's own sample grid (what the fit depends on).
    Yields ``{"hits": .., "misses": ..}``.
    """
    stats = {"hits": 0, "misses": 0}
    saved = {name: getattr(_estimation, name) for name in _HYDROSTATIC_CALLS}

    def cached(name: str, fn: Callable[..., Any]) -> Callable[..., Any]:
        store: dict[bytes, Any] = {}

        def call(*args: Any, **kwargs: Any) -> Any:
            key = pickle.dumps((args, sorted(kwargs.items())), protocol=4)
            if key in store:
                stats["hits"] += 1
                return store[key]
            stats["misses"] += 1
            out = store[key] = fn(*args, **kwargs)
            return out

        call.__name__ = name
        return call

    fit = _estimation.fit_resistance
    n_default = inspect.signature(fit).parameters["n_samples"].default
    fits: dict[bytes, Any] = {}

    def cached_fit(fun: Callable[[FloatArray], FloatArray], u_max: float,
                   knot_spacing: float, **kwargs: Any) -> Any:  # fmt: skip
        # the fit depends on ``fun`` only through its values on its sample grid
        u = np.linspace(0.0, u_max, int(kwargs.get("n_samples", n_default)))
        R = np.asarray(fun(u), dtype=float)
        key = pickle.dumps((R, float(u_max), float(knot_spacing), sorted(kwargs.items())))
        if key in fits:
            stats["hits"] += 1
            return fits[key]
        stats["misses"] += 1
        out = fits[key] = fit(fun, u_max, knot_spacing, **kwargs)
        return out

    try:
        for name, fn in saved.items():
            setattr(_estimation, name, cached(name, fn))
        _estimation.fit_resistance = cached_fit
        yield stats
    finally:
        for name, fn in saved.items():
            setattr(_estimation, name, fn)
        _estimation.fit_resistance = fit


def _model_options(model: Any) -> dict[str, Any]:
    return {
        "saturation": bool(getattr(model, "saturation", True)),
        "saturation_order": int(getattr(model, "saturation_order", 16)),
        "wave_lift": bool(getattr(model, "wave_lift", True)),
    }


def _overridden(raw: VesselData, resolved: VesselData, changes: Mapping[str, float]) -> VesselData:
    """``raw`` with the coefficients ``changes`` (values in each entry's own unit)."""
    out: dict[str, Coefficient] = {}
    for key, val in changes.items():
        base = resolved.coefficients.get(key) or raw.coefficients.get(key)
        if base is None:
            raise ValueError(f"`{key}`: no such coefficient in vessel {raw.name!r}")
        out[key] = Coefficient(float(val), base.unit, base.source, base.status)
        if key in _KT:  # the K_T polynomial is given as a whole or not at all
            for k in _KT:
                if k not in out and k not in raw.coefficients:
                    out[k] = resolved.coefficients[k]
    return raw.with_overrides(out)


def model_at(
    vessel: VesselData,
    changes: Mapping[str, float] | None = None,
    factors: Mapping[str, float] | None = None,
    *,
    resolved: VesselData | None = None,
    options: Mapping[str, Any] | None = None,
) -> Umeda4DOF:
    """The 4-DOF model rebuilt with some coefficients and factors changed.

    Parameters
    ----------
    vessel : VesselData
        The vessel as in its file (estimates are recomputed from it).
    changes : mapping, optional
        ``{dotted key: value}`` in the unit of the key's entry; an estimated key is
        fixed at the value, a file key replaced (and the estimates that depend on it
        follow).
    factors : mapping, optional
        ``{name: value}`` of :data:`FACTORS`.
    resolved : VesselData, optional
        ``vessel`` with its estimates (gives units and values of estimated keys).
    options : mapping, optional
        ``saturation``, ``saturation_order``, ``wave_lift`` of :class:`Umeda4DOF`.
    """
    if resolved is None:
        resolved = build_vessel_model(vessel).vessel
    v = _overridden(vessel, resolved, dict(changes or {}))
    data = _with_factors(build_vessel_model(v), dict(factors or {}))
    return Umeda4DOF(data, **dict(options or {}))
