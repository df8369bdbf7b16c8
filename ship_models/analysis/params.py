"""Coercion of the ship's parameters and courses: the one place that checks them.

Every public function of :mod:`ship_models.analysis` takes ``params`` as a
:class:`~continuation.params.Params`, a mapping by name or an array in the model's
order; :func:`ship_params` turns any of them into a checked ``Params`` (and applies
changes such as ``chi_c=...``), and :func:`course` checks one autopilot course.
:func:`replace_settings` gives a copy of a settings dataclass with named fields
changed, refusing unknown names; :func:`check_positive_fields` checks its fields that
must be positive numbers.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable
from typing import TYPE_CHECKING, Any, TypeVar

from continuation.params import Params

from ..contracts import VesselModel

if TYPE_CHECKING:  # pragma: no cover - typing only
    from _typeshed import DataclassInstance

_Settings = TypeVar("_Settings", bound="DataclassInstance")


def ship_params(
    model: VesselModel, params: Any = None, name: str = "params", **changes: float
) -> Params:
    """``params`` as checked :class:`Params` of ``model``, with ``changes`` applied.

    Parameters
    ----------
    model : System
        The ship model (its ``param_names``, ``check_params``, ``default_params``).
    params : Params, mapping or array_like, shape (m,), optional
        Default ``model.default_params()``.
    name : str
        Argument name used in error messages.
    **changes : float
        Values replaced after the check (e.g. ``chi_c=0.1, Fn=0.3``); must be finite.

    Returns
    -------
    Params

    Raises
    ------
    ValueError
        One line naming ``name`` (wrong names, shape, non-finite values) or the change.
    """
    if params is None:
        p = model.default_params()
    else:
        try:
            p = model.as_params(params, name)
        except (TypeError, ValueError) as exc:
            msg = str(exc)
            raise ValueError(msg if f"`{name}`" in msg else f"`{name}`: {msg}") from None
    for k, v in changes.items():
        if not (isinstance(v, (int, float)) and math.isfinite(v)):
            raise ValueError(f"`{k}` must be a finite number, got {v!r}")
    return p.replace(**changes) if changes else p


def course(value: Any, name: str = "chi_c") -> float:
    """An autopilot course in (-pi/2, pi/2) rad as a float.

    Raises
    ------
    ValueError
        If ``value`` is not a finite number in that range (message names ``name``).
    """
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"`{name}` must be a number (rad), got {value!r}") from None
    if not (math.isfinite(v) and abs(v) < math.pi / 2):
        raise ValueError(f"`{name}` must be a finite course in (-pi/2, pi/2) rad, got {value!r}")
    return v


def check_positive_fields(settings: object, names: Iterable[str]) -> None:
    """Check that the fields ``names`` of ``settings`` are finite numbers > 0.

    Parameters
    ----------
    settings : object
        A settings dataclass (checked in its ``__post_init__``).
    names : iterable of str
        The fields that must be positive.

    Raises
    ------
    ValueError
        Naming the first field that is not a finite positive number.
    """
    for name in names:
        v = getattr(settings, name)
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise ValueError(f"`{name}` must be a positive number, got {v!r}")


def replace_settings(settings: _Settings, what: str, **changes: Any) -> _Settings:
    """A copy of the settings dataclass ``settings`` with ``changes``.

    Parameters
    ----------
    settings : dataclass instance
        Frozen settings (:class:`~ship_models.analysis.critical_bvp.BVPSettings`, ...);
        their checks (``__post_init__``) run again on the copy.
    what : str
        What they set, for the message (``"BVP"`` gives "unknown BVP setting(s) ...").
    **changes
        Fields replaced.

    Returns
    -------
    dataclass instance
        ``settings`` itself when there is no change.

    Raises
    ------
    ValueError
        Naming the keys of ``changes`` that are not fields of ``settings``.
    """
    bad = sorted(set(changes) - {f.name for f in dataclasses.fields(settings)})
    if bad:
        raise ValueError(f"unknown {what} setting(s) {bad}")
    return dataclasses.replace(settings, **changes) if changes else settings


def ship_model(model: VesselModel | None) -> VesselModel:
    """``model`` checked to be an Umeda4DOF-like System, or a new purse seiner if None.

    No model is cached: a caller that solves many courses passes its model.
    """
    if model is None:
        from ship_models import purse_seiner

        return purse_seiner()
    if not (hasattr(model, "state_names") and hasattr(model, "find_equilibrium")):
        raise ValueError(
            "`model` must be an Umeda4DOF-like System (with `find_equilibrium`), "
            f"got {type(model).__name__}"
        )
    return model


#: How each ship parameter is shown in messages: (label, unit, to the user's unit).
_SHOWN: dict[str, tuple[str, str, Any]] = {
    "Fn": ("Fn", "", float),
    "chi_c": ("chi_c", " deg", math.degrees),
    "H_over_lambda": ("H/lambda", "", float),
    "lambda_over_L": ("lambda/L", "", float),
    "K_R": ("K_R", "", float),
    "T_D": ("T_D", " s", float),
}


def describe_params(params: Any) -> str:
    """Parameters in words for a message: angles in degrees, plain numbers, no reprs.

    ``"Fn = 0.25, chi_c = 42 deg, H/lambda = 0.1087, lambda/L = 1.5, K_R = 1, T_D = 0 s"``.
    """
    items = params.as_dict() if hasattr(params, "as_dict") else dict(params)
    parts = []
    for name, value in items.items():
        label, unit, conv = _SHOWN.get(name, (name, "", float))
        try:
            parts.append(f"{label} = {conv(float(value)):.6g}{unit}")
        except (TypeError, ValueError):
            parts.append(f"{label} = {value}")
    return ", ".join(parts)


__all__ = [
    "check_positive_fields",
    "course",
    "describe_params",
    "replace_settings",
    "ship_model",
    "ship_params",
]
