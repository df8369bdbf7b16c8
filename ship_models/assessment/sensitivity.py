r"""``dC/dtheta``: how the Level 2 criterion moves with the vessel's coefficients.

On the discrete grid ``C`` is piecewise constant in a coefficient ``theta`` (a wave case
switches when its threshold crosses the service ``Fn``), so its derivative is taken of
the quadrature it approximates, continuous in the steepness ``s`` on every wavelength
column ``i``:

.. math::

    C = \sum_i \Delta\lambda \int p_i(s)\, H\bigl(Fn - Fn_{cr}(\lambda_i, s; \theta)\bigr)\,ds,
    \qquad
    \frac{dC}{d\theta} = -\sum_i \Delta\lambda \sum_{s^*} p_i(s^*)\,
    \frac{\partial Fn_{cr}/\partial\theta}{|\partial Fn_{cr}/\partial s|}\Big|_{s^*},

the sum over the crossings ``Fn_cr(lambda_i, s*) = Fn`` (the service-Fn contour of the
threshold figure), ``p_i(s) = sum W2 p(lambda_i, s)`` the Longuet-Higgins density
(:func:`~ship_models.assessment.wave_weights.wave_case_density`). ``Fn_cr`` is
Melnikov's (the criterion's; milliseconds per grid); ``dFn_cr/dtheta`` by central
differences with the vessel rebuilt at ``theta +- h`` through the project's sensitivity
machinery (:func:`ship_models.analysis.sensitivity.rebuild.model_at`: an estimated
coefficient is fixed at the value, a file coefficient replaced and the estimates that
depend on it follow). The crossings and slopes are linear interpolations between grid
steepnesses (second-order accurate in the grid step).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from continuation.typing import FloatArray

from ..estimation import build_vessel_model
from ..vessel import VesselData, load_vessel
from .melnikov import melnikov_grid
from .standard import ScatterTable, SurfRidingStandard
from .wave_weights import G_STANDARD, wave_case_density


def contour_derivative(
    Fn: float,
    Fn_cr: FloatArray,
    dFn_cr: FloatArray,
    lambda_over_L: FloatArray,
    steepness: FloatArray,
    d_lambda_over_L: float,
    density: Callable[[float, FloatArray], FloatArray],
) -> float:
    r"""``dC/dtheta`` by the contour formula (module doc).

    Parameters
    ----------
    Fn : float
        Service Froude number.
    Fn_cr, dFn_cr : ndarray, shape (n_lambda, n_s)
        Thresholds and their derivatives in ``theta``.
    lambda_over_L, steepness : ndarray
        Grid (``steepness`` increasing).
    d_lambda_over_L : float
        Column width.
    density : callable
        ``density(lambda_over_L, s) -> p`` (the scatter-weighted density in
        ``(lambda/L, s)``).
    """
    out = 0.0
    s = np.asarray(steepness, dtype=float)
    for i, lam in enumerate(np.asarray(lambda_over_L, dtype=float)):
        d = np.asarray(Fn_cr[i], dtype=float) - Fn
        ok = np.isfinite(d[:-1]) & np.isfinite(d[1:])
        cross = np.nonzero(ok & (np.sign(d[:-1]) != np.sign(d[1:])) & (d[:-1] != d[1:]))[0]
        for j in cross:
            t = d[j] / (d[j] - d[j + 1])
            s_star = s[j] + t * (s[j + 1] - s[j])
            slope = (Fn_cr[i, j + 1] - Fn_cr[i, j]) / (s[j + 1] - s[j])
            dth = dFn_cr[i, j] + t * (dFn_cr[i, j + 1] - dFn_cr[i, j])
            p = float(np.asarray(density(float(lam), np.array([s_star]))).ravel()[0])
            out -= d_lambda_over_L * p * dth / abs(slope)
    return out


def scatter_density(
    L: float, scatter: ScatterTable, *, g: float = G_STANDARD
) -> Callable[[float, FloatArray], FloatArray]:
    """``p(lambda/L, s) = sum W2(Hs, Tz) p_LH(lambda/L, s; Hs, Tz)``."""
    W2 = scatter.W2

    def p(lam: float, s: FloatArray) -> FloatArray:
        tot = np.zeros(np.shape(s))
        for a, Hs in enumerate(scatter.Hs):
            for b, Tz in enumerate(scatter.Tz):
                if W2[a, b] > 0:
                    tot = tot + W2[a, b] * wave_case_density(lam, s, L, float(Hs), float(Tz), g=g)
        return tot

    return p


@dataclass(frozen=True)
class CriterionSensitivity:
    """``dC/dtheta`` of one coefficient.

    Attributes
    ----------
    key : str
    value : float
        The coefficient (its unit).
    unit : str
    step : float
        Central-difference step ``h``.
    dC_dtheta : float
    sigma : float or None
        Standard uncertainty from the vessel file, if stated.
    dC_sigma : float or None
        ``sigma dC/dtheta``: the change of ``C`` for one standard uncertainty.
    """

    key: str
    value: float
    unit: str
    step: float
    dC_dtheta: float
    sigma: float | None
    dC_sigma: float | None


def criterion_sensitivity(
    vessel: VesselData | str,
    Fn: float,
    standard: SurfRidingStandard,
    scatter: ScatterTable,
    *,
    keys: Iterable[str] | None = None,
    rel_step: float = 1e-3,
    progress: Callable[[str], None] | None = None,
) -> list[CriterionSensitivity]:
    """``dC/dtheta`` (Melnikov's ``C``) for the coefficients ``keys`` (default: those with
    a standard uncertainty in the vessel file), module doc.

    Raises
    ------
    ValueError
        An unknown key, or a coefficient at zero (no relative step).
    """
    from ..analysis.sensitivity.rebuild import model_at, reuse_hydrostatics

    raw = vessel if isinstance(vessel, VesselData) else load_vessel(vessel)
    say = progress or (lambda msg: None)
    with reuse_hydrostatics():
        base = build_vessel_model(raw)
        resolved = base.vessel
        key_list = list(keys) if keys is not None else list(raw.uncertainties)
        for k in key_list:
            if k not in resolved.coefficients:
                raise ValueError(f"`keys`: no coefficient {k!r} in vessel {raw.name!r}")
        F0 = base.forces
        mel0 = melnikov_grid(F0, standard.lambda_over_L, standard.steepness)
        density = scatter_density(F0.L, scatter, g=F0.g)
        out = []
        for k in key_list:
            say(f"dC/dtheta: {k}")
            coef = resolved.coefficients[k]
            v = float(coef.value)
            if v == 0:
                raise ValueError(f"`keys`: {k} is 0; a relative step is not defined")
            h = rel_step * abs(v)
            grids = []
            for vv in (v + h, v - h):
                m = model_at(raw, {k: vv}, resolved=resolved)
                grids.append(
                    melnikov_grid(m.forces, standard.lambda_over_L, standard.steepness).Fn_cr
                )
            dFn = (grids[0] - grids[1]) / (2 * h)
            dC = contour_derivative(
                Fn,
                mel0.Fn_cr,
                dFn,
                standard.lambda_over_L,
                standard.steepness,
                standard.d_lambda_over_L,
                density,
            )
            sig = resolved.sigma(k) if hasattr(resolved, "sigma") else None
            sig = None if sig is None or not math.isfinite(sig) else float(sig)
            out.append(
                CriterionSensitivity(
                    k, v, coef.unit, h, float(dC), sig, None if sig is None else float(sig * dC)
                )
            )
    return out


def to_json(rows: list[CriterionSensitivity]) -> list[dict[str, Any]]:
    """Rows as JSON-ready dicts, largest ``|dC_sigma|`` (else ``|dC_dtheta|``) first."""
    rows = sorted(rows, key=lambda r: -abs(r.dC_sigma if r.dC_sigma is not None else 0.0))
    return [r.__dict__.copy() for r in rows]


__all__ = [
    "CriterionSensitivity",
    "contour_derivative",
    "criterion_sensitivity",
    "scatter_density",
    "to_json",
]
