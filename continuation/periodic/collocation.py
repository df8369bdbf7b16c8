r"""Orthogonal collocation of a periodic orbit: residual, sparse Jacobian, blocks.

A cycle of :math:`\dot x = f(x, p)` with period ``T`` is written in the scaled time
:math:`\tau = t / T \in [0, 1]` as :math:`x'(\tau) = T f(x, p)`. On the
:class:`~continuation.bvp.collocation.CollocationMesh` (``N`` intervals, Gauss-Legendre
degree ``m``) the unknowns are the values at all ``M = N (m + 1) + 1`` points
(mesh nodes and collocation points) and ``T``::

    z = [X_0, X_1, ..., X_{M-1}, T]         X_q in R^n, point-major (z[q n + i])

and the equations, in the one row order of connections, landings and cycles
(:class:`~continuation.bvp.layout.OrbitLayout`: collocation, continuity, then the
problem's boundary conditions; the Jacobian is block banded in the unknowns)::

    collocation  (1/h_j) sum_l D[k,l] X_{j,l} - T f(X_{j,k}, P) = 0   rows s n + i, s = j m + k
    continuity   sum_l e[l] X_{j,l} - x_{j+1} = 0                     rows n N m + j n + i
    periodicity  x_N - x_0 - k o period = 0                           (n)
    phase        sum_j h_j sum_k b_k <X_{j,k} - ref_{j,k}, ref'_{j,k}> = 0    (1)

``X_{j,0} = x_j`` is mesh node ``j``; ``k o period`` is the winding ``k_i`` times the
period of each periodic state (a *rotation orbit* advances a circle coordinate by
``k_i`` periods per cycle; ``k = 0`` is an ordinary cycle). The phase condition is
the integral condition of Doedel (AUTO) against a reference orbit ``ref`` (the
previous point of the branch), which removes the time-shift invariance. Periodicity
and phase are the cycle's boundary conditions, where a connection has its
equilibria, Riccati and projection rows and a landing its start point.

The right-hand side and its derivatives come from the system's CasADi trace mapped
over the ``N m`` collocation points in one call (NumPy loop for systems without a
trace). Everything is assembled into a SciPy CSC matrix on a fixed pattern: the
pattern (and its COO-to-CSC permutation) is built once per layout, every Jacobian
shares its index arrays, and carries a ``condensed_lu`` hook
(:class:`~continuation.bvp.condense.StageCondenser`: the collocation rows of interval
``j`` involve only its own ``m`` stage values besides the nodes, so the stages are
eliminated interval by interval before a small dense LU, as AUTO-07p does; the
condenser of connections and landings too, on the same stage blocks), which the
driver's :class:`~continuation.linalg.BorderedLU` and Newton solves use instead of a
general sparse LU.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from .._jit import compiled
from ..bvp.collocation import CollocationMesh, stage_points
from ..bvp.condense import KERNELS as _CONDENSE_KERNELS
from ..bvp.condense import StageCondenser
from ..bvp.layout import OrbitLayout
from ..casadi_compile import compiled_soon, settled
from ..typing import FloatArray

#: CasADi functions per system, outside the system object (so that pickling a system,
#: e.g. for sweep workers, does not carry them; they are rebuilt where needed).
_SYSTEM_CACHE: weakref.WeakKeyDictionary[Any, dict[str, dict[Any, Any]]] = (
    weakref.WeakKeyDictionary()
)


def _cache_of(system: Any, name: str) -> dict[Any, Any]:
    return _SYSTEM_CACHE.setdefault(system, {}).setdefault(name, {})


def _point_functions(system: Any, free: int | None) -> tuple[Any, Any]:
    """``f`` and ``(f, f_x, f_p)`` of one point as dense SX functions.

    Built once per system and free parameter (kept beside the system: every mesh and every
    problem of a branch shares them; ``free`` not None: ``f_p`` is the one column
    ``df/dp_free``, by forward differentiation, instead of all ``n_par`` columns).
    """
    import casadi as ca

    cache = _cache_of(system, "fns")
    key = -1 if free is None else int(free)
    if key in cache:
        return cache[key]  # type: ignore[no-any-return]
    n, m = system.n_states, system.n_params
    x, p = ca.SX.sym("x", n), ca.SX.sym("p", max(m, 0))
    fx = system.symbolic(x, p)
    # one expression graph for f and both Jacobians (shared subexpressions: about
    # 1.4x faster than calling three separate functions)
    jx = ca.jacobian(fx, x)
    if free is None:
        jp = ca.jacobian(fx, p)
    else:
        jp = ca.jtimes(fx, p, ca.DM.eye(m)[:, key])
    f_one = ca.Function("f_pt", [x, p], [ca.densify(fx)])
    all_one = ca.Function("fjp_pt", [x, p], [ca.densify(fx), ca.densify(jx), ca.densify(jp)])
    cache[key] = (f_one, all_one)
    return f_one, all_one


def _mapped(system: Any, free: int | None, K: int) -> tuple[Any, Any]:
    """The point functions of :func:`_point_functions` mapped over ``K`` points (cached)."""
    cache = _cache_of(system, "maps")
    key = (-1 if free is None else int(free), int(K))
    if key not in cache:
        f_one, all_one = _point_functions(system, free)
        cache[key] = (f_one.map("f_map", "serial", K, [1], []),
                      all_one.map("fjp_map", "serial", K, [1], []))  # fmt: skip
    return cache[key]  # type: ignore[no-any-return]


@dataclass(frozen=True, eq=False)
class StageEvaluator:
    """``f``, ``f_x`` and ``f_p`` of a system on many points at once.

    Parameters
    ----------
    system : System
    n_points : int
        Number of points evaluated per call.
    free : int, optional
        Index of the continuation parameter: :meth:`all` then returns the one column
        ``df/dp_free`` of ``f_p``, shape ``(K, n, 1)`` (cheaper than all columns).
    """

    system: Any
    n_points: int
    free: int | None = None

    def __post_init__(self) -> None:
        if getattr(self.system, "has_casadi", False) and self.system.n_params > 0:
            fb, ab = _mapped(self.system, self.free, self.n_points)
            n, m, K = self.system.n_states, self.system.n_params, self.n_points
            # dense outputs evaluated in place through CasADi's buffer interface
            # (no DM conversions: about 3x less overhead per call than DM calls)
            _BUFFERS[self] = [_Buffered(fb, K, n, m, (n,)),
                              _Buffered(ab, K, n, m, (n, n * n, n * self.n_p)), False]  # fmt: skip

    def _upgrade(self) -> None:
        """Switch ``f, f_x, f_p`` to the compiled function once it is available.

        See :func:`continuation.casadi_compile.compiled_soon` (a large model only).
        """
        buf = _BUFFERS[self]
        point = _point_functions(self.system, self.free)[1]
        fn = compiled_soon(point)
        if fn is None:
            if settled(point):
                buf[2] = None  # the virtual machine for good: stop asking
            return
        cache = _cache_of(self.system, "maps")
        key = ("compiled", -1 if self.free is None else int(self.free), int(self.n_points))
        if key not in cache:
            cache[key] = fn.map("fjp_map_c", "serial", self.n_points, [1], [])
        n, m = self.system.n_states, self.system.n_params
        buf[1] = _Buffered(cache[key], self.n_points, n, m, (n, n * n, n * self.n_p))
        buf[2] = True

    @property
    def n_p(self) -> int:
        """Number of ``f_p`` columns :meth:`all` returns."""
        return int(self.system.n_params) if self.free is None else 1

    def f(self, Xs: FloatArray, P: FloatArray) -> FloatArray:
        """``f`` at the rows of ``Xs`` (K, n) -> (K, n)."""
        buf = _BUFFERS.get(self)
        if buf is not None and Xs.shape == (self.n_points, self.system.n_states):
            return buf[0](Xs, P)[0].copy()
        return np.array([self.system.f(x, P) for x in Xs])

    def all(self, Xs: FloatArray, P: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``(f (K, n), f_x (K, n, n), f_p (K, n, n_p))`` at the rows of ``Xs``."""
        K, n = Xs.shape
        npar = self.n_p
        buf = _BUFFERS.get(self)
        if buf is not None and K == self.n_points and n == self.system.n_states:
            if buf[2] is False:
                self._upgrade()
            Fo, Jo, Po = buf[1](Xs, P)
            # column-major CasADi blocks: Jo[k] holds f_x(X_k)^T, Po[k] f_p(X_k)^T
            J = Jo.reshape(K, n, n).transpose(0, 2, 1).copy()
            Jp = Po.reshape(K, npar, n).transpose(0, 2, 1).copy()
            return Fo.copy(), J, Jp
        F = np.array([self.system.f(x, P) for x in Xs])
        J = np.array([self.system.jacobian(x, P) for x in Xs])
        m = int(np.size(P))
        Jp = np.array([np.asarray(self.system.dfdp(x, P)).reshape(n, m) for x in Xs])
        if self.free is not None:
            Jp = Jp[:, :, self.free : self.free + 1]
        return F, J, Jp


