r"""Natural parameter continuation: step the free parameter, correct the state.

From ``(z_a, p_a)`` one step sets ``p_b = p_a + direction * ds``, predicts
``z = z_a + (p_b - p_a) dz/dp`` (the secant-free tangent predictor,
``dz/dp = -G_z^{-1} G_p``) and solves ``G(z, p_b) = 0`` by Newton's method at fixed
``p_b``. Simple and robust on monotone branches; it cannot pass a fold (Newton fails as
``G_z`` becomes singular, and the branch ends with ``Status.DS_MIN``). Meant for tests
and simple smooth branches; use :class:`~continuation.algorithms.palc.PALC` otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..arguments import integer_at_least
from ..settings import ContinuationSettings
from .base import ContinuationAlgorithm, StepOutcome, StepState
from .step import palc_point


@dataclass(frozen=True, kw_only=True)
class Natural(ContinuationAlgorithm):
    """Natural parameter stepping (``ds`` is a step in the free parameter).

    Parameters
    ----------
    grow_iters : int
        The step grows by ``settings.grow`` after at most this many Newton iterations.
    """

    grow_iters: int = 3

    def __post_init__(self) -> None:
        integer_at_least("grow_iters", self.grow_iters, 0)

    def step(
        self, problem: Any, state: StepState, settings: ContinuationSettings
    ) -> tuple[StepState, StepOutcome]:
        """Step ``p`` by ``direction * ds`` and correct ``z`` at fixed ``p``."""
        a = state.point
        dp = state.direction * state.ds
        if a.tau[-1] * state.direction <= 0:
            return state, StepOutcome(False, 0, 0.0, 0.0, "dp/ds changed sign: a fold")
        ua = a.u
        u_pred = ua + (dp / a.tau[-1]) * a.tau
        e_p = np.zeros(ua.size)
        e_p[-1] = state.direction
        got = palc_point(problem, u_pred, ua, e_p, abs(dp), state.w, settings.newton)
        res, b = got.res, got.point
        if b is None:
            return state, StepOutcome(False, res.iters, res.residual_norm, 0.0, got.message)
        sigma = float(np.dot(state.w * a.tau, b.u - ua))
        new = StepState(b, state.ds, state.w, state.direction, state.n_steps + 1)
        return new, StepOutcome(True, res.iters, res.residual_norm, sigma)


__all__ = ["Natural"]
