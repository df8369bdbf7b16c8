r"""The start point on the crossing branch, and the oriented start of its continuation.

With :math:`\varphi_2` the part of :math:`t_{new}` ``theta``-orthogonal to
:math:`t_{old}` and :math:`S = \langle\varphi_2, t_{new}\rangle_\theta =
\sin\angle(t_{old}, t_{new})`, the start point for the half ``sign = +-1`` solves, by
Newton's method from :math:`u^* + \mathrm{sign}\, a\, t_{new}`,

.. math::

    G(u) = 0, \qquad \langle \varphi_2, u - u^* \rangle_\theta = \mathrm{sign}\, a S,

a hyperplane *parallel to the current branch* at distance :math:`a S` from it, so the
corrector cannot fall back onto the current branch near :math:`u^*` (``a`` is the
amplitude). The corrected point is accepted only if it lies within ``a / 2`` of the
prediction and its tangent is within 45 degrees of :math:`t_{new}`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..algorithms.base import (
    ContinuationAlgorithm,
    StepOutcome,
    StepState,
    theta_norm,
)
from ..algorithms.corrector import CorrectorResult
from ..algorithms.point import oriented_point
from ..algorithms.step import palc_point
from ..settings import ContinuationSettings, NewtonSettings
from ..typing import FloatArray
from .bifurcation_equation import CrossingTangents

#: The start point must be within this fraction of the amplitude of its prediction.
START_DISTANCE = 0.5

#: ... and its tangent within this angle (degrees) of the crossing direction.
START_ANGLE_DEG = 45.0


def offset_direction(
    ct: CrossingTangents, t_new: FloatArray, w: FloatArray
) -> tuple[FloatArray, float]:
    r"""The off-branch direction :math:`\varphi_2` and :math:`S`.

    Parameters
    ----------
    ct : CrossingTangents
    t_new : ndarray, shape (N + 1,)
        The crossing tangent, either sign (``+-ct.t_new``).
    w : ndarray, shape (N + 1,)
        ``theta`` weights.

    Returns
    -------
    phi2 : ndarray, shape (N + 1,)
        ``+-ct.phi2``, signed so that :math:`S = \langle\varphi_2, t_{new}\rangle_\theta > 0`.
    S : float
        The sine of the angle between the branches.
    """
    phi2 = ct.phi2 if float((w * ct.phi2).dot(t_new)) > 0 else -ct.phi2
    return phi2, float((w * phi2).dot(t_new))


class OrientedStart(ContinuationAlgorithm):
    """An algorithm whose start tangent points along ``+orient`` (``-orient`` for ``ds < 0``).

    Instead of the sign rule on ``dp/ds``, which cannot tell the halves of a crossing branch
    apart where it is vertical, e.g. at a pitchfork.
    """

    def __init__(self, inner: ContinuationAlgorithm, orient: FloatArray) -> None:
        self.inner = inner
        self.orient = orient
        self.grow_iters = int(getattr(inner, "grow_iters", 3))

    def init(
        self, problem: Any, z0: FloatArray, p0: float, settings: ContinuationSettings
    ) -> StepState:
        """The inner algorithm's start state, its tangent turned along ``orient`` (``ds > 0``)."""
        state = self.inner.init(problem, z0, p0, settings)
        target = self.orient if settings.ds > 0 else -self.orient
        state.point = oriented_point(state.point, state.w, target)
        state.direction = 1.0 if state.point.tau[-1] >= 0 else -1.0
        return state

    def step(
        self, problem: Any, state: StepState, settings: ContinuationSettings
    ) -> tuple[StepState, StepOutcome]:
        """One step of the inner algorithm."""
        return self.inner.step(problem, state, settings)

    def __repr__(self) -> str:
        return f"OrientedStart({self.inner!r})"


def start_point(
    problem: Any,
    ct: CrossingTangents,
    t_new: FloatArray,
    amplitude: float,
    sign: float,
    w: FloatArray,
    newton: NewtonSettings,
) -> tuple[FloatArray | None, str]:
    """Solve ``G(u) = 0, <phi2, u - u*>_theta = sign a S`` from ``u* + sign a t_new``.

    Returns ``(u, "")`` or ``(None, reason)``.
    """
    u_star = np.append(ct.z, ct.p)
    phi2, S = offset_direction(ct, t_new, w)
    u_pred = u_star + sign * amplitude * t_new

    def near_prediction(res: CorrectorResult) -> str:
        dist = theta_norm(res.u - u_pred, w)
        if dist > START_DISTANCE * amplitude:
            return (
                f"the corrected start point is {dist / amplitude:.3g} amplitudes away from "
                "its prediction on the crossing branch"
            )
        return ""

    got = palc_point(
        problem,
        u_pred,
        u_star,
        w * phi2,
        sign * amplitude * S,
        w,
        newton,
        border=w * t_new,
        accept=near_prediction,
    )
    res, pt = got.res, got.point
    if not res.converged or res.lin is None:
        return None, f"the start point did not converge ({res.message or 'Newton failed'})"
    if got.singular:
        return None, f"no tangent at the start point ({got.message})"
    if pt is None:
        return None, got.message
    cos = abs(float((w * pt.tau).dot(t_new)))
    if cos < math.cos(math.radians(START_ANGLE_DEG)):
        return None, (
            f"the tangent at the start point turns by {math.degrees(math.acos(cos)):.1f} deg "
            "from the crossing direction"
        )
    return np.array(res.u), ""


__all__ = ["START_ANGLE_DEG", "START_DISTANCE", "OrientedStart", "offset_direction", "start_point"]
