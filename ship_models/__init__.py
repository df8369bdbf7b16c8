"""Vessel models for broachkit.

Public names
------------
load_vessel(path_or_name) -> VesselData
    Read and validate a vessel TOML file (every number with value/unit/source/status).
VesselData, Coefficient, VesselFileError
    The validated data, one number, and the error naming a bad field.
resolve_vessel(vessel) -> VesselModelData
    Estimate missing coefficients by named methods and build the force model.
Umeda4DOF(vessel)
    Surge-sway-yaw-roll-rudder model of Umeda (1999), a ``continuation.System``.
SurgeModel(vessel)
    The uncoupled surge model (chi_c = 0 reduction), a ``continuation.System``.
purse_seiner(**options) -> Umeda4DOF
    The default vessel of the paper, from ``data/purse_seiner.toml``.
purse_seiner_surge() -> SurgeModel
    Its uncoupled surge model.
get_model(name, **options), list_models(), register_model(name, factory)
    Registry of models: packaged vessel files (``"purse_seiner"``,
    ``"purse_seiner_surge"``, ``"kvlcc2"``, ...), registered factories and plugins of
    the entry-point group ``broachkit.models``; a path to a ``.toml`` file works too.
load_model_file(path, kind="4dof") -> Umeda4DOF | SurgeModel
    The model of a user's vessel file.
get_vessel_data(name) -> VesselModelData
    The resolved vessel behind a model name or file (no CasADi model built).
PAPER_FN, PAPER_FN_BRACKET, PAPER_CHI_C
    The published operating point of Umeda (1999) (:mod:`ship_models.paper`), the
    default ``Fn`` and course everywhere in the ship layer.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from continuation._lazy import lazy_exports

if TYPE_CHECKING:  # for type checkers; _LAZY is what runs
    from .estimation import VesselModelData, resolve_vessel
    from .paper import PAPER_CHI_C, PAPER_FN, PAPER_FN_BRACKET
    from .registry import (
        PluginError,
        get_model,
        get_vessel_data,
        list_models,
        load_model_file,
        model_info,
        register_model,
    )
    from .surge import SurgeModel
    from .umeda_4dof import Umeda4DOF
    from .vessel import Coefficient, VesselData, VesselFileError, available_vessels, load_vessel

#: Public name -> the sub-module defining it, imported on first use (issue 27: a single
#: command-line query imports only what it needs; tests/test_import_light.py checks
#: this table against ``__all__`` and the imports above).
_LAZY: dict[str, str] = {
    "VesselModelData": ".estimation",
    "resolve_vessel": ".estimation",
    "PAPER_CHI_C": ".paper",
    "PAPER_FN": ".paper",
    "PAPER_FN_BRACKET": ".paper",
    "PluginError": ".registry",
    "get_model": ".registry",
    "get_vessel_data": ".registry",
    "list_models": ".registry",
    "load_model_file": ".registry",
    "model_info": ".registry",
    "register_model": ".registry",
    "SurgeModel": ".surge",
    "Umeda4DOF": ".umeda_4dof",
    "Coefficient": ".vessel",
    "VesselData": ".vessel",
    "VesselFileError": ".vessel",
    "available_vessels": ".vessel",
    "load_vessel": ".vessel",
}

#: The same table by sub-module, as the engine's :func:`continuation._lazy.lazy_exports`
#: (which makes ``__getattr__`` and ``__dir__``) takes it.
_EXPORTS: dict[str, list[str]] = {}
for _name, _sub in _LAZY.items():
    _EXPORTS.setdefault(_sub.lstrip("."), []).append(_name)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
del _name, _sub


def purse_seiner(**options: Any) -> Umeda4DOF:
    """Umeda's (1999) purse seiner as a :class:`Umeda4DOF` (options go to the constructor)."""
    from .umeda_4dof import Umeda4DOF

    return Umeda4DOF("purse_seiner", **options)


def purse_seiner_surge() -> SurgeModel:
    """The purse seiner's uncoupled surge model."""
    from .surge import SurgeModel

    return SurgeModel("purse_seiner")


__all__ = [
    "PAPER_CHI_C",
    "PAPER_FN",
    "PAPER_FN_BRACKET",
    "Coefficient",
    "PluginError",
    "SurgeModel",
    "Umeda4DOF",
    "VesselData",
    "VesselFileError",
    "VesselModelData",
    "available_vessels",
    "get_model",
    "get_vessel_data",
    "list_models",
    "load_model_file",
    "load_vessel",
    "model_info",
    "purse_seiner",
    "purse_seiner_surge",
    "register_model",
    "resolve_vessel",
]
