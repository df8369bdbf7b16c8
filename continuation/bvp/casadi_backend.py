r"""Residual and Jacobians of a connecting orbit: CasADi boundary rows, compiled orbit rows.

One core for every orbit that ends at a saddle: a *connection* (it starts at a saddle
too, with a phase condition) and a *landing* (:mod:`continuation.bvp.landing`: it starts
at a given point ``x_0``, which fixes the time shift, so there is no phase condition).
The two differ only in their start condition (:attr:`ConnectionLayout.start_point`).

:func:`build_connection_functions` turns a :class:`~continuation.system.System`
and an unknown-vector :class:`ConnectionLayout` into :class:`ConnectionFunctions`, which
evaluates, for the inputs ``(w, P, h, T, Qm, Qp, shift, ref, dref, pin)``,

* the residual ``G`` (``(n_eq,)``),
* ``dG/dw`` (sparse ``(n_eq, n_eq)``), its exact Jacobian in the unknowns ``w``,
* ``dG/dP`` (sparse ``(n_eq, n_params)``), its exact Jacobian in the full parameter
  vector ``P``,

in two parts. The collocation and continuity rows and their derivatives are filled by
the compiled kernel every collocated orbit shares (:mod:`continuation.bvp._collocation_jit`,
the one of periodic orbits too) from ``f``, ``f_x`` and ``f_p`` at the ``N m`` stages.
The stage values and the boundary rows (equilibria, Riccati, projections, start point,
phase) with their exact Jacobians by automatic differentiation come from one CasADi
expression graph (``ca.Function`` s built once, expanded to SX for small systems). Every
quantity that may change without changing the *structure* of the problem (mesh spacing
``h``, truncation time ``T``, reference Schur bases ``Qm``/``Qp``, the periodic
``shift``, the phase-condition reference orbit and the pinned value) is a numeric
input. Adapting the mesh with a fixed number of intervals, changing ``T`` or updating a
reference therefore never rebuilds the functions. The right-hand side is the system's
own CasADi trace, evaluated on all ``N m`` collocation points at once through
``Function.map``.

Unknowns, in this order (see :class:`ConnectionLayout`)::

    w = [ vec(X) (n M),  x_-  (n),  [x_+ (n)],  vec(R_-) ((n-k_-) k_-),
          vec(R_+) ((n-k_+) k_+),  unknown parameters (q) ]

with ``X`` the ``(n, M)`` matrix of values at the ``M = N (m + 1) + 1`` mesh and
collocation points (interval by interval, so the Jacobian is almost block
banded). The orbit block and the collocation and continuity rows are placed by
:class:`~continuation.bvp.layout.OrbitLayout`, the layout periodic orbits use too (the
CSC patterns are built here from its index arrays). Equations, in this order::

    collocation   (1/(h_j T)) sum_l D[k,l] X_{j,l} - f(X_{j,k}, P)         (n N m)
    continuity    sum_l e[l] X_{j,l} - x_{j+1}                              (n N)
    equilibria    f(x_-, P) = 0   [and f(x_+, P) = 0]                       (n or 2n)
    Riccati (-)   T21 + T22 R - R T11 - R T12 R = 0,  T = Qm^T A_-^T Qm     ((n-k_-) k_-)
    boundary (-)  (Qm_1 + Qm_2 R_-)^T (x(0) - x_-) = 0                      (k_-)
    Riccati (+)   same with Qp and A_+^T                                    ((n-k_+) k_+)
    boundary (+)  (Qp_1 + Qp_2 R_+)^T (x(T) - x_+) = 0                      (k_+)
    phase         sum_j h_j sum_k b_k <X_{j,k} - ref_{j,k}, dref_{j,k}> = 0   or   pin  (1)

``A_pm = df/dx(x_pm, P)``; ``x_+ = x_- + shift`` when the end point is the start
point shifted by a period. The Riccati blocks make the projection boundary
conditions smooth functions of the unknowns (see :mod:`continuation.bvp.connection`).

A landing layout (``start_point=True``) has no ``x_-``, no ``R_-`` and no phase row;
its end equilibrium ``x_e`` is the ``x_to`` block with ``x_+ = x_e + shift``, and the
start rows ``x(0) - x_0 = 0`` (``n``) come after continuity::

    w = [ vec(X),  x_e (n),  vec(R_+),  unknown parameters (q = k_+) ]
    collocation, continuity, start (n), f(x_e, P) = 0 (n), Riccati (+), boundary (+)

The numeric inputs after ``w`` and ``P`` are :meth:`ConnectionLayout.data_names`.
"""

from __future__ import annotations

import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np
import scipy.sparse as sp

