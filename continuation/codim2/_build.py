r"""Residuals and exact derivatives of the augmented fold and Hopf systems.

Each augmented residual :math:`G(z, p_2; P, c)` is written once as a *recipe* in
terms of ``f(x)``, ``J(x) = df/dx`` and a few vector operations. With a CasADi
trace of the system the recipe is applied to ``SX`` symbols, so ``dG/dz`` and
``dG/dp_2`` are exact (they contain the second derivatives of ``f`` that the
Moore-Spence and Roose-Hlavacek systems need). For NumPy-only systems the same
recipe is evaluated numerically and differentiated by central differences.

``P`` is the full parameter vector (its entries at the two free positions are
ignored) and ``c`` the normalisation data of the Hopf system (vector and target
value, shape ``(n+1,)``), so they stay inputs of the compiled functions and a
problem can change them without a new trace.
"""

from __future__ import annotations

import weakref
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np
import scipy.sparse as sp

from ..differentiation import fd_jacobian
from ..system import System
from ..typing import FloatArray

Recipe = Callable[..., Any]


@dataclass(frozen=True)
class _VecOps:
    """The few vector operations a recipe needs, for one backend."""

    matvec: Callable[[Any, Any], Any]
    dot: Callable[[Any, Any], Any]
    vertcat: Callable[..., Any]


_CA_VEC = _VecOps(ca.mtimes, ca.dot, ca.vertcat)
_NP_VEC = _VecOps(
    lambda A, v: np.asarray(A) @ v,
    lambda a, b: np.array([float(np.dot(a, b))]),
    lambda *xs: np.concatenate([np.atleast_1d(np.asarray(x, dtype=float)) for x in xs]),
)


def fold_recipe(n: int, x: Any, z: Any, f: Any, J: Any, c: Any, vo: _VecOps) -> Any:
    r"""Moore-Spence fold system, ``z = (x, p1, v)``, shape ``(2n+1,)``.

    .. math::

        G = \begin{pmatrix} f(x, p_1, p_2) \\ J(x, p_1, p_2)\, v \\
            \tfrac12 (v^T v - 1) \end{pmatrix}

    (Moore & Spence 1980, "The calculation of turning points of nonlinear
    equations", SIAM J. Numer. Anal. 17, 567-576; here with the normalisation
    ``|v| = 1``, which never degenerates along the curve.) ``c`` is unused.

    The system is regular at nondegenerate folds, and also at cusp and
    Bogdanov-Takens points (there ``J`` still has a one-dimensional kernel).
    """
    v = z[n + 1 : 2 * n + 1]
    return vo.vertcat(f, vo.matvec(J, v), 0.5 * (vo.dot(v, v) - 1.0))


def hopf_recipe(n: int, x: Any, z: Any, f: Any, J: Any, c: Any, vo: _VecOps) -> Any:
    r"""Roose-Hlavacek Hopf system, ``z = (x, p1, kappa, v)``, shape ``(2n+2,)``.

    .. math::

        G = \begin{pmatrix} f \\ (J^2 + \kappa I)\, v \\ c^T v - 1 \\
            c^T J v - \sigma + \kappa / \sigma \end{pmatrix}

    with normalisation data ``c = (c_1..c_n, sigma)``, ``sigma > 0``.

    At a Hopf point ``J`` has eigenvalues :math:`\pm i\omega`, ``kappa = omega**2``
    and ``v`` spans, with ``J v``, the real critical eigenspace (Roose &
    Hlavacek 1985, "A direct method for the computation of Hopf bifurcation
    points", SIAM J. Appl. Math. 45, 879-894; Kuznetsov 2004, "Elements of
    Applied Bifurcation Theory", 3rd ed., Sec. 10.2.2); for ``kappa < 0`` the
    solutions are neutral saddles (eigenvalues :math:`\pm\mu`, ``mu**2 = -kappa``).

    The target :math:`s(\kappa) = \sigma - \kappa/\sigma` of the second
    normalisation replaces the usual ``0``, for two reasons:

    * with ``c^T J v = 0`` every fold point (``kappa = 0``, ``J v = 0``) solves the
      system too, so the fold curve crosses the Hopf curve at each
      Bogdanov-Takens point and the Jacobian is singular there; ``s(0) = sigma != 0``
      excludes ``J v = 0``;
    * on the neutral-saddle side the Jacobian is singular wherever ``v`` is a real
      eigenvector of ``J``, which for ``v = a e_+ + b e_-`` happens exactly when
      ``s = ±mu``; ``s(kappa)**2 + kappa = sigma**2 - kappa + kappa**2/sigma**2 > 0``
      for every ``kappa``, so ``s(kappa) > mu`` and this never occurs.
    """
    kappa = z[n + 1]
    v = z[n + 2 : 2 * n + 2]
    cv, sigma = c[:n], c[n]
    Jv = vo.matvec(J, v)
    return vo.vertcat(
        f,
        vo.matvec(J, Jv) + kappa * v,
        vo.dot(cv, v) - 1.0,
        vo.dot(cv, Jv) - sigma + kappa / sigma,
    )


