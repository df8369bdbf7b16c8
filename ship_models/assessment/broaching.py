r"""A broaching version of Level 2 over autopilot course (beyond the standard, opt-in).

The criterion counts surf-riding (``chi = 0``). Broaching capsize in quartering seas is
Umeda's (1999) heteroclinic bifurcation of the 4-DOF model at the autopilot course
``chi_c``: here ``C2_ij(chi_c) = [Fn > Fn_cap(lambda_i, s_j; chi_c)]`` with the 4-DOF
capsizing threshold, and

.. math::

    C_{broach}(\chi_c) = \sum W2 \sum_{k} w_k\, C2_k(\chi_c)

over a coarse set of wave cases ``k`` (each 4-DOF threshold is a collocation solve of
seconds): every fine wave case of the criterion's grid gives its weight to the nearest
coarse case (in ``lambda/L`` and ``H/lambda`` separately), so ``sum_k w_k`` equals the
fine grid's sum. This re-binning is a coarser quadrature of the same sum, its error not
estimated beyond the comparison printed at ``chi_c = 0``: there the 4-DOF threshold is
the surge model's (lateral motions vanish), and the coarse ``C`` is reported beside
the fine one.

The threshold comes through one adapter, :func:`capsizing_fn`: the capsizing threshold
of ``ship_models.analysis.threshold`` when it is installed, otherwise the heteroclinic
critical ``Fn`` of :func:`ship_models.analysis.critical.critical_fn` (``method="bvp"``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from continuation.typing import FloatArray

from .criteria import surf_riding_indicator
from .standard import ScatterTable, SurfRidingStandard


@dataclass(frozen=True)
class CapsizingFn:
    """The capsizing threshold of one wave and course as the adapter returns it."""

    Fn: float
    status: str
    mechanism: str


def capsizing_fn(
    model: Any, params: Any, chi_c: float, Fn_guess: float | None = None
) -> CapsizingFn:
    """The 4-DOF capsizing threshold at course ``chi_c`` (rad), by
    :func:`ship_models.analysis.threshold.capsizing_threshold` (the lowest Fn at which the
    upslope branch capsizes, with its mechanism).

    Where nothing capsizes because the ship surf-rides instead (``chi_c = 0``: no lateral
    motion), the surf-riding threshold, the heteroclinic Fn, is returned with the
    mechanism ``"surf-riding"``: that is what C2 counts there.
    """
    from continuation.status import Status
    from ship_models.analysis.params import ship_params
    from ship_models.analysis.threshold import capsizing_threshold

    changes = {} if Fn_guess is None else {"Fn": float(Fn_guess)}
    p = ship_params(model, params, **changes)
    r = capsizing_threshold(model, p, chi_c=chi_c)
    if r.status is Status.NO_SOLUTION and math.isfinite(r.Fn_heteroclinic):
        return CapsizingFn(float(r.Fn_heteroclinic), "SUCCESS", "surf-riding")
    return CapsizingFn(float(r.Fn), r.status.name, str(r.mechanism))


def rebin(fine: FloatArray, coarse: FloatArray) -> FloatArray:
    """Index of the nearest coarse value of every fine value."""
    fine = np.asarray(fine, dtype=float)
    coarse = np.asarray(coarse, dtype=float)
    return np.argmin(np.abs(fine[:, None] - coarse[None, :]), axis=1)


@dataclass(frozen=True)
class BroachingLevel2:
    """``C_broach`` over courses on a coarse set of wave cases.

    Attributes
    ----------
    chi_c_deg : ndarray, shape (n_c,)
    lambda_over_L, steepness : ndarray
        The coarse wave cases.
    Fn_cap : ndarray, shape (n_c, n_l, n_s)
        4-DOF thresholds (NaN where not found; counted in ``C_upper``).
    status : list of list of list of str
    C, C_upper : ndarray, shape (n_c,) or None
        Without a scatter table: None.
    C_sea_state : ndarray, shape (n_c, n_Hs, n_Tz)
    mechanism : str
    C_surge_coarse : float or None
        ``C`` of the surge thresholds ``Fn_guess`` on the same coarse cases: against the
        fine surf-riding ``C`` it measures the re-binning error.
    """

    chi_c_deg: FloatArray
    lambda_over_L: FloatArray
    steepness: FloatArray
    Fn_cap: FloatArray
    status: list[list[list[str]]]
    C: FloatArray | None
    C_upper: FloatArray | None
    C_sea_state: FloatArray
    mechanism: str
    C_surge_coarse: float | None = None


def broaching_level2(
    model4: Any,
    Fn: float,
    chi_c_deg: FloatArray,
    lambda_coarse: FloatArray,
    steepness_coarse: FloatArray,
    weights: FloatArray,
    standard: SurfRidingStandard,
    scatter: ScatterTable | None = None,
    *,
    Fn_guess: FloatArray | None = None,
    progress: Callable[[str], None] | None = None,
) -> BroachingLevel2:
    """``C_broach(chi_c)`` (module doc).

    Parameters
    ----------
    model4 : Umeda4DOF
    Fn : float
        Service Froude number.
    chi_c_deg : array_like, shape (n_c,)
        Courses (deg).
    lambda_coarse, steepness_coarse : array_like
        The coarse wave cases.
    weights : ndarray, shape (n_Hs, n_Tz, n_lambda, n_s)
        Fine weights on the standard's grid.
    standard, scatter
        As for :func:`~ship_models.assessment.criteria.level2`.
    Fn_guess : ndarray, shape (n_l, n_s), optional
        Starting guesses (e.g. the surge model's exact thresholds there).
    """
    say = progress or (lambda msg: None)
    chis = np.atleast_1d(np.asarray(chi_c_deg, dtype=float))
    lc = np.atleast_1d(np.asarray(lambda_coarse, dtype=float))
    sc = np.atleast_1d(np.asarray(steepness_coarse, dtype=float))
    il, js = rebin(standard.lambda_over_L, lc), rebin(standard.steepness, sc)
    Wc = np.zeros(weights.shape[:2] + (lc.size, sc.size))
    for a in range(lc.size):
        for b in range(sc.size):
            Wc[:, :, a, b] = weights[:, :, il == a][:, :, :, js == b].sum(axis=(2, 3))
    Fn_cap = np.full((chis.size, lc.size, sc.size), np.nan)
    status = [[["" for _ in sc] for _ in lc] for _ in chis]
    mech = ""
    base = model4.default_params()
    for k, chi in enumerate(chis):
        for a, lam in enumerate(lc):
            for b, s in enumerate(sc):
                say(f"broaching: chi_c {chi:g} deg, lambda/L {lam:g}, H/lambda {s:g}")
                p = base.replace(H_over_lambda=float(s), lambda_over_L=float(lam))
                guess = None if Fn_guess is None else float(Fn_guess[a, b])
                try:
                    r = capsizing_fn(model4, p, math.radians(chi), guess)
                except (ValueError, ArithmeticError) as exc:
                    status[k][a][b] = f"failed: {exc}"
                    continue
                mech = mech or r.mechanism
                status[k][a][b] = r.status
                if r.status == "SUCCESS":
                    Fn_cap[k, a, b] = r.Fn
    C_ss = np.stack([np.einsum("abij,ij->ab", Wc, surf_riding_indicator(Fn, f)) for f in Fn_cap])
    miss = np.stack([np.einsum("abij,ij->ab", Wc, (~np.isfinite(f)).astype(float)) for f in Fn_cap])
    if scatter is None:
        return BroachingLevel2(chis, lc, sc, Fn_cap, status, None, None, C_ss, mech)
    W2 = scatter.W2
    C = np.einsum("ab,kab->k", W2, C_ss)
    C_up = C + np.einsum("ab,kab->k", W2, miss)
    C_ref = None
    if Fn_guess is not None:
        ref = np.einsum("abij,ij->ab", Wc, surf_riding_indicator(Fn, Fn_guess))
        C_ref = float(np.sum(W2 * ref))
    return BroachingLevel2(chis, lc, sc, Fn_cap, status, C, C_up, C_ss, mech, C_ref)


__all__ = ["BroachingLevel2", "CapsizingFn", "broaching_level2", "capsizing_fn", "rebin"]
