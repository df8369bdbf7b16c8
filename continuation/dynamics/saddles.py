r"""Local analysis of equilibria: Newton refinement, sorted eigen-data, unstable directions.

Eigenvalues are sorted by decreasing real part, then decreasing imaginary part; an
eigenvalue counts as unstable when its real part exceeds
``eig_tol * max(1, max|lambda|)``.

Sign convention of the unstable eigenvector ``v_u`` of an index-1 saddle (so that
"upslope/downslope" is reproducible): its *reference component* is positive. The
reference component is the state named by ``orient`` if given; otherwise the first
periodic state if its component is at least ``1e-3`` of the largest one (for the ship:
``+v_u`` increases ``xi_G``); otherwise the largest component
(:func:`reference_component`). The left eigenvector ``w_u`` is scaled so that
``w_u . v_u = 1`` (:func:`left_unstable_vector`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..newton import newton
from ..settings import NewtonSettings
from ..typing import ComplexArray, FloatArray
from ._common import state_period

#: Newton settings of :func:`refine_equilibrium` (and of the equilibrium tracker).
REFINE_NEWTON = NewtonSettings(tol=1e-11, step_tol=1e-10, max_iter=30)


def eig_sorted(J: FloatArray) -> tuple[ComplexArray, Any]:
    """Eigenvalues ``(n,)`` and right eigenvectors ``(n, n)`` of ``J``, sorted (module notes)."""
    vals, vecs = np.linalg.eig(np.asarray(J, dtype=float))
    order = np.lexsort((-vals.imag, -vals.real))
    return np.asarray(vals, complex)[order], np.asarray(vecs, complex)[:, order]


def n_unstable_of(vals: ComplexArray, eig_tol: float = 1e-9) -> int:
    """Number of eigenvalues ``vals (n,)`` with real part above ``eig_tol max(1, max|lambda|)``."""
    return int(np.sum(vals.real > unstable_threshold(vals, eig_tol)))


def unstable_threshold(vals: ComplexArray, eig_tol: float = 1e-9) -> float:
    """``eig_tol * max(1, max|lambda|)`` (``eig_tol`` for no eigenvalues)."""
    return eig_tol * (max(1.0, float(np.max(np.abs(vals)))) if vals.size else 1.0)


def reference_component(v: FloatArray, period: FloatArray) -> int:
    """Index of the component of ``v (n,)`` that the orientation makes positive (module notes)."""
    big = float(np.max(np.abs(v)))
    cand = [k for k in np.flatnonzero(period > 0) if abs(v[k]) >= 1e-3 * big]
    return int(cand[0]) if cand else int(np.argmax(np.abs(v)))


def refine_equilibrium(
    system: Any,
    x: Any,
    p: FloatArray,
    *,
    settings: NewtonSettings | None = None,
    eig_tol: float = 1e-9,
    name: str = "x",
    max_move: float = 5e-2,
) -> tuple[FloatArray, ComplexArray, Any, int]:
    """Newton-refine an equilibrium and return ``(x, eigenvalues, eigenvectors, n_unstable)``.

    Parameters
    ----------
    system : System
    x : array_like, shape (n,)
        A point near an equilibrium.
    p : ndarray, shape (m,)
        Parameter vector.
    settings : NewtonSettings, optional
    eig_tol : float
        Real parts above ``eig_tol * max(1, max|lambda|)`` count as unstable.
    name : str
        Argument name for error messages.
    max_move : float
        Largest allowed correction of each component ``i``, relative to
        ``max(1, |x_i|)``: Newton may not wander to another equilibrium.

    Raises
    ------
    ValueError
        If Newton does not converge from ``x``, or converges further than ``max_move``
        away (the point is not near an equilibrium).
    """
    x0 = system.check_state(x, name) if hasattr(system, "check_state") else np.asarray(x, float)
    res = newton(
        lambda z: system.f(z, p),
        lambda z: system.jacobian(z, p),
        x0,
        settings or REFINE_NEWTON,
    )
    if not res.converged:
        raise ValueError(f"`{name}` is not close to an equilibrium: {res.message}")
    moves = np.abs(res.z - x0)
    move = float(np.max(moves))
    if np.any(moves > max_move * np.maximum(1.0, np.abs(x0))):
        raise ValueError(
            f"`{name}` is not close to an equilibrium: Newton moved it by {move:.3g} to {res.z}"
        )
    vals, vecs = eig_sorted(system.jacobian(res.z, p))
    n_unst = n_unstable_of(vals, eig_tol)
    return np.asarray(res.z, dtype=float), vals, vecs, n_unst


def oriented_unstable_direction(
    system: Any,
    J: FloatArray,
    *,
    orient: str | int | None = None,
    scale: Any = None,
    eig_tol: float = 1e-9,
) -> tuple[float, FloatArray, ComplexArray]:
    """Unstable eigenvalue and oriented unit eigenvector of an index-1 saddle.

    Parameters
    ----------
    system : System
        Supplies state names and periods for the orientation.
    J : ndarray, shape (n, n)
        Jacobian at the saddle.
    orient : str or int, optional
        State whose component of ``v_u`` is made positive.
    scale : array_like (n,), optional
        ``v_u`` has unit norm in ``||v / scale||_2``.
    eig_tol : float
        Real parts within ``eig_tol * max(1, max|lambda|)`` of zero count as zero.

    Returns
    -------
    (lambda_u, v_u, eigenvalues)

    Raises
    ------
    ValueError
        If ``J`` has not exactly one eigenvalue with positive real part, or an
        eigenvalue on the imaginary axis (not hyperbolic), or ``orient`` names a
        state whose component vanishes.
    """
    n = J.shape[0]
    vals, vecs = eig_sorted(J)
    thr = unstable_threshold(vals, eig_tol)
    n_unst = int(np.sum(vals.real > thr))
    if n_unst != 1:
        raise ValueError(
            f"`x_saddle` must have exactly one unstable eigenvalue (saddle of index 1; only "
            f"1-D unstable manifolds are supported), got {n_unst}: eigenvalues {vals}"
        )
    if np.any(np.abs(vals.real) <= thr):
        raise ValueError(f"`x_saddle` is not hyperbolic (eigenvalue on the imaginary axis): {vals}")
    lam = float(vals[0].real)
    v = np.real(vecs[:, 0])
    s = np.ones(n) if scale is None else np.asarray(scale, dtype=float).reshape(n)
    v = v / np.linalg.norm(v / s)
    names = tuple(system.state_names)
    if orient is not None:
        i = names.index(orient) if isinstance(orient, str) and orient in names else orient
        if not isinstance(i, (int, np.integer)) or not 0 <= int(i) < n:
            raise ValueError(f"`orient` must be a state name or index, got {orient!r}")
        i = int(i)
        if abs(v[i]) <= 1e-9 * np.max(np.abs(v)):
            raise ValueError(f"`orient` state {names[i]!r} has no component along v_u")
    else:
        i = reference_component(v, state_period(system, n))
    if v[i] < 0:
        v = -v
    return lam, v, vals


def left_unstable_vector(J: FloatArray, period: FloatArray) -> FloatArray | None:
    """Left unstable eigenvector ``w_u (n,)`` with ``w_u . v_u = 1`` of a saddle's ``J (n, n)``.

    ``v_u`` is the right eigenvector of the eigenvalue with the largest real part,
    oriented by :func:`reference_component`. ``None`` if that eigenvalue is complex or
    ``w_u . v_u`` vanishes. The caller checks that the saddle has index 1.
    """
    J = np.asarray(J, dtype=float)
    lam, V = eig_sorted(J)
    if abs(lam[0].imag) > 1e-12 * max(1.0, abs(lam[0])):
        return None
    v = np.real(V[:, 0])
    if v[reference_component(v, period)] < 0:
        v = -v
    lamL, W = eig_sorted(J.T)  # left eigenvectors: same eigenvalues
    k = int(np.argmin(np.abs(lamL - lam[0])))
    w = np.real(W[:, k])
    wv = float(np.dot(w, v))
    if not math.isfinite(wv) or abs(wv) <= 1e-12 * np.linalg.norm(w) * np.linalg.norm(v):
        return None
    return w / wv


__all__ = [
    "eig_sorted",
    "left_unstable_vector",
    "oriented_unstable_direction",
    "reference_component",
    "refine_equilibrium",
]