@dataclass(frozen=True)
class AugmentedFunctions:
    r"""Compiled residual of one augmented system and its derivatives.

    All callables take ``(z, p2, P, c)``: ``z`` shape ``(N,)``, ``p2`` scalar,
    ``P`` shape ``(m,)`` (full parameter vector), ``c`` shape ``(n+1,)``
    (normalisation data; zeros where unused).

    Attributes
    ----------
    G : callable
        Residual, shape ``(N,)``.
    dGdz : callable
        ``dG/dz``, dense ``(N, N)`` ndarray.
    dGdz_sparse : callable
        ``dG/dz`` as SciPy CSC.
    dGdp : callable
        ``dG/dp2``, shape ``(N,)``.
    linearize : callable
        ``linearize(z, p2, P, c, sparse) -> (G, dG/dz, dG/dp2)`` in one evaluation.
    bvv : callable
        ``bvv(x, Pv, v)``: the second directional derivative
        :math:`B(v, v) = \frac{d^2}{dt^2} f(x + t v)|_{t=0}`, shape ``(n,)``, with
        ``Pv`` the parameter vector in use.
    cvvv : callable
        ``cvvv(x, Pv, v)``: the third directional derivative
        :math:`C(v, v, v) = \frac{d^3}{dt^3} f(x + t v)|_{t=0}`, shape ``(n,)``.
    bmap : callable
        ``bmap(x, Pv, U, W)``: the bilinear form :math:`B(u_j, w_j)` for the columns
        of ``U``, ``W`` (shape ``(n, k)``), in one evaluation; shape ``(n, k)``.
    cmap : callable
        ``cmap(x, Pv, V)``: :math:`C(v_j, v_j, v_j)` for the columns of ``V``;
        shape ``(n, k)``.
    exact : bool
        True when built from a CasADi trace.
    """

    G: Callable[..., FloatArray]
    dGdz: Callable[..., FloatArray]
    dGdz_sparse: Callable[..., Any]
    dGdp: Callable[..., FloatArray]
    linearize: Callable[..., tuple[Any, Any, Any]]
    bvv: Callable[..., FloatArray]
    cvvv: Callable[..., FloatArray]
    bmap: Callable[..., FloatArray]
    cmap: Callable[..., FloatArray]
    exact: bool


def _param_expr(P: Any, p1: Any, p2: Any, i1: int, i2: int, m: int) -> Any:
    entries = [P[k] for k in range(m)]
    entries[i1] = p1
    entries[i2] = p2
    return ca.vertcat(*entries)


def param_vector(P: FloatArray, p1: float, p2: float, i1: int, i2: int) -> FloatArray:
    """``P`` with entries ``i1``, ``i2`` set to ``p1``, ``p2``; shape ``(m,)``."""
    v = np.array(P, dtype=float)
    v[i1] = p1
    v[i2] = p2
    return v


