r"""Level 1 and Level 2 of the surf-riding/broaching criterion (MSC.1/Circ.1627).

The section and paragraph numbers of the criterion in MSC.1/Circ.1627 could not be
checked against its text, so none is cited (see :mod:`~ship_models.assessment.standard`).

Level 1: a ship is not vulnerable if ``L >= 200 m`` or ``Fn <= 0.3``
(:func:`level1`).

Level 2: with the critical Froude number ``Fn_cr(lambda_i, s_j)`` of each
regular wave case (Melnikov's, :mod:`~ship_models.assessment.melnikov`, or the exact
one, :mod:`~ship_models.assessment.exact`),

.. math::

    C2_{ij} = [\,Fn > Fn_{cr}(\lambda_i, s_j)\,], \qquad
    C(H_s, T_z) = \sum_{i,j} w_{ij}(H_s, T_z)\, C2_{ij}, \qquad
    C = \sum_{H_s, T_z} W2(H_s, T_z)\, C(H_s, T_z),

(:func:`level2`), and the ship is not vulnerable if ``C <= R_SR`` (0.005). The weights
``w_ij`` are those of :mod:`~ship_models.assessment.wave_weights`; over the grid they
sum to the probability of the grid's band of waves, not to one (the truncation is
reported per sea state). A wave case without a threshold (NaN: the continuation did
not reach it) is counted as 0 in ``C`` and as 1 in ``C_upper``, so that the verdict is
stated only when both agree.

``C`` as a function of the service ``Fn`` is a step function: the sum of the weights
``a_ij = sum W2 w_ij`` of the cases with ``Fn_cr < Fn``. The operational limit
(:func:`operational_limit`) is the largest ``Fn`` with ``C(Fn) <= R_SR``, read off the
sorted thresholds exactly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from continuation.typing import FloatArray

from .standard import ScatterTable, SurfRidingStandard
from .wave_weights import G_STANDARD, wave_case_weights


@dataclass(frozen=True)
class Level1Result:
    """Level 1 verdict."""

    vulnerable: bool
    reason: str


def level1(L: float, Fn: float, standard: SurfRidingStandard) -> Level1Result:
    """Level 1: not vulnerable if ``L >= L_min`` (200 m) or ``Fn <= Fn_max`` (0.3)."""
    if L >= standard.L_min:
        return Level1Result(False, f"L = {L:g} m >= {standard.L_min:g} m")
    if Fn <= standard.Fn_max:
        return Level1Result(False, f"Fn = {Fn:g} <= {standard.Fn_max:g}")
    return Level1Result(
        True, f"L = {L:g} m < {standard.L_min:g} m and Fn = {Fn:g} > {standard.Fn_max:g}"
    )


def sea_state_weights(
    standard: SurfRidingStandard,
    L: float,
    Hs: FloatArray,
    Tz: FloatArray,
    *,
    g: float = G_STANDARD,
) -> FloatArray:
    """``w_ij`` of every sea state, shape ``(n_Hs, n_Tz, n_lambda, n_s)``."""
    out = np.empty((len(Hs), len(Tz), standard.lambda_over_L.size, standard.steepness.size))
    for a, h in enumerate(Hs):
        for b, t in enumerate(Tz):
            out[a, b] = wave_case_weights(
                standard.lambda_over_L,
                standard.steepness,
                standard.d_lambda_over_L,
                standard.d_steepness,
                L,
                float(h),
                float(t),
                g=g,
            )
    return out


@dataclass(frozen=True)
class Level2Result:
    """Level 2 for one threshold surface.

    Attributes
    ----------
    C : float or None
        The criterion (None without a scatter table).
    C_upper : float or None
        With the wave cases without a threshold counted as surf-riding.
    vulnerable : bool or None
        ``C > R_SR``; None without a scatter table or when ``C`` and ``C_upper`` fall on
        different sides of ``R_SR``.
    C_sea_state : ndarray, shape (n_Hs, n_Tz)
        ``C(Hs, Tz)``.
    grid_mass : ndarray, shape (n_Hs, n_Tz)
        ``sum_ij w_ij``: the probability of the grid's band of waves (truncation).
    Hs, Tz : ndarray
        The sea states.
    Fn_limit : float or None
        Largest ``Fn`` with ``C <= R_SR`` (None without a scatter table).
    missing_cells : int
        Wave cases without a threshold.
    """

    C: float | None
    C_upper: float | None
    vulnerable: bool | None
    C_sea_state: FloatArray
    grid_mass: FloatArray
    Hs: FloatArray
    Tz: FloatArray
    Fn_limit: float | None
    missing_cells: int


def surf_riding_indicator(Fn: float, Fn_cr: FloatArray) -> FloatArray:
    """``C2_ij = 1`` where ``Fn > Fn_cr`` (0 elsewhere and where ``Fn_cr`` is NaN)."""
    Fn_cr = np.asarray(Fn_cr, dtype=float)
    with np.errstate(invalid="ignore"):
        return np.where(np.isfinite(Fn_cr) & (Fn > Fn_cr), 1.0, 0.0)


def operational_limit(Fn_cr: FloatArray, a: FloatArray, R_SR: float) -> float:
    r"""Largest ``Fn`` with ``C(Fn) = sum_{Fn_cr < Fn} a <= R_SR`` (module doc).

    Cells without a threshold count as surf-riding at every ``Fn`` (conservative).
    Returns ``inf`` when even every cell together stays within ``R_SR``.
    """
    Fn_cr = np.asarray(Fn_cr, dtype=float).ravel()
    a = np.asarray(a, dtype=float).ravel()
    missing = ~np.isfinite(Fn_cr)
    base = float(a[missing].sum())
    if base > R_SR:
        return -np.inf
    order = np.argsort(Fn_cr[~missing], kind="stable")
    f = Fn_cr[~missing][order]
    cum = base + np.cumsum(a[~missing][order])
    over = np.nonzero(cum > R_SR)[0]
    if over.size == 0:
        return np.inf
    return float(f[over[0]])


def level2(
    Fn: float,
    Fn_cr: FloatArray,
    weights: FloatArray,
    Hs: FloatArray,
    Tz: FloatArray,
    standard: SurfRidingStandard,
    scatter: ScatterTable | None = None,
) -> Level2Result:
    """Level 2 (module doc).

    Parameters
    ----------
    Fn : float
        Service Froude number.
    Fn_cr : ndarray, shape (n_lambda, n_s)
        Thresholds of the wave cases.
    weights : ndarray, shape (n_Hs, n_Tz, n_lambda, n_s)
        :func:`sea_state_weights` of ``Hs, Tz`` (those of ``scatter`` when given).
    Hs, Tz : ndarray
    standard : SurfRidingStandard
    scatter : ScatterTable, optional
        ``W2``; without it only ``C(Hs, Tz)`` is computed.
    """
    Fn_cr = np.asarray(Fn_cr, dtype=float)
    if weights.shape[2:] != Fn_cr.shape:
        raise ValueError(f"weights {weights.shape} do not match thresholds {Fn_cr.shape}")
    C2 = surf_riding_indicator(Fn, Fn_cr)
    missing = ~np.isfinite(Fn_cr)
    C_ss = np.einsum("abij,ij->ab", weights, C2)
    C_ss_up = C_ss + np.einsum("abij,ij->ab", weights, missing.astype(float))
    mass = weights.sum(axis=(2, 3))
    if scatter is None:
        return Level2Result(None, None, None, C_ss, mass, Hs, Tz, None, int(missing.sum()))
    if not (np.array_equal(scatter.Hs, Hs) and np.array_equal(scatter.Tz, Tz)):
        raise ValueError("`weights` must be computed on the sea states of `scatter`")
    W2 = scatter.W2
    C = float(np.sum(W2 * C_ss))
    C_up = float(np.sum(W2 * C_ss_up))
    R = standard.R_SR
    vul: bool | None = C > R if (C > R) == (C_up > R) else None
    a = np.einsum("ab,abij->ij", W2, weights)
    return Level2Result(
        C, C_up, vul, C_ss, mass, Hs, Tz, operational_limit(Fn_cr, a, R), int(missing.sum())
    )


__all__ = [
    "Level1Result",
    "Level2Result",
    "level1",
    "level2",
    "operational_limit",
    "sea_state_weights",
    "surf_riding_indicator",
]
