r"""The interface of the continuation algorithms: step state, outcome, step-size rule.

Notation: ``u = (z, p)`` in ``R^(N+1)``; ``G(z, p) = 0`` has ``N`` equations. The
``theta``-weighted inner product (settings ``theta``) is

.. math::

    \langle a, b \rangle_\theta = \frac{1-\theta}{N}\, a_z \cdot b_z + \theta\, a_p b_p
    = (w \circ a) \cdot b ,

with weight vector ``w`` (:func:`theta_weights`). Tangents ``tau`` have unit
``theta``-norm.

An algorithm (:class:`ContinuationAlgorithm`) makes its start state once (``init``)
and then attempts steps (``step``) from a :class:`StepState`, each returning a
:class:`StepOutcome`; the driver (:mod:`continuation.driver`) chooses the next step
length with :func:`adapt_ds`, the one step-size rule of the engine. The machinery the
algorithms share lives in :mod:`.corrector` (Newton's method on the bordered system),
:mod:`.point` (converged points and tangents) and :mod:`continuation.linalg`.
"""

from __future__ import annotations

import abc
import math
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from ..settings import ContinuationSettings
from ..typing import FloatArray
from .point import PointInfo, initial_point


# ---------------------------------------------------------------------------- norms
def theta_weights(n_unknowns: int, theta: float) -> FloatArray:
    """Weights ``w`` of the ``theta`` inner product, shape ``(N + 1,)``."""
    w = np.full(n_unknowns + 1, (1.0 - theta) / max(n_unknowns, 1))
    w[-1] = theta
    return w


def theta_norm(v: FloatArray, w: FloatArray) -> float:
    """``sqrt(sum(w * v**2))``."""
    return math.sqrt(float((w * v).dot(v)))


# ---------------------------------------------------------------------------- algorithm API
@dataclass(eq=False, slots=True)
class StepState:
    """Mutable iteration state passed between the driver and an algorithm.

    Attributes
    ----------
    point : PointInfo
        The last accepted point.
    ds : float
        Current step length (``> 0``; the direction is carried by ``point.tau``).
    w : ndarray, shape (N + 1,)
        ``theta`` weights.
    direction : float
        ``+1`` or ``-1``: the sign of ``dp/ds`` requested at the start.
    n_steps : int
        Accepted steps so far.
    prev_d : ndarray, shape (N + 1,), or None
        ``u - (u_0 + prev_h * prev_tau)`` of ``point``'s ``u``, with ``u_0`` the accepted
        point before it: how far the last step's corrector moved ``point`` from the
        tangent prediction (for predictors that extrapolate the branch; None at the start
        or when unknown).
    prev_tau : ndarray, shape (N + 1,), or None
        Tangent at ``u_0``.
    prev_h : float
        Pseudo-arclength from ``u_0`` to ``point``.
    retries : int
        Rejected attempts from ``point`` so far (set by the algorithm).
    """

    point: PointInfo
    ds: float
    w: FloatArray
    direction: float = 1.0
    n_steps: int = 0
    prev_d: FloatArray | None = None
    prev_tau: FloatArray | None = None
    prev_h: float = 0.0
    retries: int = 0


class StepOutcome(NamedTuple):
    """Result of one attempted step.

    Immutable; a named tuple, cheap to create on the hot path of small problems.

    Attributes
    ----------
    converged : bool
        The step was accepted.
    newton_iters : int
        Corrector iterations.
    residual_norm : float
        Final ``max |G|``.
    sigma : float
        Pseudo-arclength step achieved, ``<tau_prev, u_new - u_prev>_theta``.
    message : str
        Why a step was rejected.
    """

    converged: bool
    newton_iters: int
    residual_norm: float
    sigma: float = 0.0
    message: str = ""


def adapt_ds(
    ds: float, outcome: StepOutcome, settings: ContinuationSettings, *, grow_iters: int = 3
) -> float:
    """Next step length, the engine's one step-size rule.

    ``ds * grow`` after an easy step (``<= grow_iters`` iterations), ``ds`` after a harder
    one, capped at ``ds_max``; ``ds * shrink`` after a failure (:data:`RETRY` for a step the
    driver refuses after the algorithm accepted it). Never below zero; the caller compares
    with ``ds_min``.
    """
    if outcome.converged:
        if outcome.newton_iters <= grow_iters:
            return min(ds * settings.grow, settings.ds_max)
        return min(ds, settings.ds_max)
    return ds * settings.shrink


class ContinuationAlgorithm(abc.ABC):
    """A predictor-corrector scheme: ``init`` once, then ``step`` repeatedly."""

    def init(
        self, problem: Any, z0: FloatArray, p0: float, settings: ContinuationSettings
    ) -> StepState:
        """State at the (already corrected) start point ``(z0, p0)``.

        The tangent there is oriented so that ``sign(dp/ds) = sign(settings.ds)``;
        algorithms that need more start-up state override this.
        """
        w = theta_weights(z0.size, settings.theta)
        direction = 1.0 if settings.ds > 0 else -1.0
        pt = initial_point(problem, np.asarray(z0, float), float(p0), w, direction)
        return StepState(point=pt, ds=abs(settings.ds), w=w, direction=direction)

    @abc.abstractmethod
    def step(
        self, problem: Any, state: StepState, settings: ContinuationSettings
    ) -> tuple[StepState, StepOutcome]:
        """Attempt one step of length ``state.ds``; on success return the new state."""

    grow_iters: int = 3


#: The outcome of a step the driver refuses after the algorithm accepted it (a bound
#: crossed but not located, several real eigenvalues crossing in one step): retried
#: shorter by :func:`adapt_ds`.
RETRY = StepOutcome(False, 0, math.nan, 0.0, "retried shorter")


__all__ = [
    "RETRY",
    "ContinuationAlgorithm",
    "StepOutcome",
    "StepState",
    "adapt_ds",
    "theta_norm",
    "theta_weights",
]