def _build_casadi(
    system: System, recipe: Recipe, n_unknowns: int, i1: int, i2: int
) -> AugmentedFunctions:
    n, m = system.n_states, system.n_params
    Z = ca.SX.sym("z", n_unknowns)
    p2 = ca.SX.sym("p2")
    P = ca.SX.sym("P", m)
    C = ca.SX.sym("c", n + 1)
    X = Z[:n]
    Pv = _param_expr(P, Z[n], p2, i1, i2, m)
    F = system.symbolic(X, Pv)
    J = ca.jacobian(F, X)
    G = recipe(n, X, Z, F, J, C, _CA_VEC)
    fG = ca.Function("G", [Z, p2, P, C], [G])
    fJz = ca.Function("dGdz", [Z, p2, P, C], [ca.jacobian(G, Z)])
    Gz, Gp = ca.jacobian(G, Z), ca.jacobian(G, p2)
    fJp = ca.Function("dGdp", [Z, p2, P, C], [Gp])
    fLin = ca.Function("linearize", [Z, p2, P, C], [G, Gz, Gp])
    # B(v, v) = d/dx (J v) . v, with an unconstrained parameter vector.
    Xb = ca.SX.sym("x", n)
    Pb = ca.SX.sym("p", m)
    Vb = ca.SX.sym("v", n)
    Fb = system.symbolic(Xb, Pb)
    Jv = ca.jtimes(Fb, Xb, Vb)
    Bvv = ca.jtimes(Jv, Xb, Vb)
    fB = ca.Function("bvv", [Xb, Pb, Vb], [Bvv])
    fC = ca.Function("cvvv", [Xb, Pb, Vb], [ca.jtimes(Bvv, Xb, Vb)])
    Wb = ca.SX.sym("w", n)
    fB2 = ca.Function("buw", [Xb, Pb, Vb, Wb], [ca.jtimes(Jv, Xb, Wb)])
    maps: dict[tuple[str, int], ca.Function] = {}

    def mapped(fn: ca.Function, k: int) -> ca.Function:
        key = (fn.name(), k)
        if key not in maps:
            maps[key] = fn.map(k)
        return maps[key]

    def G_(z: FloatArray, p: float, Pf: FloatArray, c: FloatArray) -> FloatArray:
        return np.asarray(fG(z, p, Pf, c), dtype=float).reshape(-1)

    def Jz(z: FloatArray, p: float, Pf: FloatArray, c: FloatArray) -> FloatArray:
        return np.asarray(fJz(z, p, Pf, c), dtype=float)

    def Jz_sparse(z: FloatArray, p: float, Pf: FloatArray, c: FloatArray) -> Any:
        return sp.csc_matrix(fJz(z, p, Pf, c).sparse())

    def Jp(z: FloatArray, p: float, Pf: FloatArray, c: FloatArray) -> FloatArray:
        return np.asarray(fJp(z, p, Pf, c), dtype=float).reshape(-1)

    def lin(z: FloatArray, p: float, Pf: FloatArray, c: FloatArray, sparse: bool) -> Any:
        g, gz, gp = fLin(z, p, Pf, c)
        gz_out = sp.csc_matrix(gz.sparse()) if sparse else np.asarray(gz, dtype=float)
        return (
            np.asarray(g, dtype=float).reshape(-1),
            gz_out,
            np.asarray(gp, dtype=float).reshape(-1),
        )

    def B(x: FloatArray, Pv_: FloatArray, v: FloatArray) -> FloatArray:
        return np.asarray(fB(x, Pv_, v), dtype=float).reshape(-1)

    def C3(x: FloatArray, Pv_: FloatArray, v: FloatArray) -> FloatArray:
        return np.asarray(fC(x, Pv_, v), dtype=float).reshape(-1)

    def Bmap(x: FloatArray, Pv_: FloatArray, U: FloatArray, W: FloatArray) -> FloatArray:
        k = np.shape(U)[1]
        return np.asarray(mapped(fB2, k)(x, Pv_, U, W), dtype=float).reshape(n, k)

    def Cmap(x: FloatArray, Pv_: FloatArray, V: FloatArray) -> FloatArray:
        k = np.shape(V)[1]
        return np.asarray(mapped(fC, k)(x, Pv_, V), dtype=float).reshape(n, k)

    return AugmentedFunctions(G_, Jz, Jz_sparse, Jp, lin, B, C3, Bmap, Cmap, True)