class _Buffered:
    """A mapped CasADi function with dense outputs, evaluated in preallocated arrays.

    Inputs: the ``K`` points ``(K, n)`` (column-major ``(n, K)`` for CasADi) and the
    parameters ``(n_par,)``; outputs: one ``(K, w)`` array per output width ``w``.
    """

    def __init__(self, fn: Any, K: int, n: int, n_par: int, widths: tuple[int, ...]) -> None:
        self._fn = fn  # (kept alive with its buffer)
        self._buf, self._run = fn.buffer()
        self._x = np.zeros((K, n))
        self._p = np.zeros(n_par)
        self._out = tuple(np.zeros((K, w)) for w in widths)
        self._buf.set_arg(0, memoryview(self._x))
        self._buf.set_arg(1, memoryview(self._p))
        for i, o in enumerate(self._out):
            self._buf.set_res(i, memoryview(o))

    def __call__(self, Xs: FloatArray, P: FloatArray) -> tuple[FloatArray, ...]:
        self._x[...] = Xs
        self._p[...] = P
        self._run()
        return self._out


#: Buffered evaluators per StageEvaluator (outside the instance: it stays picklable).
_BUFFERS: weakref.WeakKeyDictionary[Any, list[Any]] = weakref.WeakKeyDictionary()


#: Index patterns of this many layout sizes ``(n, N, m)`` are kept (oldest dropped).
PATTERNS_KEPT = 8
_PATTERNS: dict[tuple[Any, ...], dict[str, Any]] = {}


