r"""Newton's method with few Jacobians: for systems whose Jacobian costs many residuals.

:func:`simplified_newton` solves ``G(z) = 0`` keeping the factorised Jacobian ``J_0``
of the last refresh for as long as the residual contracts fast, and (by default)
correcting it between refreshes by Broyden's rank-one updates, applied in product
form to ``J_0^{-1}`` so that nothing but the sparse LU of ``J_0`` is ever stored:

.. math::

    B_{k+1} = B_k + \frac{G(z_{k+1})\, s_k^T}{s_k^T s_k}, \qquad
    B_{k+1}^{-1} = \Bigl(I + \frac{s_{k+1} s_k^T}{s_k^T s_k}\Bigr) B_k^{-1},

so the next step is ``s_{k+1} = w / (1 - s_k^T w / s_k^T s_k)`` with
``w = -(\prod_j (I + s_{j+1} s_j^T / s_j^T s_j)) J_0^{-1} G(z_{k+1})``
(Broyden 1965, Math. Comp. 19:577-593; the product form: Kelley 2003, *Solving
Nonlinear Equations with Newton's Method*, SIAM, Sec. 4.3, algorithm ``brsol``).
Without the updates (``broyden=False``) it is the chord method with Jacobian
refreshes, Shamanskii's modification of Newton's method (Kelley 2003, Sec. 2.3.3).

The Jacobian is refreshed (and the Broyden history dropped) when an iteration reduces
``max |G|`` by less than the factor ``refresh``, or when a step does not reduce it at
all; a step from a fresh Jacobian that increases the residual is halved up to 10 times
(damping). Near the solution Broyden's method converges q-superlinearly (Dennis & Moré
1974), so for a collocation system whose Jacobian costs about five residuals one
Jacobian and a handful of residuals usually suffice.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import ConvergenceError
from ..newton import NewtonResult
from ..settings import NewtonSettings
from ..status import Status
from ..typing import FloatArray

#: Largest number of Broyden updates kept before the Jacobian is refreshed.
MAX_UPDATES = 30


class JacobianCache:
    """The last factorised Jacobian of :func:`simplified_newton`, kept between calls.

    Pass the same instance to a sequence of solves of nearby problems (the points of a
    curve, one after the other): each starts from the factorisation the previous one
    ended with instead of evaluating and factorising a new Jacobian, and refreshes it
    only when the residual stops contracting fast. ``n_factorisations`` counts the
    Jacobians factorised through this cache.
    """

    __slots__ = ("solve", "n_factorisations")

    def __init__(self) -> None:
        self.solve: Callable[[FloatArray], FloatArray] | None = None
        self.n_factorisations = 0

    def clear(self) -> None:
        """Forget the factorisation (the next solve evaluates a fresh Jacobian)."""
        self.solve = None


def _factorise(J: Any) -> Callable[[FloatArray], FloatArray]:
    if sp.issparse(J):
        lu = spla.splu(sp.csc_matrix(J))
        return lu.solve
    import scipy.linalg as la

    fac = la.lu_factor(np.asarray(J, dtype=float), check_finite=False)
    return lambda b: la.lu_solve(fac, b, check_finite=False)


def simplified_newton(
    residual: Callable[[FloatArray], FloatArray],
    jacobian: Callable[[FloatArray], Any],
    z0: FloatArray,
    settings: NewtonSettings | None = None,
    *,
    broyden: bool = True,
    refresh: float = 0.3,
    throw: bool = False,
    cache: JacobianCache | None = None,
) -> NewtonResult:
    r"""Solve ``G(z) = 0`` with few Jacobian evaluations (see the module docstring).

    Parameters
    ----------
    residual : callable
        ``z -> G(z)``, shape ``(N,)``.
    jacobian : callable
        ``z -> dG/dz``, dense ``(N, N)`` or SciPy sparse.
    z0 : ndarray, shape (N,)
        Initial guess.
    settings : NewtonSettings, optional
        ``tol`` (on ``max |G|``) and ``max_iter`` (iterations, i.e. steps) are used.
    broyden : bool
        Broyden rank-one updates between Jacobian refreshes (else plain chord steps).
    refresh : float
        In (0, 1): the Jacobian is refreshed after an iteration that reduces ``max |G|``
        by less than this factor.
    throw : bool
        Raise :class:`~continuation.errors.ConvergenceError` on failure.
    cache : JacobianCache, optional
        Start from its factorisation (if any) instead of a fresh Jacobian; on return
        it holds the factorisation in use at the end (see :class:`JacobianCache`).

    Returns
    -------
    NewtonResult
        ``iterations`` counts steps (residual evaluations after the first);
        ``message`` also gives the number of Jacobians.

    Raises
    ------
    ValueError
        If ``z0`` is not a finite 1-D array or ``refresh`` is not in (0, 1).
    """
    settings = settings if settings is not None else NewtonSettings()
    if not isinstance(settings, NewtonSettings):
        raise ValueError(f"`settings` must be a NewtonSettings, got {type(settings).__name__}")
    if not (isinstance(refresh, float | int) and 0.0 < refresh < 1.0):
        raise ValueError(f"`refresh` must be in (0, 1), got {refresh!r}")
    if cache is not None and not isinstance(cache, JacobianCache):
        raise ValueError(f"`cache` must be a JacobianCache, got {type(cache).__name__}")
    z = np.array(z0, dtype=float)
    if z.ndim != 1 or not np.all(np.isfinite(z)):
        raise ValueError("`z0` must be a finite 1-D array")
    tol, max_iter = settings.tol, settings.max_iter
    # a factorisation handed over by the cache counts as old (refreshed on stagnation)
    solve: Callable[[FloatArray], FloatArray] | None = None if cache is None else cache.solve

    def fail(status: Status, msg: str, it: int, rn: float) -> NewtonResult:
        if cache is not None:
            cache.solve = solve
        if throw:
            raise ConvergenceError(msg)
        return NewtonResult(z, False, it, rn, status, msg)

    g = np.asarray(residual(z), dtype=float).reshape(-1)
    rn = float(np.max(np.abs(g))) if g.size else 0.0
    if not math.isfinite(rn):
        return fail(Status.NONFINITE, "non-finite residual at the initial guess", 0, rn)
    steps: list[FloatArray] = []  # Broyden history s_j and their squared norms
    norms: list[float] = []
    n_jac, it = 0, 0
    while rn > tol:
        if it >= max_iter:
            return fail(
                Status.NEWTON_FAILED,
                f"no convergence in {max_iter} iterations (|G|={rn:.2e}, {n_jac} Jacobians)",
                it,
                rn,
            )
        fresh = solve is None
        if fresh:
            try:
                solve = _factorise(jacobian(z))
            except (RuntimeError, np.linalg.LinAlgError, ValueError) as exc:
                return fail(Status.SINGULAR, f"singular Jacobian: {exc}", it, rn)
            n_jac += 1
            if cache is not None:
                cache.n_factorisations += 1
            steps.clear()
            norms.clear()
        assert solve is not None
        s = -np.asarray(solve(g), dtype=float)
        if broyden and steps:
            for j in range(len(steps) - 1):
                s += steps[j + 1] * (float(steps[j].dot(s)) / norms[j])
            denom = 1.0 - float(steps[-1].dot(s)) / norms[-1]
            if not (abs(denom) > 1e-12 and math.isfinite(denom)):
                solve = None  # degenerate update: start again from a fresh Jacobian
                continue
            s /= denom
        if not np.all(np.isfinite(s)):
            if fresh:
                return fail(Status.NONFINITE, "non-finite Newton step", it, rn)
            solve = None
            continue
        lam = 1.0
        z_new = z + s
        g_new = np.asarray(residual(z_new), dtype=float).reshape(-1)
        rn_new = float(np.max(np.abs(g_new)))
        if not (rn_new < rn) and not fresh:
            solve = None  # the old Jacobian no longer gives descent: refresh, retry
            continue
        tries = 0
        while not (rn_new <= rn) and tries < 10:  # fresh Jacobian: damp the step
            lam *= 0.5
            z_new = z + lam * s
            g_new = np.asarray(residual(z_new), dtype=float).reshape(-1)
            rn_new = float(np.max(np.abs(g_new)))
            tries += 1
        if not (rn_new <= rn):
            return fail(Status.NEWTON_FAILED, f"no descent along the Newton step (|G|={rn:.2e})",
                        it, rn)  # fmt: skip
        it += 1
        contraction = rn_new / rn if rn > 0 else 0.0
        z, g, rn = z_new, g_new, rn_new
        if rn <= tol:
            break
        if contraction > refresh or lam < 1.0 or len(steps) >= MAX_UPDATES:
            solve = None
        elif broyden:
            steps.append(s if lam == 1.0 else lam * s)
            norms.append(float(steps[-1].dot(steps[-1])))
    if cache is not None:
        cache.solve = solve if solve is not None else cache.solve
    return NewtonResult(
        z,
        True,
        it,
        rn,
        Status.SUCCESS,
        f"converged in {it} iterations with {n_jac} Jacobians (|G|={rn:.2e})",
    )


__all__ = ["MAX_UPDATES", "JacobianCache", "simplified_newton"]
