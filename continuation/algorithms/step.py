r"""One pseudo-arclength correction: the engine's single predictor-corrector step.

Every place that moves along a branch by solving the bordered system

.. math::

    G(z, p) = 0, \qquad c \cdot (u - u_{\mathrm{ref}}) = \sigma, \qquad u = (z, p),

from a predicted point and then needs the corrected point with its tangent calls
:func:`palc_point`: the PALC step (:class:`~continuation.algorithms.palc.PALC`, border
``c = w o tau_a``, Keller 1977), natural stepping (:class:`~continuation.algorithms.
natural.Natural`, ``c = e_p``), the special-point locator (points at pseudo-arclength
``sigma`` inside a step, :mod:`continuation.locate`) and the start of a switched branch
(:func:`continuation.switching.start.start_point`). They differ only in the predictor,
the border and their acceptance tests, which they pass in; the Newton corrector
(:func:`~continuation.algorithms.corrector.correct`) and the tangent
(:func:`~continuation.algorithms.point.make_point`) are the same. The compiled step of
:mod:`continuation._kernel` is this step for small dense systems; whatever it does not
accept is redone here.

Keller, H. B. (1977), "Numerical solution of bifurcation and nonlinear eigenvalue
problems", in *Applications of Bifurcation Theory*, Academic Press, 359-384.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..settings import NewtonSettings
from ..typing import FloatArray
from .corrector import CorrectorResult, correct
from .point import PointInfo, make_point


@dataclass
class PalcPoint:
    """Outcome of :func:`palc_point`.

    Attributes
    ----------
    res : CorrectorResult
        The corrector's result (converged or not).
    point : PointInfo or None
        The corrected point with its tangent; None when the step failed.
    message : str
        Why it failed (empty on success).
    singular : bool
        The corrector converged and was accepted but the bordered matrix at the point
        is singular (no tangent): ``res.lin`` holds the linearisation there.
    """

    res: CorrectorResult
    point: PointInfo | None
    message: str = ""
    singular: bool = False


def palc_point(
    problem: Any,
    u_pred: FloatArray,
    u_ref: FloatArray,
    c: FloatArray,
    sigma: float,
    w: FloatArray,
    newton: NewtonSettings,
    *,
    border: FloatArray | None = None,
    accept: Callable[[CorrectorResult], str] | None = None,
    **correct_options: Any,
) -> PalcPoint:
    """Correct ``u_pred`` onto the branch and compute the tangent there.

    Parameters
    ----------
    problem : Problem
        The continuation problem ``G(z, p)``.
    u_pred : ndarray, shape (N + 1,)
        The predicted point ``(z, p)``.
    u_ref : ndarray, shape (N + 1,)
        Reference point of the constraint ``c . (u - u_ref) = sigma``.
    c : ndarray, shape (N + 1,)
        Last row of the bordered system (``w o tau_a`` for pseudo-arclength, ``e_p``
        for natural stepping).
    sigma : float
        Right-hand side of the constraint (the step length for PALC).
    w : ndarray, shape (N + 1,)
        ``theta`` weights of the tangent's norm.
    newton : NewtonSettings
        The corrector's settings.
    border : ndarray, shape (N + 1,), optional
        Border (and orientation) of the tangent's bordered matrix; default ``c``, in
        which case the corrector's last factorisation is reused.
    accept : callable, optional
        ``accept(res) -> reason`` on the converged corrector result, before the tangent
        is computed; a non-empty reason fails the step with that message.
    **correct_options
        Passed to :func:`~continuation.algorithms.corrector.correct`
        (``max_contraction``, ``exact``, ``predict_final``).

    Returns
    -------
    PalcPoint
    """
    res = correct(problem, u_pred, u_ref, c, sigma, newton, **correct_options)
    if not res.converged or res.lin is None:
        return PalcPoint(res, None, res.message)
    if accept is not None:
        why = accept(res)
        if why:
            return PalcPoint(res, None, why)
    try:
        if border is None:
            pt = make_point(
                res.z,
                res.p,
                res.lin,
                c,
                w,
                iters=res.iters,
                lu=res.lu,
                u=res.u,
                residual_norm=res.g_norm,
                t_raw=res.t_raw,
                jac_finite=res.jac_finite,
            )
        else:
            pt = make_point(res.z, res.p, res.lin, border, w)
    except np.linalg.LinAlgError as exc:
        return PalcPoint(res, None, str(exc), singular=True)
    return PalcPoint(res, pt)


__all__ = ["PalcPoint", "palc_point"]