class CollocationLayout:
    """Index bookkeeping of the discretised cycle on one mesh (see module doc).

    The orbit's unknowns and its collocation and continuity rows are those of every
    collocated orbit (:attr:`orbit`, a :class:`~continuation.bvp.layout.OrbitLayout`);
    this class adds the cycle's own unknown ``T`` (column :attr:`T_col`), its boundary
    rows (periodicity from :attr:`row_period`, the phase row :attr:`row_phase`), the CSC
    pattern of the compiled kernel and the condenser of the layout's stage blocks.

    Parameters
    ----------
    n : int
        State dimension.
    mesh : CollocationMesh
        Nodes and degree (its ``T`` is not used).
    """

    def __init__(self, n: int, mesh: CollocationMesh) -> None:
        # the index arrays, the CSC pattern and its condenser depend on (n, N, m) only:
        # shared by all meshes of that size (a branch re-meshed every few steps builds
        # them once, and the condenser's structures are reused)
        key = (int(n), mesh.n_intervals, mesh.degree, np.asarray(mesh.e).tobytes())
        shared = _PATTERNS.get(key)
        if shared is None:
            obj = CollocationLayout.__new__(CollocationLayout)
            obj._indices(n, mesh)
            shared = dict(obj.__dict__)
            if len(_PATTERNS) >= PATTERNS_KEPT:
                del _PATTERNS[next(iter(_PATTERNS))]
            _PATTERNS[key] = shared
        self.__dict__.update(shared)
        self.mesh = mesh
        # quadrature weights of the stage points (sum = 1)
        self.weights = (mesh.h[:, None] * mesh.b[None, :]).ravel()  # (N m,)
        self._B_const = (mesh.D[None, :, :] / mesh.h[:, None, None])[..., None, None] * np.eye(n)

    def _indices(self, n: int, mesh: CollocationMesh) -> None:
        """The mesh-independent part of :meth:`__init__`."""
        self.n = n
        N, m = mesh.n_intervals, mesh.degree
        self.N, self.m = N, m
        # the one orbit layout of connections, landings and cycles
        self.orbit = OrbitLayout(n, N, m)
        self.M = mesh.n_points
        self.n_unknowns = n * self.M + 1
        # stage point indices (N m,) in interval order
        self.stage_points = stage_points(N, m)
        # block pattern of the collocation rows: (N, m, m+1, n, n)
        rows_b, cols_b = self.orbit.collocation_blocks()
        self._col_rows = rows_b.ravel()
        self._col_cols = cols_b.ravel()
        # continuity rows: d/dX_{j,l} = e[l] I, d/dx_{j+1} = -I (values by the kernel)
        rows_c, cols_c, _ = self.orbit.continuity_entries(mesh.e)
        # the boundary conditions: periodicity rows, then the phase row
        rp = self.orbit.boundary_row + np.arange(n)
        self.row_period = int(rp[0])
        self.row_phase = int(rp[-1]) + 1
        self._const_rows = np.concatenate([rows_c, rp, rp])
        self._const_cols = np.concatenate([cols_c, (self.M - 1) * n + np.arange(n), np.arange(n)])
        self._const_vals = np.concatenate([np.ones(n), -np.ones(n)])  # periodicity
        # T column of the collocation rows (row s n + i of stage s)
        self._T_rows = np.arange(self.orbit.continuity_row)
        self.T_col = n * self.M
        self.stage_rows = self._T_rows.reshape(N * m, n)  # row of stage s, component i
        self._build_pattern()

    def _build_pattern(self) -> None:
        """The CSC pattern of ``dG/dz`` and the permutation of :meth:`assemble`'s values."""
        n, M = self.n, self.M
        self._ph_cols = (self.stage_points[:, None] * n + np.arange(n)[None, :]).ravel()
        rows = np.concatenate(
            [self._col_rows, self._const_rows, self._T_rows,
             np.full(self._ph_cols.size, self.row_phase)]
        )  # fmt: skip
        cols = np.concatenate(
            [self._col_cols, self._const_cols, np.full(self._T_rows.size, self.T_col),
             self._ph_cols]
        )  # fmt: skip
        size = n * M + 1
        # positions in the kernel's values (continuation.bvp._collocation_jit): the
        # blocks, the (unused) f_p values, the continuity entries, then the cycle's own
        nB, nS = self._col_rows.size, self._T_rows.size
        pos = np.concatenate([np.arange(nB), nB + nS + np.arange(rows.size - nB)])
        srt = np.lexsort((rows, cols))  # column-major, rows sorted within a column
        order = pos[srt]
        self._n_vals = int(nS + rows.size)  # the kernel's values, f_p ones included
        key = cols[srt].astype(np.int64) * size + rows[srt]
        first = np.concatenate(([True], key[1:] != key[:-1]))
        slot = np.cumsum(first) - 1  # CSC slot of each sorted value
        self._order = order
        self._slot_of = None if bool(np.all(first)) else slot  # duplicates: summed
        ukey = key[first]
        indices = (ukey % size).astype(np.int32)
        indptr = np.searchsorted(ukey // size, np.arange(size + 1)).astype(np.int32)
        template = sp.csc_matrix((np.ones(ukey.size), indices, indptr), shape=(size, size))
        template.has_canonical_format  # noqa: B018  (flag checked once, shared)
        # stage condensation: the collocation rows and stage unknowns of interval j, the
        # same blocks as a connection's (OrbitLayout.stage_blocks)
        self.condenser = StageCondenser(*self.orbit.stage_blocks())
        template.condensed_lu = self.condenser.factor
        self._template = template

    # ------------------------------------------------------------------ unpacking
    def split(self, z: FloatArray) -> tuple[FloatArray, float]:
        """``(X (M, n), T)`` from the unknown vector."""
        n, M = self.n, self.M
        return z[: n * M].reshape(M, n), float(z[n * M])

    def join(self, X: FloatArray, T: float) -> FloatArray:
        """Inverse of :meth:`split`."""
        return np.concatenate([np.asarray(X, dtype=float).reshape(-1), [float(T)]])

    def blocks(self, X: FloatArray, T: float, J: FloatArray) -> FloatArray:
        r"""Collocation Jacobian blocks ``B[j, k, l] = D[k,l]/h_j I - [l = k+1] T f_x``.

        Shape ``(N, m, m + 1, n, n)`` (``J``: ``f_x`` at the stages, ``(N m, n, n)``).
        """
        N, m, n = self.N, self.m, self.n
        B = self._B_const.copy()  # D[k,l]/h_j I, the same at every evaluation
        Js = J.reshape(N, m, n, n)
        for k in range(m):
            B[:, k, k + 1] -= T * Js[:, k]
        return B

    def kernel_args(self) -> tuple[Any, ...]:
        """The layout's constant arrays in the order of the compiled kernel.

        See :func:`continuation.bvp._collocation_jit.cycle_linearize`: ``D, e, h, weights,
        stage_points,
        B_const (flat), const_vals (the periodicity entries), order, slot_of (empty:
        none)``.
        """
        args = self.__dict__.get("_kernel_args")
        if args is None:
            mesh = self.mesh
            f64 = np.ascontiguousarray
            args = (
                f64(mesh.D, dtype=float), f64(mesh.e, dtype=float), f64(mesh.h, dtype=float),
                f64(self.weights, dtype=float), f64(self.stage_points, dtype=np.int64),
                f64(self._B_const, dtype=float).ravel(), f64(self._const_vals, dtype=float),
                f64(self._order, dtype=np.int64),
                np.zeros(0, dtype=np.int64) if self._slot_of is None
                else f64(self._slot_of, dtype=np.int64),
            )  # fmt: skip
            self.__dict__["_kernel_args"] = args
        return args  # type: ignore[no-any-return]


def monodromy_factors(layout: CollocationLayout, B: FloatArray, stages: bool = False) -> Any:
    r"""Transfer matrices :math:`\Phi_j` of the linearised collocation equations.

    Condensation of the block structure: on interval ``j`` the linearised collocation
    rows :math:`\sum_l B_{j,k,l} \delta X_{j,l} = 0` are solved for the stage
    perturbations in terms of the left node, :math:`\delta X_{j,1..m} = -K_j^{-1}
    B_{j,:,0} \delta x_j` (:math:`K_j = [B_{j,k,l}]_{k, l \ge 1}`), and continuity gives
    :math:`\delta x_{j+1} = \Phi_j \delta x_j` with

    .. math:: \Phi_j = e_0 I - \sum_{l \ge 1} e_l\,[K_j^{-1} B_{j,:,0}]_l .

    ``Phi_{N-1} ... Phi_0`` is the monodromy matrix of the Gauss-Legendre (Runge-Kutta)
    discretisation of the variational equation :math:`y' = T f_x(x(\tau)) y`, i.e.
    of the collocation system itself; its eigenvalues are the Floquet multipliers to
    the order ``2 m`` of the method.

    Returns
    -------
    ndarray, shape (N, n, n)
        The ``Phi_j``; with ``stages=True`` also the stage responses
        ``S[j, l] = dX_{j,l} / dx_j``, shape ``(N, m, n, n)``.
    """
    N, m, n = layout.N, layout.m, layout.n
    e = layout.mesh.e
    K = B[:, :, 1:].transpose(0, 1, 3, 2, 4).reshape(N, m * n, m * n)
    R = B[:, :, 0].reshape(N, m * n, n)
    X: np.ndarray = np.empty((N, m * n, n))  # block LU and solves in one compiled call
    if not compiled(_CONDENSE_KERNELS).solve_many(np.array(K), np.ascontiguousarray(R), X):
        X = np.linalg.solve(K, R)  # a singular block: raises LinAlgError
    S = -X.reshape(N, m, n, n)  # stage responses
    Phi = (e[1:] @ S.reshape(N, m, n * n)).reshape(N, n, n)  # sum_l e_l S_l
    Phi += e[0] * np.eye(n)
    return (Phi, S) if stages else Phi


__all__ = ["CollocationLayout", "StageEvaluator", "monodromy_factors"]