def _build_numpy(
    system: System, recipe: Recipe, n_unknowns: int, i1: int, i2: int
) -> AugmentedFunctions:
    n = system.n_states

    def G_(z: FloatArray, p: float, Pf: FloatArray, c: FloatArray) -> FloatArray:
        z = np.asarray(z, dtype=float)
        x = z[:n]
        Pv = param_vector(Pf, z[n], p, i1, i2)
        f = system.f(x, Pv)
        J = system.jacobian(x, Pv)
        return np.asarray(recipe(n, x, z, f, J, np.asarray(c, float), _NP_VEC), dtype=float)

    def Jz(z: FloatArray, p: float, Pf: FloatArray, c: FloatArray) -> FloatArray:
        return fd_jacobian(lambda w: G_(w, p, Pf, c), np.asarray(z, dtype=float))

    def Jz_sparse(z: FloatArray, p: float, Pf: FloatArray, c: FloatArray) -> Any:
        return sp.csc_matrix(Jz(z, p, Pf, c))

    def Jp(z: FloatArray, p: float, Pf: FloatArray, c: FloatArray) -> FloatArray:
        col = fd_jacobian(lambda q: G_(z, q[0], Pf, c), np.array([float(p)]))
        return col.reshape(-1)

    def lin(z: FloatArray, p: float, Pf: FloatArray, c: FloatArray, sparse: bool) -> Any:
        gz = Jz(z, p, Pf, c)
        return G_(z, p, Pf, c), (sp.csc_matrix(gz) if sparse else gz), Jp(z, p, Pf, c)

    def _h(x: FloatArray, v: FloatArray, power: float) -> float:
        h = np.finfo(float).eps ** power * max(1.0, float(np.max(np.abs(x))))
        return h / max(1.0, float(np.max(np.abs(v))))

    def B(x: FloatArray, Pv: FloatArray, v: FloatArray) -> FloatArray:
        x, v = np.asarray(x, dtype=float), np.asarray(v, dtype=float)
        h = _h(x, v, 0.25)
        return (system.f(x + h * v, Pv) - 2 * system.f(x, Pv) + system.f(x - h * v, Pv)) / h**2

    def C3(x: FloatArray, Pv: FloatArray, v: FloatArray) -> FloatArray:
        x, v = np.asarray(x, dtype=float), np.asarray(v, dtype=float)
        h = _h(x, v, 0.2)
        fs = [system.f(x + k * h * v, Pv) for k in (2, 1, -1, -2)]
        return (fs[0] - 2 * fs[1] + 2 * fs[2] - fs[3]) / (2 * h**3)

    def Bmap(x: FloatArray, Pv: FloatArray, U: FloatArray, W: FloatArray) -> FloatArray:
        cols = [
            0.25 * (B(x, Pv, U[:, j] + W[:, j]) - B(x, Pv, U[:, j] - W[:, j]))
            for j in range(np.shape(U)[1])
        ]
        return np.column_stack(cols)

    def Cmap(x: FloatArray, Pv: FloatArray, V: FloatArray) -> FloatArray:
        return np.column_stack([C3(x, Pv, V[:, j]) for j in range(np.shape(V)[1])])

    return AugmentedFunctions(G_, Jz, Jz_sparse, Jp, lin, B, C3, Bmap, Cmap, False)


_CACHE: weakref.WeakKeyDictionary[System, dict[tuple[str, int, int], AugmentedFunctions]] = (
    weakref.WeakKeyDictionary()
)


def augmented_functions(
    system: System, kind: str, recipe: Recipe, n_unknowns: int, i1: int, i2: int
) -> AugmentedFunctions:
    """Build (once per system, kind and parameter pair) the augmented functions."""
    try:
        per_system = _CACHE.setdefault(system, {})
    except TypeError:  # not weak-referenceable: no caching
        per_system = {}
    key = (kind, i1, i2)
    if key not in per_system:
        build = _build_casadi if getattr(system, "has_casadi", False) else _build_numpy
        per_system[key] = build(system, recipe, n_unknowns, i1, i2)
    return per_system[key]


__all__ = [
    "AugmentedFunctions",
    "augmented_functions",
    "fold_recipe",
    "hopf_recipe",
    "param_vector",
]