from .. import _jit
from ..casadi_compile import compilation_allowed, compiled
from ..linalg import csc_with_data
from ..typing import FloatArray
from .collocation import CollocationMesh, stage_points
from .condense import StageCondenser
from .layout import OrbitLayout


@dataclass(frozen=True)
class ConnectionLayout(OrbitLayout):
    """Sizes and positions of the unknowns of a discretised connection.

    An :class:`~continuation.bvp.layout.OrbitLayout` (the orbit's unknowns and its
    collocation and continuity rows, shared with cycles) with the connection's own
    unknowns and boundary rows.

    Attributes
    ----------
    n : int
        State dimension.
    n_intervals, degree : int
        ``N`` and ``m`` of the mesh.
    separate_to : bool
        ``x_+`` is its own unknown (else ``x_+ = x_- + shift``).
    k_minus : int
        ``dim E^s(A_-^T) = n - dim W^u(x_-)``: boundary conditions at ``t = 0``.
    k_plus : int
        ``dim E^u(A_+^T) = n - dim W^s(x_+)``: boundary conditions at ``t = T``.
    unknown_param_index : tuple of int
        Positions, in the full parameter vector, of the parameters solved for.
    pin : tuple of int or None
        ``(state index, mesh node index)`` of a pinned-value phase condition, or
        None for the integral phase condition.
    start_point : bool
        The orbit starts at a given point ``x_0`` (a landing): ``k_minus = 0``, no
        ``x_-``, no phase condition; ``x_to`` is the end equilibrium ``x_e`` and the
        end point ``x_e + shift``.
    """

    n: int
    n_intervals: int
    degree: int
    separate_to: bool
    k_minus: int
    k_plus: int
    unknown_param_index: tuple[int, ...]
    pin: tuple[int, int] | None
    start_point: bool = False

    def __post_init__(self) -> None:
        if self.start_point and (self.k_minus or self.pin is not None or self.separate_to):
            raise ValueError(
                "a start-point layout has no start saddle, no phase condition and its end "
                "equilibrium as the `x_to` block (k_minus=0, pin=None, separate_to=False)"
            )

    def _sizes(self) -> list[tuple[str, int]]:
        n, km, kp = self.n, self.k_minus, self.k_plus
        return [
            ("orbit", n * self.n_points),
            ("x_from", 0 if self.start_point else n),
            ("x_to", n if self.separate_to or self.start_point else 0),
            ("R_minus", (n - km) * km),
            ("R_plus", (n - kp) * kp),
            ("params", len(self.unknown_param_index)),
        ]

    def slices(self) -> dict[str, slice]:
        """Slices of each block in ``w``."""
        out, pos = {}, 0
        for name, size in self._sizes():
            out[name] = slice(pos, pos + size)
            pos += size
        return out

    @property
    def n_unknowns(self) -> int:
        """Length of ``w``."""
        return sum(s for _, s in self._sizes())

    # ------------------------------------------------------------------ packing
    def checked(self, z: Any) -> FloatArray:
        """``z`` as a float array, checked to have shape ``(n_unknowns,)``.

        Raises
        ------
        ValueError
            If it has another shape (the message names ``z``).
        """
        z = np.asarray(z, dtype=float)
        if z.shape != (self.n_unknowns,):
            raise ValueError(f"`z` must have shape ({self.n_unknowns},), got {z.shape}")
        return z

    def orbit_unknowns(self, X: Any) -> FloatArray:
        """A zero ``z``, shape ``(n_unknowns,)``, with the orbit ``X`` (M, n) in its orbit block.

        Raises
        ------
        ValueError
            If ``X`` does not have shape ``(M, n)`` (the message names ``X``).
        """
        X = np.asarray(X, dtype=float)
        if X.shape != (self.n_points, self.n):
            raise ValueError(f"`X` must have shape ({self.n_points}, {self.n}), got {X.shape}")
        z = np.zeros(self.n_unknowns)
        z[self.slices()["orbit"]] = X.reshape(-1)  # row-major (M, n) == column-major (n, M)
        return z

    def orbit_of(self, z: FloatArray) -> FloatArray:
        """The orbit block of ``z`` (checked by :meth:`checked`) as ``X``, shape ``(M, n)``."""
        return z[self.slices()["orbit"]].reshape(self.n_points, self.n)

    def solved_params(self, z: FloatArray, free: Sequence[str]) -> dict[str, float]:
        """The solved parameters of ``z`` by name (``free``, in the order of the block)."""
        return dict(zip(free, z[self.slices()["params"]].tolist(), strict=True))

    def full_params(self, values: Any, z: FloatArray) -> FloatArray:
        """A copy of the full parameter vector ``values`` with the solved ones from ``z``."""
        v = np.array(values, dtype=float)
        v[list(self.unknown_param_index)] = np.asarray(z)[self.slices()["params"]]
        return v

    @property
    def start_rows(self) -> slice:
        """Rows of the start condition ``x(0) - x_0`` in ``G`` (a start-point layout)."""
        if not self.start_point:
            raise ValueError("a connection layout has no start-point rows")
        a = self.boundary_row
        return slice(a, a + self.n)

    def data_names(self) -> tuple[str, ...]:
        """Names of the numeric inputs of ``G`` after ``w`` and ``P``."""
        if self.start_point:
            return ("h", "T", "Qp", "shift", "x0")
        return ("h", "T", "Qm", "Qp", "shift", "ref", "dref", "pin")

    @property
    def orbit(self) -> OrbitLayout:
        """The orbit's unknowns and its collocation and continuity rows (:mod:`.layout`)."""
        return OrbitLayout(self.n, self.n_intervals, self.degree)

    def stage_blocks(self) -> tuple[np.ndarray, np.ndarray]:
        """Collocation rows and stage unknowns of each interval, two ``(N, m n)`` arrays.

        :meth:`OrbitLayout.stage_blocks <continuation.bvp.layout.OrbitLayout.stage_blocks>`:
        the blocks that :class:`~continuation.bvp.condense.StageCondenser` eliminates.
        """
        return self.orbit.stage_blocks()


