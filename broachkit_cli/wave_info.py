"""The wave-force model behind a ship model, for the commands' JSON output.

``broachkit critical --json`` (and any command that wants it) names the wave-force
model it used (:attr:`ship_models.contracts.WaveForceModel.name`) and, for a tabulated
model (the panel method), the table's validity range and whether the wave and course
asked for lie inside it.
"""

from __future__ import annotations

import math
from typing import Any

from ship_models.contracts import wave_model_name


def wave_force_fields(model: Any, params: Any = None) -> dict[str, Any]:
    """``{"wave_force_model": name, ...}`` for JSON output.

    Parameters
    ----------
    model : VesselModel
    params : Params, optional
        With ``lambda_over_L`` and ``chi_c``: adds ``wave_force_in_range`` for a
        tabulated model (``False``: the forces are extrapolated).
    """
    out: dict[str, Any] = {"wave_force_model": wave_model_name(model)}
    waves = getattr(getattr(model, "forces", None), "waves", None)
    lo_hi = getattr(waves, "valid_lambda_over_L", None)
    if lo_hi is not None:
        out["wave_force_valid"] = {
            "lambda_over_L": list(lo_hi),
            "chi_deg_max": math.degrees(waves.valid_chi),
        }
        try:
            lL, chi = float(params["lambda_over_L"]), float(params["chi_c"])
        except (TypeError, KeyError, IndexError, ValueError):
            return out
        out["wave_force_in_range"] = bool(waves.in_range(lL, chi))
    return out
