"""The vessel's model rebuilt with some coefficients and factors changed, cheaply.

The expensive hydrostatic steps are reused inside
:func:`~ship_models.estimation.reuse_hydrostatics` (re-exported here).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ...contracts import VesselModel
from ...estimation import build_vessel_model, reuse_hydrostatics
from ...vessel import Coefficient, VesselData
from .factors import _KT, _with_factors


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
    model: VesselModel | None = None,
    options: Mapping[str, Any] | None = None,
) -> VesselModel:
    """The vessel's model rebuilt with some coefficients and factors changed.

    The model rebuilds itself (:meth:`~ship_models.contracts.VesselModel.rebuild`):
    its class, options and wave-force builder are kept, so a vessel with its own wave
    forces keeps them.

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
    model : VesselModel, optional
        The model to rebuild (default: the 4-DOF model of ``vessel`` with
        ``options``).
    options : mapping, optional
        ``saturation``, ``saturation_order``, ``wave_lift`` of the default model
        (only without ``model``).
    """
    if model is not None and options:
        raise ValueError("`options`: give either `model` (its options are kept) or options")
    builder = model.data.wave_builder if model is not None else None
    if resolved is None:
        resolved = build_vessel_model(vessel, waves=builder).vessel
    v = _overridden(vessel, resolved, dict(changes or {}))
    data = _with_factors(build_vessel_model(v, waves=builder), dict(factors or {}))
    if model is None:
        from ...registry import vessel_model  # (the registry imports the model classes)

        return vessel_model(data, **dict(options or {}))
    return model.rebuild(data)


__all__ = ["model_at", "reuse_hydrostatics"]
