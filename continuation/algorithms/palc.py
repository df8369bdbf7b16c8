r"""Pseudo-arclength continuation (PALC, Keller 1977).

Keller, H. B. (1977), "Numerical solution of bifurcation and nonlinear eigenvalue
problems", in *Applications of Bifurcation Theory*, Academic Press, 359-384.

From an accepted point ``u_a = (z_a, p_a)`` with unit tangent ``tau_a`` (``theta``-norm),
one step of length ``ds``

1. predicts ``u_pred = u_a + ds * tau_a``;
2. corrects by Newton's method on the bordered system

   .. math::

       G(z, p) = 0, \qquad \langle \tau_a, u - u_a \rangle_\theta - ds = 0,

   whose Jacobian is ``[[G_z, G_p], [(w o tau_a)^T]]``;
3. computes the new tangent from ``[[G_z, G_p], [(w o tau_a)^T]] t = e_{N+1}`` at the
   converged point, ``tau = t / ||t||_theta``; the last equation gives
   ``<tau_a, tau>_theta > 0``, so the orientation is kept through folds. The same LU
   factorisation gives the branch-point test function (see :mod:`.base`).

A step is rejected (and retried by the driver with a smaller ``ds``) when

* Newton fails (no convergence in ``newton.max_iter`` iterations, divergence, a
  singular bordered matrix);
* the corrector contracts too slowly: a Newton step is not at least ``max_contraction``
  times shorter than the previous one while the point has not yet converged
  (Allgower & Georg 1990, *Numerical Continuation Methods*, Sec. 6.1 and Program 1,
  contraction rate ``0.8``);
* the corrected point is farther than ``max_distance * ds`` from the predictor
  (``theta``-norm). The correction is ``theta``-orthogonal to ``tau_a``, so this bounds
  the angle between the chord ``u_b - u_a`` and ``tau_a`` by ``atan(max_distance)``
  (45 degrees by default); on a smooth branch the chord turns by about half the
  tangent, so only a corrector that left the branch it started from trips it
  (Allgower & Georg 1990, Program 1: "maximal distance to curve");
* the tangent turns by more than ``max_angle_deg`` (to avoid jumping between branches).

All three geometric safeguards are waived once ``ds`` has reached ``ds_min``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..settings import ContinuationSettings
from .base import (
    ContinuationAlgorithm,
    StepOutcome,
    StepState,
    correct,
    make_point,
)


class PALC(ContinuationAlgorithm):
    """Pseudo-arclength continuation with a bordered tangent predictor.

    Parameters
    ----------
    max_angle_deg : float
        Largest accepted angle (``theta``-metric) between consecutive tangents; a larger
        turn rejects the step unless ``ds`` is already at ``ds_min``.
    grow_iters : int
        The step grows by ``settings.grow`` after a step needing at most this many
        corrector iterations.
    max_contraction : float
        Largest accepted ratio of consecutive Newton step lengths in the corrector,
        in (0, 1).
    max_distance : float
        Largest accepted ``theta``-distance of the corrected point from the predictor,
        in units of ``ds`` (> 0).
    """

    def __init__(
        self,
        *,
        max_angle_deg: float = 60.0,
        grow_iters: int = 3,
        max_contraction: float = 0.8,
        max_distance: float = 1.0,
    ) -> None:
        if not (0 < max_angle_deg <= 180):
            raise ValueError(f"`max_angle_deg` must be in (0, 180], got {max_angle_deg}")
        if not (isinstance(grow_iters, int) and grow_iters >= 0):
            raise ValueError(f"`grow_iters` must be an integer >= 0, got {grow_iters!r}")
        if not (0 < max_contraction < 1):
            raise ValueError(f"`max_contraction` must be in (0, 1), got {max_contraction!r}")
        if not (max_distance > 0 and math.isfinite(max_distance)):
            raise ValueError(f"`max_distance` must be a positive number, got {max_distance!r}")
        self.max_angle_deg = float(max_angle_deg)
        self.grow_iters = grow_iters
        self.max_contraction = float(max_contraction)
        self.max_distance = float(max_distance)
        self._cos_max = math.cos(math.radians(max_angle_deg))

    def __repr__(self) -> str:
        return (
            f"PALC(max_angle_deg={self.max_angle_deg}, grow_iters={self.grow_iters}, "
            f"max_contraction={self.max_contraction}, max_distance={self.max_distance})"
        )

    def step(
        self, problem: Any, state: StepState, settings: ContinuationSettings
    ) -> tuple[StepState, StepOutcome]:
        """One predictor-corrector step of length ``state.ds``."""
        a = state.point
        ds = state.ds
        c = state.w * a.tau
        ua = a.u
        guarded = ds > settings.ds_min * (1 + 1e-12)
        u_pred = ua + ds * a.tau
        res = correct(
            problem,
            u_pred,
            ua,
            c,
            ds,
            settings.newton,
            max_contraction=self.max_contraction if guarded else None,
            exact=False,
        )
        if not res.converged or res.lin is None:
            return state, StepOutcome(False, res.iters, res.residual_norm, 0.0, res.message)
        if guarded and res.iters:  # (no iteration: within the step tolerance of u_pred)
            d = res.u - u_pred
            dist = math.sqrt(float((state.w * d).dot(d)))
            if dist > self.max_distance * ds:
                return state, StepOutcome(
                    False,
                    res.iters,
                    res.residual_norm,
                    0.0,
                    f"corrected point {dist / ds:.3g} ds away from the predictor",
                )
        try:
            b = make_point(
                res.z,
                res.p,
                res.lin,
                c,
                state.w,
                iters=res.iters,
                lu=res.lu,
                u=res.u_full,
                t_raw=res.t_raw,
            )
        except np.linalg.LinAlgError as exc:
            return state, StepOutcome(False, res.iters, res.residual_norm, 0.0, str(exc))
        cos_angle = b.ctau  # = c . tau (make_point's border is c)
        if cos_angle < self._cos_max and guarded:
            return state, StepOutcome(
                False,
                res.iters,
                res.residual_norm,
                0.0,
                f"tangent turned by {math.degrees(math.acos(max(-1.0, cos_angle))):.1f} deg",
            )
        new = StepState(b, ds, state.w, state.direction, state.n_steps + 1)
        return new, StepOutcome(True, res.iters, res.residual_norm, ds)


__all__ = ["PALC"]
