"""Immutable, self-validating settings for Newton solves and continuation."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from .arguments import integer_at_least, positive


@dataclass(frozen=True, kw_only=True)
class NewtonSettings:
    """Settings of Newton's method.

    Attributes
    ----------
    tol : float
        Converged when ``||G(z)||_inf <= tol`` and the last Newton step is below
        ``step_tol``. The continuation corrector
        (:func:`continuation.algorithms.corrector.correct`) also accepts a stalled iteration
        whose residual is above ``tol`` but at the round-off level of ``G``'s terms
        (backward error ``<= 64 eps``), never any other residual.
    step_tol : float
        Tolerance on the last Newton step. In the continuation corrector it is
        componentwise: ``|dz_i| <= step_tol * (|z_i| + min(1, ||z||_inf))`` for every
        unknown (the free parameter included); the plain equilibrium solver
        (:mod:`continuation.newton`) tests ``||dz||_inf <= step_tol * (1 + ||z||_inf)``.
    max_iter : int
        Maximum number of iterations.
    damping : bool
        Halve the step (up to 10 times) when the residual does not decrease.
    """

    tol: float = 1e-10
    step_tol: float = 1e-8
    max_iter: int = 20
    damping: bool = False

    def __post_init__(self) -> None:
        positive("tol", self.tol)
        positive("step_tol", self.step_tol)
        integer_at_least("max_iter", self.max_iter, 1)


@dataclass(frozen=True, kw_only=True)
class DetectionSettings:
    """Which special points to detect, and whether to locate them.

    Attributes
    ----------
    fold, hopf, branch_point : bool
        Detect these kinds of special point.
    locate : bool
        Locate detected points to ``tol`` (otherwise only bracket them).
    tol : float
        Location tolerance on the arclength (``theta``-norm): a located point is
        within ``tol`` of the zero of its test function along the branch, unless its
        ``SpecialPoint.error`` states more (a noisy test function, or a point next
        to a branch point that the corrector determines only to ``sqrt(|G|)``).
    max_iter : int
        Maximum iterations of the locator.
    eig_tol : float
        Real parts with ``|Re| <= eig_tol`` count as zero when counting unstable
        eigenvalues.
    imag_tol : float
        An eigenvalue counts as complex when ``|Im| > imag_tol * max(1, |lambda|)``.
    n_eigs : int
        For large sparse problems (sparse Jacobian and ``n > dense_eigs_max``) only
        the ``n_eigs`` eigenvalues nearest ``eig_sigma`` are computed, by ARPACK
        shift-invert (``scipy.sparse.linalg.eigs``); the others are stored as NaN and
        ``n_unstable`` counts among the computed ones. This is exact as long as every
        eigenvalue with positive real part is among the ``n_eigs`` nearest ``eig_sigma``
        (the usual situation near the first instabilities; raise ``n_eigs`` if not).
    eig_sigma : float
        Shift of the shift-invert eigenvalue solve.
    dense_eigs_max : int
        Problems up to this size always get all eigenvalues by dense LAPACK.
    """

    fold: bool = True
    hopf: bool = True
    branch_point: bool = True
    locate: bool = True
    tol: float = 1e-10
    max_iter: int = 50
    eig_tol: float = 1e-10
    imag_tol: float = 1e-8
    n_eigs: int = 6
    eig_sigma: float = 0.0
    dense_eigs_max: int = 100

    def __post_init__(self) -> None:
        positive("tol", self.tol)
        positive("eig_tol", self.eig_tol)
        positive("imag_tol", self.imag_tol)
        integer_at_least("max_iter", self.max_iter, 1)
        integer_at_least("n_eigs", self.n_eigs, 1)
        integer_at_least("dense_eigs_max", self.dense_eigs_max, 0)
        if not math.isfinite(self.eig_sigma):
            raise ValueError(f"`eig_sigma` must be finite, got {self.eig_sigma!r}")


@dataclass(frozen=True, kw_only=True)
class ContinuationSettings:
    """Settings of pseudo-arclength continuation.

    Attributes
    ----------
    ds : float
        Initial signed step; its sign picks the direction (``+`` increases the
        free parameter at the start).
    ds_min, ds_max : float
        Bounds on ``|ds|``; the branch stops with ``Status.DS_MIN`` below ``ds_min``.
    p_min, p_max : float
        Bounds on the free parameter; the branch stops on reaching one.
    max_steps : int
        Maximum number of continuation steps (each direction).
    theta : float
        Weight of the parameter in the arclength norm, in (0, 1]:
        ``||(dz, dp)||_theta**2 = (1 - theta) * |dz|**2 / N + theta * dp**2``
        (``N`` unknowns). ``theta = 1`` degenerates to natural parameter stepping,
        which cannot pass folds.
    grow, shrink : float
        Step-size factors on easy convergence / failure.
    newton : NewtonSettings
        Corrector settings.
    detect : DetectionSettings
        Special-point detection settings.
    """

    ds: float = 1e-2
    ds_min: float = 1e-8
    ds_max: float = 1e-1
    p_min: float = -math.inf
    p_max: float = math.inf
    max_steps: int = 500
    theta: float = 0.5
    grow: float = 1.5
    shrink: float = 0.5
    newton: NewtonSettings = field(default_factory=NewtonSettings)
    detect: DetectionSettings = field(default_factory=DetectionSettings)

    def __post_init__(self) -> None:
        for name in ("ds", "ds_min", "ds_max"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v)):
                raise ValueError(f"`{name}` must be a finite number, got {v!r}")
        if not (self.ds_max >= abs(self.ds) >= self.ds_min > 0):
            raise ValueError(
                "need ds_max >= |ds| >= ds_min > 0, got "
                f"ds_max={self.ds_max}, ds={self.ds}, ds_min={self.ds_min}"
            )
        if not self.p_min < self.p_max:
            raise ValueError(f"need p_min < p_max, got p_min={self.p_min}, p_max={self.p_max}")
        integer_at_least("max_steps", self.max_steps, 1)
        if not (0 < self.theta <= 1):
            raise ValueError(f"`theta` must be in (0, 1], got {self.theta}")
        if not self.grow >= 1:
            raise ValueError(f"`grow` must be >= 1, got {self.grow}")
        if not (0 < self.shrink < 1):
            raise ValueError(f"`shrink` must be in (0, 1), got {self.shrink}")


__all__ = ["NewtonSettings", "DetectionSettings", "ContinuationSettings"]
