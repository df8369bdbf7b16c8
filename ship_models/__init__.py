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
"""

from __future__ import annotations

from typing import Any

from .estimation import VesselModelData, resolve_vessel
from .surge import SurgeModel
from .umeda_4dof import Umeda4DOF
from .vessel import Coefficient, VesselData, VesselFileError, available_vessels, load_vessel


def purse_seiner(**options: Any) -> Umeda4DOF:
    """Umeda's (1999) purse seiner as a :class:`Umeda4DOF` (options go to the constructor)."""
    return Umeda4DOF("purse_seiner", **options)


def purse_seiner_surge() -> SurgeModel:
    """The purse seiner's uncoupled surge model."""
    return SurgeModel("purse_seiner")


__all__ = [
    "Coefficient",
    "SurgeModel",
    "Umeda4DOF",
    "VesselData",
    "VesselFileError",
    "VesselModelData",
    "available_vessels",
    "load_vessel",
    "purse_seiner",
    "purse_seiner_surge",
    "resolve_vessel",
]