def _to_dm(A: sp.spmatrix) -> ca.DM:
    A = sp.csc_matrix(A)
    A.sort_indices()
    sparsity = ca.Sparsity(A.shape[0], A.shape[1], A.indptr.tolist(), A.indices.tolist())
    return ca.DM(sparsity, A.data.tolist())


def _riccati(A: Any, Q: Any, k: int, R: Any) -> tuple[Any, Any]:
    """Riccati residual and the basis ``Q_1 + Q_2 R`` of the invariant subspace of ``A^T``."""
    n = Q.shape[0]
    M = ca.mtimes([Q.T, A.T, Q])
    T11, T12 = M[:k, :k], M[:k, k:]
    T21, T22 = M[k:, :k], M[k:, k:]
    res = T21 + ca.mtimes(T22, R) - ca.mtimes(R, T11) - ca.mtimes([R, T12, R])
    Y = Q[:, :k] + ca.mtimes(Q[:, k:], R) if k < n else Q
    return res, Y


#: The functions are expanded from MX to SX when the system's right-hand side has at
#: most this many instructions times the number of collocation points (the small
#: demos: 10^3-10^4; the ship's 12 000-instruction model on 360 points stays MX, whose
#: expansion would take minutes and much memory).
MAX_EXPANDED_POINT_INSTRUCTIONS = 100_000

#: The compiled collocation and continuity rows of every collocated orbit
#: (:func:`continuation._jit.compiled`), shared with periodic orbits.
KERNELS = "continuation.bvp._collocation_jit"


def _block_permutation(n_rows: int, n_cols: int, K: int, cols: Any = None) -> list[int]:
    """Non-zeros of ``K`` column-major ``(n_rows, n_cols)`` blocks side by side, permuted.

    Taken in the order ``[s, a, b]`` (block ``s``, row ``a``, column ``cols[b]``:
    row-major blocks of the columns ``cols``, default all).
    """
    c = np.arange(n_cols) if cols is None else np.asarray(cols, dtype=int)
    s, a, b = np.meshgrid(np.arange(K), np.arange(n_rows), c, indexing="ij")
    return ((s * n_cols + b) * n_rows + a).ravel().tolist()  # type: ignore[no-any-return]


