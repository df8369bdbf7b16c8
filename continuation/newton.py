r"""Newton's method for :math:`G(z) = 0`, dense or sparse, with a status instead of prints."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .errors import ConvergenceError
from .settings import NewtonSettings
from .status import Status
from .typing import FloatArray

_GETRF, _GETRS = la.get_lapack_funcs(("getrf", "getrs"), (np.zeros(1),))


@dataclass(frozen=True)
class NewtonResult:
    """Outcome of :func:`newton`.

    Attributes
    ----------
    z : ndarray, shape (N,)
        Last iterate (the solution when ``converged``).
    converged : bool
        Whether the tolerances were met.
    iterations : int
        Number of Newton steps taken.
    residual_norm : float
        ``||G(z)||_inf`` at the last iterate.
    status : Status
        ``SUCCESS``, ``NEWTON_FAILED``, ``SINGULAR`` or ``NONFINITE``.
    message : str
        Human-readable explanation.
    """

    z: FloatArray
    converged: bool
    iterations: int
    residual_norm: float
    status: Status
    message: str


def solve_linear(A: Any, b: FloatArray) -> FloatArray:
    """Solve ``A x = b`` for dense ndarray or SciPy sparse ``A``; raises LinAlgError if singular."""
    if sp.issparse(A):
        factor = getattr(A, "condensed_lu", None)  # see linalg.BorderedLU
        lu = factor(A) if factor is not None else None
        if lu is None:
            lu = spla.splu(sp.csc_matrix(A))
        x = lu.solve(np.asarray(b, dtype=float))
    else:
        # LAPACK getrf/getrs directly: the factorisation of scipy.linalg.lu_factor without
        # its per-call overhead and without a LinAlgWarning on exactly singular matrices
        lu, piv, info = _GETRF(np.asarray(A, dtype=float))
        if info != 0:
            raise np.linalg.LinAlgError("singular matrix")
        x, info = _GETRS(lu, piv, np.asarray(b, dtype=float))
    if not np.all(np.isfinite(x)):
        raise np.linalg.LinAlgError("singular or ill-conditioned matrix")
    return np.asarray(x, dtype=float)


def newton(
    residual: Callable[[FloatArray], FloatArray],
    jacobian: Callable[[FloatArray], Any],
    z0: FloatArray,
    settings: NewtonSettings | None = None,
    *,
    throw: bool = False,
) -> NewtonResult:
    r"""Solve :math:`G(z) = 0` by Newton's method, :math:`z_{k+1} = z_k - J(z_k)^{-1} G(z_k)`.

    Parameters
    ----------
    residual : callable
        ``G(z) -> ndarray (N,)``.
    jacobian : callable
        ``J(z) -> ndarray (N, N)`` or SciPy sparse matrix.
    z0 : ndarray, shape (N,)
        Starting guess.
    settings : NewtonSettings, optional
        Tolerances and iteration limit.
    throw : bool
        Raise :class:`ConvergenceError` instead of returning a failed result.

    Returns
    -------
    NewtonResult
    """
    s = settings or NewtonSettings()
    z = np.array(z0, dtype=float)
    if not np.all(np.isfinite(z)):
        raise ValueError("`z0` contains NaN or inf")
    g = np.asarray(residual(z), dtype=float)
    rn = float(np.max(np.abs(g))) if g.size else 0.0
    status, msg = Status.NEWTON_FAILED, ""
    it = 0
    converged = False
    if not np.isfinite(rn):
        status, msg = Status.NONFINITE, "residual is not finite at the starting guess"
    else:
        step_norm = np.inf
        while it < s.max_iter:
            if rn <= s.tol and step_norm <= s.step_tol * (1 + np.max(np.abs(z))):
                converged = True
                break
            try:
                dz = solve_linear(jacobian(z), g)
            except (np.linalg.LinAlgError, RuntimeError) as exc:
                status, msg = Status.SINGULAR, f"singular Jacobian at iteration {it}: {exc}"
                break
            lam = 1.0
            z_new = z - dz
            g_new = np.asarray(residual(z_new), dtype=float)
            rn_new = float(np.max(np.abs(g_new))) if g_new.size else 0.0
            if s.damping:
                tries = 0
                while (not np.isfinite(rn_new) or rn_new > rn) and tries < 10:
                    lam *= 0.5
                    z_new = z - lam * dz
                    g_new = np.asarray(residual(z_new), dtype=float)
                    rn_new = float(np.max(np.abs(g_new)))
                    tries += 1
            it += 1
            step_norm = lam * float(np.max(np.abs(dz))) if dz.size else 0.0
            z, g, rn = z_new, g_new, rn_new
            if not np.isfinite(rn):
                status, msg = Status.NONFINITE, f"residual became non-finite at iteration {it}"
                break
            if rn <= s.tol and step_norm <= s.step_tol * (1 + np.max(np.abs(z))):
                converged = True
                break
    if converged:
        status, msg = Status.SUCCESS, f"converged in {it} iterations (|G|={rn:.2e})"
    elif not msg:
        msg = (
            f"Newton did not converge in {s.max_iter} iterations (|G|={rn:.2e} > tol={s.tol:.1e})."
        )
    result = NewtonResult(z, converged, it, rn, status, msg)
    if throw and not converged:
        raise ConvergenceError(msg)
    return result


__all__ = ["NewtonResult", "newton", "solve_linear"]
