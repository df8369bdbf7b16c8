r"""One-shot equilibrium solves and de-duplication modulo periodic states."""

from __future__ import annotations

import logging
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from .errors import ConvergenceError
from .newton import NewtonResult, newton
from .params import Params
from .settings import NewtonSettings
from .stability import n_unstable, sort_eigenvalues
from .status import Status
from .typing import ComplexArray, FloatArray

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class EquilibriumResult(NewtonResult):
    """A :class:`~continuation.newton.NewtonResult` with the eigen-data of the point.

    Attributes
    ----------
    eigenvalues : ndarray, shape (n,) complex
        Eigenvalues of ``df/dx`` at ``z``, sorted by decreasing real part (NaN if the
        solve failed).
    eigenvectors : ndarray, shape (n, n) complex or None
        Unit eigenvectors, column ``k`` for ``eigenvalues[k]``.
    n_unstable : int
        Saddle index (-1 if the solve failed).
    params : Params or None
        The parameters of the solve.
    """

    eigenvalues: ComplexArray | None = None
    eigenvectors: Any = None
    n_unstable: int = -1
    params: Params | None = None

    @property
    def x(self) -> FloatArray:
        """The equilibrium (alias of ``z``), shape ``(n,)``."""
        return self.z

    @property
    def stable(self) -> bool:
        """Converged and no eigenvalue with positive real part."""
        return self.converged and self.n_unstable == 0


def solve_equilibrium(
    system: Any,
    x0: Any,
    params: Any,
    settings: NewtonSettings | None = None,
    throw: bool = True,
    *,
    eig_tol: float = 1e-10,
) -> EquilibriumResult:
    """Solve ``f(x, p) = 0`` by Newton's method from ``x0`` and return eigen-data.

    Parameters
    ----------
    system : System
    x0 : array_like, shape (n,)
        Initial guess.
    params : Params, mapping or array_like (m,)
        Parameter values.
    settings : NewtonSettings, optional
    throw : bool
        Raise :class:`~continuation.errors.ConvergenceError` if Newton fails (default).
    eig_tol : float
        Threshold on real parts for the saddle index.

    Returns
    -------
    EquilibriumResult
    """
    x = system.check_state(x0, "x0")
    par = system.as_params(params)
    pv = np.array(par.values)
    res = newton(lambda z: system.f(z, pv), lambda z: system.jacobian(z, pv), x, settings)
    if not res.converged:
        if throw:
            raise ConvergenceError(res.message)
        nan = np.full(system.n_states, np.nan + 0j)
        return EquilibriumResult(
            res.z,
            False,
            res.iterations,
            res.residual_norm,
            res.status,
            res.message,
            eigenvalues=nan,
            eigenvectors=None,
            n_unstable=-1,
            params=par,
        )
    vals, vecs = np.linalg.eig(np.asarray(system.jacobian(res.z, pv), dtype=float))
    vals = np.asarray(vals, dtype=complex)
    order = np.lexsort((-vals.imag, -vals.real))
    vals, vecs = vals[order], np.asarray(vecs, complex)[:, order]
    return EquilibriumResult(
        res.z,
        True,
        res.iterations,
        res.residual_norm,
        Status.SUCCESS,
        res.message,
        eigenvalues=sort_eigenvalues(vals),
        eigenvectors=vecs,
        n_unstable=n_unstable(vals, eig_tol),
        params=par,
    )


def unique_equilibria(system: Any, points: Iterable[Any], tol: float = 1e-6) -> FloatArray:
    """Remove duplicates from a list of points, modulo the periods of periodic states.

    Two points are the same when ``max |system.difference(x1, x2)| <= tol`` (so ``x`` and
    ``x + period`` coincide). The first representative of each class is kept, in the
    input order, unchanged (not wrapped).

    Parameters
    ----------
    system : System
        Supplies ``difference`` and ``n_states``.
    points : iterable of array_like (n,), or ndarray (k, n)
        Candidate points; ``EquilibriumResult`` objects are accepted too (their ``z``).
    tol : float
        Max-norm tolerance.

    Returns
    -------
    ndarray, shape (k_unique, n)
    """
    if not (np.isfinite(tol) and tol >= 0):
        raise ValueError(f"`tol` must be a non-negative number, got {tol}")
    n = system.n_states
    keep: list[FloatArray] = []
    for k, pt in enumerate(points):
        x = np.asarray(getattr(pt, "z", pt), dtype=float)
        if x.shape != (n,):
            raise ValueError(f"`points[{k}]` must have shape ({n},), got {x.shape}")
        if not np.all(np.isfinite(x)):
            raise ValueError(f"`points[{k}]` contains NaN or inf")
        if any(np.max(np.abs(system.difference(x, y))) <= tol for y in keep):
            continue
        keep.append(x)
    return np.array(keep, dtype=float).reshape(len(keep), n)


__all__ = ["EquilibriumResult", "solve_equilibrium", "unique_equilibria"]