class ConnectionFunctions:
    """Residual and Jacobians of one :class:`ConnectionLayout` (see module doc).

    Build with :func:`build_connection_functions`, which caches per system and layout.
    The collocation and continuity rows and their derivatives are filled by the compiled
    kernel of every collocated orbit (:mod:`continuation.bvp._collocation_jit`, with the
    row scale ``h_j T`` and the factor ``1`` on ``f``) from ``f``, ``f_x`` and ``f_p`` at
    the stages; the boundary rows (equilibria, Riccati, projections, start point, phase)
    and their exact Jacobians come from one CasADi expression graph, which evaluates the
    stage values too. Each CasADi function is built on first use.

    Attributes
    ----------
    layout : ConnectionLayout
    B : casadi.Function
        ``(w, P, *data) -> (F, g_b)``: ``f`` at the stages, ``(n, N m)``, and the boundary
        rows ``G[n N (m + 1):]``; its inputs are ``w, P`` and
        :meth:`ConnectionLayout.data_names`.
    n_equations : int
    """

    def __init__(self, system: Any, layout: ConnectionLayout) -> None:
        fns = system.casadi_functions()
        f_fun, jac_fun = fns["f"], fns["jac"]  # SX functions of (x, p)
        n, N, m = layout.n, layout.n_intervals, layout.degree
        M = layout.n_points
        n_par = system.n_params
        sl = layout.slices()
        self.layout = layout
        mesh = CollocationMesh(N, m, 1.0)

        w = ca.MX.sym("w", layout.n_unknowns)
        P = ca.MX.sym("P", n_par)
        data = {
            "h": ca.MX.sym("h", N),
            "T": ca.MX.sym("T"),
            "Qm": ca.MX.sym("Qm", n, n),
            "Qp": ca.MX.sym("Qp", n, n),
            "shift": ca.MX.sym("shift", n),
            "ref": ca.MX.sym("ref", n, N * m),
            "dref": ca.MX.sym("dref", n, N * m),
            "pin": ca.MX.sym("pin"),
            "x0": ca.MX.sym("x0", n),
        }
        h, shift = data["h"], data["shift"]

        # effective parameter vector: unknown parameters come from w
        upar = w[sl["params"]]
        pos = {i: j for j, i in enumerate(layout.unknown_param_index)}
        if n_par:
            P_eff = ca.vertcat(*[upar[pos[i]] if i in pos else P[i] for i in range(n_par)])
        else:
            P_eff = P

        X = ca.reshape(w[sl["orbit"]], n, M)
        if layout.start_point:
            x_from = None
            x_to = w[sl["x_to"]] + shift
        else:
            x_from = w[sl["x_from"]]
            x_to = w[sl["x_to"]] if layout.separate_to else x_from + shift

        Xs = X[:, stage_points(N, m).tolist()]
        # the stage evaluations (most of the cost) by compiled copies when possible
        fmap = compiled(f_fun).map("fmap", "serial", N * m, [1], [])
        F = fmap(Xs, P_eff)  # (n, N m)

        eqs = []
        if x_from is None:  # a landing: the start point, then its end equilibrium
            eqs += [X[:, 0] - data["x0"], f_fun(w[sl["x_to"]], P_eff)]
        else:
            eqs.append(f_fun(x_from, P_eff))
            if layout.separate_to:
                eqs.append(f_fun(x_to, P_eff))
        km, kp = layout.k_minus, layout.k_plus
        if km > 0:
            assert x_from is not None  # (k_minus = 0 in a start-point layout)
            A_m = jac_fun(x_from, P_eff)
            Rm = ca.reshape(w[sl["R_minus"]], n - km, km)
            ric, Y = _riccati(A_m, data["Qm"], km, Rm)
            if km < n:
                eqs.append(ca.vec(ric))
            eqs.append(ca.mtimes(Y.T, X[:, 0] - x_from))
        if kp > 0:
            A_p = jac_fun(x_to, P_eff)
            Rp = ca.reshape(w[sl["R_plus"]], n - kp, kp)
            ric, Y = _riccati(A_p, data["Qp"], kp, Rp)
            if kp < n:
                eqs.append(ca.vec(ric))
            eqs.append(ca.mtimes(Y.T, X[:, M - 1] - x_to))
        if layout.start_point:
            phase = None
        elif layout.pin is None:
            # (1, N m): h_j b_k of each stage
            E = sp.kron(sp.eye(N), np.ones((1, m)), format="csc")
            h_rep = ca.mtimes(h.T, _to_dm(E))
            b_rep = ca.DM(np.tile(mesh.b, N)).T  # (1, N m)
            wq = h_rep * b_rep
            phase = ca.sum2(ca.sum1((Xs - data["ref"]) * data["dref"]) * wq)
        else:
            i_state, i_node = layout.pin
            phase = X[i_state, i_node * (m + 1)] - data["pin"]
        g_rest = ca.vertcat(*eqs)
        g_b = ca.vertcat(g_rest, *([] if phase is None else [phase]))
        if layout.boundary_row + g_b.shape[0] != layout.n_unknowns:
            raise ValueError(
                f"internal count mismatch: {layout.boundary_row + g_b.shape[0]} equations "
                f"for {layout.n_unknowns} unknowns"
            )
        names = ["w", "P", *layout.data_names()]
        inputs = [w, P, *(data[k] for k in names[2:])]
        self.B = ca.Function("B", inputs, [F, g_b], names, ["F", "g_b"])
        # small systems: the functions are expanded to SX (one flat instruction list,
        # about half the evaluation time of the MX graph with its mapped calls)
        self._expand = f_fun.n_instructions() * N * m <= MAX_EXPANDED_POINT_INSTRUCTIONS
        if self._expand:
            self.B = self.B.expand()
        self.n_equations = int(layout.n_unknowns)
        self.n_params = int(n_par)
        self.arg_sizes = tuple(int(self.B.nnz_in(i)) for i in range(self.B.n_in()))
        self._bB = _Buffered(self.B)
        # collocation rows and stage unknowns of each interval: the linear solves of
        # Newton and of the driver condense the stages (continuation.bvp.condense)
        self.condenser = StageCondenser(*layout.stage_blocks())
        self._D = np.ascontiguousarray(mesh.D, dtype=float)
        self._e = np.ascontiguousarray(mesh.e, dtype=float)
        # The Jacobians cost most of the construction (about 0.8 s of 1 s for the ship);
        # a residual-only user (finite differences of G in a model coefficient) never
        # needs them, so each is built on first use.
        self._graph = (fns, inputs, names, F, g_rest, phase, Xs, P_eff, n_par, w, P)
        self._jac: dict[Any, Any] = {}
        self._Bc: tuple[FloatArray, FloatArray, FloatArray, FloatArray] | None = None

    def _function(self, with_p: bool, values: bool = True) -> tuple[ca.Function, _Buffered]:
        """``(w, P, *data) -> (F, f_x, f_p, g_b, dg_b/dw[, dg_b/dP])``, built once.

        ``f_x`` and ``f_p`` at the stages leave as row-major blocks (``(N m, n, n)`` and
        ``(N m, n, n_p)``, the columns :meth:`_fp_columns`); the Jacobians of the boundary
        rows as their non-zeros. ``values=False``: ``dG/dw`` alone (``with_p`` False,
        ``(f_x, f_p, dg_b/dw)``) or ``dG/dP`` alone (``with_p`` True, ``(f_p, dg_b/dP)``),
        without the residual's ``F`` and ``g_b``.
        """
        name = {(True, True): "L_all", (False, True): "L_w", (False, False): "J_w",
                (True, False): "J_P"}[(with_p, values)]  # fmt: skip
        hit = self._jac.get(name)
        if hit is None:
            fns, inputs, names, F, g_rest, phase, Xs, P_eff, n_par, w, P = self._graph
            n, K = self.layout.n, self.layout.n_stages
            jmap = compiled(fns["jac"]).map("jac_map", "serial", K, [1], [])
            JF = ca.vec(ca.densify(jmap(Xs, P_eff)))[_block_permutation(n, n, K)]
            cols = self._fp_columns(with_p)
            if cols:
                pmap = compiled(fns["dfdp"]).map("dfdp_map", "serial", K, [1], [])
                JP = ca.vec(ca.densify(pmap(Xs, P_eff)))[_block_permutation(n, n_par, K, cols)]
            else:
                JP = ca.MX(0, 1)
            # The integral phase row is dense in the orbit unknowns; a dense row defeats
            # the column colouring of a forward-mode Jacobian, so it is differentiated on
            # its own (one reverse sweep).
            last = [] if phase is None else [phase]
            if with_p:
                Jp = ca.vertcat(ca.jacobian(g_rest, P), *(ca.jacobian(r, P) for r in last))
            if with_p and not values:
                outs, onames = [JP, Jp], ["f_p", "dg_b_dP"]
            else:
                g_b = ca.vertcat(g_rest, *last)
                Jw = ca.vertcat(ca.jacobian(g_rest, w), *(ca.jacobian(r, w) for r in last))
                outs, onames = [F, JF, JP, g_b, Jw], ["F", "f_x", "f_p", "g_b", "dg_b_dw"]
                if not values:
                    outs, onames = [JF, JP, Jw], ["f_x", "f_p", "dg_b_dw"]
                if with_p:
                    outs.append(Jp)
                    onames.append("dg_b_dP")
            fn = ca.Function(name, inputs, outs, names, onames)
            if self._expand:
                fn = fn.expand()
            hit = (fn, _Buffered(fn))
            self._jac[name] = hit
        return hit

    def _fp_columns(self, with_p: bool) -> list[int]:
        """The columns of ``f_p`` evaluated: all with ``dG/dP``, else the solved ones."""
        return list(range(self.n_params)) if with_p else list(self.layout.unknown_param_index)

    def _patterns(self, with_p: bool) -> dict[str, Any]:
        """CSC templates of ``dG/dw`` and ``dG/dP`` and where their values come from.

        The kernel's values (:mod:`continuation.bvp._collocation_jit`: the blocks, the
        ``f_p`` columns, the continuity entries) are followed by the non-zeros of the
        boundary rows' Jacobians in ``w`` and in ``P``; ``order_w[q]`` is the value of CSC
        slot ``q`` of ``dG/dw``, ``order_p`` that of ``dG/dP``. The pattern of the
        collocation rows is that of ``D[k, l] / (h_j T) I - [l = k + 1] f_x``: the
        diagonal of the blocks ``l != k + 1``, the whole block ``l = k + 1``.
        """
        pat = self._jac.get(("patterns", with_p))
        if pat is not None:
            return pat  # type: ignore[no-any-return]
        lay = self.layout
        n, m, K = lay.n, lay.degree, lay.n_stages
        m1, n_par, br = m + 1, self.n_params, lay.boundary_row
        fn = self._function(with_p)[0]
        sw = fn.sparsity_out(4)
        sP = fn.sparsity_out(5) if with_p else ca.Sparsity(0, n_par)
        # the blocks: (N, m, m+1, n, n)
        rows_b, cols_b = lay.orbit.collocation_blocks()
        k = np.arange(m)[None, :, None, None, None]
        l_ = np.arange(m1)[None, None, :, None, None]
        i = np.arange(n)[None, None, None, :, None]
        ii = np.arange(n)[None, None, None, None, :]
        keep = np.broadcast_to((l_ == k + 1) | (i == ii), rows_b.shape)
        fns = self._graph[0]
        n_b = rows_b.size
        pos_b = np.arange(n_b).reshape(rows_b.shape)
        # the f_p values [s, i, c] of the columns q = cols[c]: the solved parameters into
        # w, the others into P
        cols = np.asarray(self._fp_columns(with_p), dtype=int)
        n_p = cols.size
        n_fp = K * n * n_p
        unk = list(lay.unknown_param_index)
        col_of = np.full(n_par, -1)  # column in w of each solved parameter
        col_of[unk] = lay.slices()["params"].start + np.arange(len(unk))
        # the structural non-zeros of f_p (i, q) at every stage s: row s n + i
        jp = np.asarray(ca.DM(fns["dfdp"].sparsity_out(0), 1.0).full()).reshape(n, n_par) != 0
        s_, i_, c_ = np.nonzero(np.broadcast_to(jp[None][:, :, cols], (K, n, n_p)))
        q_ = cols[c_]
        rows_fp, pos_fp = s_ * n + i_, n_b + (s_ * n + i_) * n_p + c_
        u = col_of[q_] >= 0
        rows_u, cols_u, pos_u = rows_fp[u], col_of[q_[u]], pos_fp[u]
        rows_k, cols_k, pos_k = rows_fp[~u], q_[~u], pos_fp[~u]
        # the continuity entries, in the order of OrbitLayout.continuity_entries
        rows_c, cols_c, _ = lay.orbit.continuity_entries(self._e)
        n_c = rows_c.size
        off = n_b + n_fp + n_c
        # the boundary rows (CasADi's column-major non-zeros)
        rows_w = br + np.asarray(sw.row(), dtype=np.int64)
        cols_w = np.repeat(np.arange(sw.size2()), np.diff(sw.colind()))
        pos_w = off + np.arange(rows_w.size)
        rows_P = br + np.asarray(sP.row(), dtype=np.int64)
        cols_P = np.repeat(np.arange(sP.size2()), np.diff(sP.colind()))
        pos_P = off + rows_w.size + np.arange(rows_P.size)
        nw = lay.n_unknowns
        tw, order_w = _csc(
            np.concatenate([rows_b[keep], rows_u, rows_c, rows_w]),
            np.concatenate([cols_b[keep], cols_u, cols_c, cols_w]),
            np.concatenate([pos_b[keep], pos_u, off - n_c + np.arange(n_c), pos_w]),
            (nw, nw),
        )
        first = self._jac.setdefault("w_template", tw)  # one template for both variants
        if first is not tw:
            if not (np.array_equal(first.indices, tw.indices)
                    and np.array_equal(first.indptr, tw.indptr)):  # fmt: skip
                raise ValueError("internal error: two patterns of the connection's Jacobian")
            tw = first
        tw.condensed_lu = self.condenser.factor
        tp, order_p = _csc(
            np.concatenate([rows_k, rows_P]), np.concatenate([cols_k, cols_P]),
            np.concatenate([pos_k, pos_P]), (nw, n_par),
        )  # fmt: skip
        pat = {
            "w": tw, "p": tp, "order_w": order_w, "order_p": order_p,
            "order_none": np.zeros(0, dtype=np.int64),
            "bounds": (off, off + rows_w.size, off + rows_w.size + rows_P.size),
            "fp_start": n_b,
            "shapes": ((K, n), (K, n, n), (K, n, n_p)),
        }  # fmt: skip
        self._jac[("patterns", with_p)] = pat
        return pat

    def flat_args(self, args: list[Any]) -> list[FloatArray]:
        """The inputs as contiguous float vectors (matrices column-major), sizes checked.

        Parameters
        ----------
        args : list
            ``[w, P, *layout.data_names()]`` as arrays or scalars (a connection:
            ``[w, P, h, T, Qm, Qp, shift, ref, dref, pin]``).

        Returns
        -------
        list of ndarray
            One 1-D float64 array per input, of length ``B.nnz_in(i)``.
        """
        out = []
        for i, a in enumerate(args):
            v = np.ascontiguousarray(np.asarray(a, dtype=float).ravel(order="F"))
            if v.size != self.arg_sizes[i]:
                raise ValueError(
                    f"input {self.B.name_in(i)!r} of G has {v.size} entries, expected "
                    f"{self.arg_sizes[i]}"
                )
            out.append(v)
        return out

    def _flat(self, args: list[Any]) -> list[FloatArray]:
        if len(args) == len(self.arg_sizes) and all(
            type(a) is np.ndarray and a.ndim == 1 and a.dtype == np.float64
            and a.size == k and a.flags.c_contiguous
            for a, k in zip(args, self.arg_sizes, strict=True)
        ):  # fmt: skip
            return args
        return self.flat_args(args)

    def _orbit(self, flat: list[FloatArray]) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``X`` (``(M, n)``, a view of ``w``), the row scales ``d_j = h_j T`` and ``Bc``.

        ``Bc`` is the constant part ``D[k,l] / d_j I`` of the blocks, flat (the kernel's
        ``Bc``). The last ones are kept: one mesh and ``T`` per problem, many
        evaluations, recognised by the problem's own (cached) input arrays, else by value.
        """
        lay = self.layout
        X = flat[0][: lay.n_orbit_unknowns].reshape(lay.n_points, lay.n)
        h, T = flat[2], flat[3]
        last = self._Bc
        if last is None or last[0] is not h or last[1] is not T:
            d = h * T[0]
            if last is None or not np.array_equal(last[2], d):
                Bc = _jit.compiled(KERNELS).constant_blocks(self._D, d, lay.n)
            else:
                Bc = last[3]
            last = self._Bc = (h, T, d, Bc)
        return X, last[2], last[3]

    def residual(self, args: list[Any]) -> FloatArray:
        """``G(*args)`` as a flat array, shape ``(n_eq,)``."""
        flat = self._flat(args)
        lay = self.layout
        G = np.empty(self.n_equations)
        F = np.empty((lay.n_stages, lay.n))
        self._bB(flat, [F, G[lay.boundary_row :]])
        X, d, _ = self._orbit(flat)
        _jit.compiled(KERNELS).collocation_residual(X, F, 1.0, self._D, self._e, d, G)
        return G

    def _linearize(
        self, args: list[Any], with_p: bool
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        flat = self._flat(args)
        pat = self._patterns(with_p)
        br = self.layout.boundary_row
        G = np.empty(self.n_equations)
        F, J, Jp = (np.empty(s) for s in pat["shapes"])
        a, b, c = pat["bounds"]
        vals = np.empty(c)
        outs = [F, J, Jp, G[br:], vals[a:b]] + ([vals[b:c]] if with_p else [])
        self._function(with_p)[1](flat, outs)
        X, d, Bc = self._orbit(flat)
        data_w = np.empty(pat["order_w"].size)
        order_p = pat["order_p"] if with_p else pat["order_none"]
        data_p = np.empty(order_p.size)
        _jit.compiled(KERNELS).linearize(
            X, F, J, Jp, 1.0, self._D, self._e, d, Bc, G, vals,
            pat["order_w"], data_w, order_p, data_p,
        )  # fmt: skip
        return G, data_w, data_p

    def jacobian(self, args: list[Any]) -> sp.csc_matrix:
        """``dG/dw`` as SciPy CSC, shape ``(n_eq, n_eq)`` (the residual is not evaluated)."""
        flat = self._flat(args)
        pat = self._patterns(False)
        _, J, Jp = (np.empty(s) for s in pat["shapes"])
        a, b, c = pat["bounds"]
        vals = np.empty(c)
        self._function(False, values=False)[1](flat, [J, Jp, vals[a:b]])
        _, _, Bc = self._orbit(flat)
        _jit.compiled(KERNELS).collocation_values(J, Jp, 1.0, Bc, self._e, vals)
        return csc_with_data(pat["w"], vals[pat["order_w"]])

    def residual_jacobian(self, args: list[Any]) -> tuple[FloatArray, sp.csc_matrix]:
        """``(G, dG/dw)`` in one evaluation."""
        g, jw, _ = self._linearize(args, False)
        return g, csc_with_data(self._patterns(False)["w"], jw)

    def linearize(self, args: list[Any]) -> tuple[FloatArray, sp.csc_matrix, sp.csc_matrix]:
        """``(G, dG/dw, dG/dP)`` in one evaluation."""
        g, jw, jp = self._linearize(args, True)
        pat = self._patterns(True)
        return g, csc_with_data(pat["w"], jw), csc_with_data(pat["p"], jp)

    def param_jacobian(self, args: list[Any]) -> sp.csc_matrix:
        """``dG/dP`` as SciPy CSC, shape ``(n_eq, n_params)`` (nothing else is evaluated).

        Its values are those :meth:`linearize` places: ``-f_p`` on the collocation rows
        (the kernel's ``-c f_p`` with ``c = 1``) and the boundary rows' ``dg_b/dP``.
        """
        flat = self._flat(args)
        pat = self._patterns(True)
        Jp = np.empty(pat["shapes"][2])
        _, b, c = pat["bounds"]
        vals = np.empty(c)
        self._function(True, values=False)[1](flat, [Jp, vals[b:c]])
        s0 = pat["fp_start"]
        vals[s0 : s0 + Jp.size] = -Jp.ravel()
        return csc_with_data(pat["p"], vals[pat["order_p"]])


def _csc(
    rows: np.ndarray, cols: np.ndarray, pos: np.ndarray, shape: tuple[int, int]
) -> tuple[sp.csc_matrix, np.ndarray]:
    """The CSC template of the entries ``(rows, cols)`` and the value index of each slot.

    Raises
    ------
    ValueError
        If an entry repeats (the orbit rows and the boundary rows are disjoint).
    """
    srt = np.lexsort((rows, cols))  # column-major, rows sorted within a column
    key = cols[srt].astype(np.int64) * shape[0] + rows[srt]
    if key.size and np.any(key[1:] == key[:-1]):
        raise ValueError("internal error: a repeated entry in the connection's pattern")
    indices = (key % shape[0]).astype(np.int32)
    indptr = np.searchsorted(key // shape[0], np.arange(shape[1] + 1)).astype(np.int32)
    A = sp.csc_matrix((np.ones(key.size), indices, indptr), shape=shape)
    A.has_canonical_format  # noqa: B018  (sorted, no duplicates: flag checked once)
    return A, np.ascontiguousarray(pos[srt], dtype=np.int64)


class _Buffered:
    """Evaluate a ``ca.Function`` on NumPy buffers (``Function.buffer``): no conversions.

    The inputs are 1-D float64 arrays of the functions' input sizes (checked by the
    caller); the outputs are written into the given contiguous float64 arrays (views
    allowed), one per output with its number of non-zeros.
    """

    def __init__(self, fn: ca.Function) -> None:
        self._fn = fn  # (kept alive with its buffer)
        self._buf, self._trigger = fn.buffer()

    def __call__(self, args: list[FloatArray], outs: list[FloatArray]) -> None:
        buf = self._buf
        for i, a in enumerate(args):
            buf.set_arg(i, memoryview(a))
        for i, o in enumerate(outs):
            buf.set_res(i, memoryview(o))
        self._trigger()


_CACHE: weakref.WeakKeyDictionary[Any, dict[tuple[ConnectionLayout, bool], ConnectionFunctions]] = (
    weakref.WeakKeyDictionary()
)


def build_connection_functions(system: Any, layout: ConnectionLayout) -> ConnectionFunctions:
    """Build (or fetch from a per-system cache) the functions of ``layout``.

    Parameters
    ----------
    system : System
        A system with a CasADi trace (``system.casadi_functions()``).
    layout : ConnectionLayout
        Sizes of the discretisation; the cache key together with ``system``.
    """
    per_system = _CACHE.setdefault(system, {})
    # functions built with the virtual machine are rebuilt once compilation is allowed
    key = (layout, compilation_allowed())
    fn = per_system.get(key)
    if fn is None and not key[1]:
        fn = per_system.get((layout, True))  # compiled ones serve everywhere
    if fn is None:
        fn = ConnectionFunctions(system, layout)
        per_system[key] = fn
    return fn


__all__ = ["ConnectionFunctions", "ConnectionLayout", "build_connection_functions"]
