r"""Pseudo-arclength continuation (PALC, Keller 1977).

Keller, H. B. (1977), "Numerical solution of bifurcation and nonlinear eigenvalue
problems", in *Applications of Bifurcation Theory*, Academic Press, 359-384.

From an accepted point ``u_a = (z_a, p_a)`` with unit tangent ``tau_a`` (``theta``-norm),
one step of length ``ds``

1. predicts ``u_pred = u_a + ds * tau_a`` (tangent predictor), or, by default, from the
   cubic Hermite interpolant of the last two points and their tangents (see below);
2. corrects by Newton's method on the bordered system

   .. math::

       G(z, p) = 0, \qquad \langle \tau_a, u - u_a \rangle_\theta - ds = 0,

   whose Jacobian is ``[[G_z, G_p], [(w o tau_a)^T]]``;
3. computes the new tangent from ``[[G_z, G_p], [(w o tau_a)^T]] t = e_{N+1}`` at the
   converged point, ``tau = t / ||t||_theta``; the last equation gives
   ``<tau_a, tau>_theta > 0``, so the orientation is kept through folds. The same LU
   factorisation gives the branch-point test function (see :mod:`.point`).

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

All three geometric safeguards are waived once ``ds`` has reached ``ds_min``; the
distance is measured from the tangent predictor whichever predictor was used.

Hermite predictor
-----------------
With the previous point ``u_0`` at pseudo-arclength ``h`` behind ``u_a`` and the tangents
``tau_0``, ``tau_a``, the cubic ``q(s)`` with ``q(-h) = u_0``, ``q'(-h) = tau_0``,
``q(0) = u_a``, ``q'(0) = tau_a`` is extrapolated to ``s = ds``:

.. math::

    q(ds) = u_a + ds\,\tau_a + \alpha E + \beta F, \qquad
    E = u_0 - u_a + h \tau_a, \quad F = \tau_0 - \tau_a,

    \alpha = r^2 (3 + 2r), \quad \beta = r^2 (h + ds), \quad r = ds / h .

Its error is ``O(ds^4)`` on a smooth branch against ``O(ds^2)`` for the tangent, so the
corrector needs fewer Newton iterations (the corrected point is the same: it solves the
same equations). This is the polynomial extrapolation predictor of Allgower & Georg
(1990, *Numerical Continuation Methods*, Sec. 6.3; Lundberg & Poore 1991, SIAM J. Sci.
Stat. Comput. 12:695-723, for higher orders). It is used only on a smooth piece of
branch (consecutive tangents within ``HERMITE_MAX_TURN_DEG`` = 30 degrees) and never on a
retry after a rejected step, which always uses the tangent predictor.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..arguments import integer_at_least
from ..problem import exact_jacobian, jacobian_is_stability, step_kernel
from ..settings import ContinuationSettings
from .base import ContinuationAlgorithm, StepOutcome, StepState
from .corrector import NOISE_SLACK, ROUNDOFF_FLOOR, CorrectorResult
from .step import palc_point

#: The Hermite predictor is used only where consecutive tangents differ by at most this
#: angle (degrees, ``theta``-metric): where the steps resolve the branch's turning, so
#: that the cubic through the last two points is a faithful local model of it.
HERMITE_MAX_TURN_DEG = 30.0
_COS_HERMITE = math.cos(math.radians(HERMITE_MAX_TURN_DEG))

#: The compiled step's scalar arguments for the last ``(settings, PALC)`` pair used in
#: this thread, ``last = (array, settings, palc)`` (entries 0 and 1, ``ds`` and ``h``,
#: are overwritten every step; per thread, so concurrent runs never share it).
_SCALARS = threading.local()


@dataclass(frozen=True, kw_only=True)
class PALC(ContinuationAlgorithm):
    """Pseudo-arclength continuation with a bordered tangent predictor.

    A small frozen object: its parameters only (the compiled step's scalar arguments
    are cached per thread in this module, not on the object).

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
    predictor : {"hermite", "tangent"}
        ``"hermite"``: cubic Hermite extrapolation of the last two points when the
        branch is smooth there, else the tangent; ``"tangent"``: always the tangent.
    kernel : bool
        Run each step as one compiled call where the problem offers one
        (``problem.step_kernel()``: small dense systems with a CasADi trace;
        :mod:`continuation._kernel`). Same predictor, corrector,
        safeguards, tangent and eigenvalues; any step the kernel does not accept as a
        whole (a rejection, a singular matrix, ...) is redone by the Python step,
        which decides. ``False``: always the Python step.
    """

    max_angle_deg: float = 60.0
    grow_iters: int = 3
    max_contraction: float = 0.8
    max_distance: float = 1.0
    predictor: str = "hermite"
    kernel: bool = True
    _cos_max: float = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        max_angle_deg, grow_iters = self.max_angle_deg, self.grow_iters
        max_contraction, max_distance = self.max_contraction, self.max_distance
        predictor, kernel = self.predictor, self.kernel
        if not (0 < max_angle_deg <= 180):
            raise ValueError(f"`max_angle_deg` must be in (0, 180], got {max_angle_deg}")
        integer_at_least("grow_iters", grow_iters, 0)
        if not (0 < max_contraction < 1):
            raise ValueError(f"`max_contraction` must be in (0, 1), got {max_contraction!r}")
        if not (max_distance > 0 and math.isfinite(max_distance)):
            raise ValueError(f"`max_distance` must be a positive number, got {max_distance!r}")
        if predictor not in ("hermite", "tangent"):
            raise ValueError(f"`predictor` must be 'hermite' or 'tangent', got {predictor!r}")
        if not isinstance(kernel, bool):
            raise ValueError(f"`kernel` must be True or False, got {kernel!r}")
        set_ = object.__setattr__  # (frozen: the normalised values set once, here)
        set_(self, "max_angle_deg", float(max_angle_deg))
        set_(self, "max_contraction", float(max_contraction))
        set_(self, "max_distance", float(max_distance))
        set_(self, "_cos_max", math.cos(math.radians(max_angle_deg)))

    def step(
        self, problem: Any, state: StepState, settings: ContinuationSettings
    ) -> tuple[StepState, StepOutcome]:
        """One predictor-corrector step of length ``state.ds``."""
        if self.kernel:
            kern = step_kernel(problem)
            if kern is not None:
                done = self._kernel_step(kern, problem, state, settings)
                if done is not None:
                    return done
        a = state.point
        ds = state.ds
        tau = a.tau
        c = state.w * tau
        ua = a.u
        guarded = ds > settings.ds_min * (1 + 1e-12)
        u_lin = u_pred = ua + ds * tau
        d_prev = state.prev_d
        if (
            d_prev is not None
            and state.prev_tau is not None
            and not state.retries
            and self.predictor == "hermite"
            and float(c.dot(state.prev_tau)) >= _COS_HERMITE
        ):
            # q(ds) = u_a + ds tau_a + alpha E + beta F with E = -d_prev - h F, where
            # d_prev = u_a - (u_0 + h tau_0) was measured by the previous step's distance
            # safeguard and F = tau_0 - tau_a (see the module docstring)
            h = state.prev_h
            r = ds / h
            al = r * r * (3.0 + 2.0 * r)
            be = r * r * (h + ds)
            u_pred = u_lin - al * d_prev + (be - al * h) * (state.prev_tau - tau)
        d = None

        def near_predictor(res: CorrectorResult) -> str:
            # the distance safeguard, measured from the tangent predictor
            nonlocal d
            d = res.u - u_lin
            dist = math.sqrt(float((state.w * d).dot(d)))
            if dist > self.max_distance * ds:
                return f"corrected point {dist / ds:.3g} ds away from the predictor"
            return ""

        got = palc_point(
            problem,
            u_pred,
            ua,
            c,
            ds,
            state.w,
            settings.newton,
            accept=near_predictor if guarded else None,
            max_contraction=self.max_contraction if guarded else None,
            exact=False,
            # (with exact derivatives Newton's rate is quadratic, and a Jacobian one
            # iterate from the row is harmless where it is not the row's stability
            # matrix: the last linearisation may be skipped)
            predict_final=exact_jacobian(problem) and not jacobian_is_stability(problem),
        )
        res, b = got.res, got.point
        if b is None:
            state.retries += 1
            return state, StepOutcome(False, res.iters, res.residual_norm, 0.0, got.message)
        cos_angle = b.ctau  # = c . tau (make_point's border is c)
        if cos_angle < self._cos_max and guarded:
            state.retries += 1
            return state, StepOutcome(
                False,
                res.iters,
                res.residual_norm,
                0.0,
                f"tangent turned by {math.degrees(math.acos(max(-1.0, cos_angle))):.1f} deg",
            )
        new = StepState(b, ds, state.w, state.direction, state.n_steps + 1, d, tau, ds)
        return new, StepOutcome(True, res.iters, res.residual_norm, ds)

    def _kernel_step(
        self, kern: Any, problem: Any, state: StepState, settings: ContinuationSettings
    ) -> tuple[StepState, StepOutcome] | None:
        """:meth:`step` as one compiled call; None when the kernel did not accept the step.

        The Python step then runs and decides.
        """
        a = state.point
        ds = state.ds
        guarded = ds > settings.ds_min * (1 + 1e-12)
        d_prev = state.prev_d
        hermite = d_prev is not None and not state.retries and self.predictor == "hermite"
        sc = getattr(_SCALARS, "last", None)
        if sc is None or sc[1] is not settings or sc[2] is not self:
            nw, det = settings.newton, settings.detect
            arr = np.array([0.0, 1.0, _COS_HERMITE, self.max_contraction, self.max_distance,
                            self._cos_max, nw.tol, nw.step_tol, nw.max_iter, det.eig_tol,
                            det.imag_tol, NOISE_SLACK, ROUNDOFF_FLOOR])  # fmt: skip
            sc = _SCALARS.last = (arr, settings, self)
        arr = sc[0]
        arr[0] = ds
        arr[1] = state.prev_h if hermite else 1.0
        got = kern.step(a.u, a.tau, state.w, d_prev, state.prev_tau, arr, hermite, guarded,
                        jacobian_is_stability(problem))  # fmt: skip
        if got is None:
            return None
        b, it, rn, d = got
        new = StepState(b, ds, state.w, state.direction, state.n_steps + 1,
                        d if guarded else None, a.tau, ds)  # fmt: skip
        return new, StepOutcome(True, it, rn, ds)


__all__ = ["PALC"]
