r"""CasADi construction of the collocation residual of a connecting orbit, built once.

One core for every orbit that ends at a saddle: a *connection* (it starts at a saddle
too, with a phase condition) and a *landing* (:mod:`continuation.bvp.landing`: it starts
at a given point ``x_0``, which fixes the time shift, so there is no phase condition).
The two differ only in their start condition (:attr:`ConnectionLayout.start_point`).

:func:`build_connection_functions` turns a :class:`~continuation.system.System`
and an unknown-vector :class:`ConnectionLayout` into compiled ``ca.Function`` s

* ``G(w, P, h, T, Qm, Qp, shift, ref, dref, pin) -> (n_eq,)``, the residual,
* ``G_w`` (sparse ``(n_eq, n_eq)``), its exact Jacobian in the unknowns ``w``,
* ``G_P`` (sparse ``(n_eq, n_params)``), its exact Jacobian in the full parameter
  vector ``P``,

where every quantity that may change without changing the *structure* of the
problem (mesh spacing ``h``, truncation time ``T``, reference Schur bases
``Qm``/``Qp``, the periodic ``shift``, the phase-condition reference orbit and the
pinned value) is a numeric input. Adapting the mesh with a fixed number of
intervals, changing ``T`` or updating a reference therefore never rebuilds the
functions. The right-hand side is the system's own CasADi trace, evaluated on all
``N m`` collocation points at once through ``Function.map``, so the Jacobian
re-uses the mapped derivative of ``f`` instead of growing an expression per point.

Unknowns, in this order (see :class:`ConnectionLayout`)::

    w = [ vec(X) (n M),  x_-  (n),  [x_+ (n)],  vec(R_-) ((n-k_-) k_-),
          vec(R_+) ((n-k_+) k_+),  unknown parameters (q) ]

with ``X`` the ``(n, M)`` matrix of values at the ``M = N (m + 1) + 1`` mesh and
collocation points (interval by interval, so the Jacobian is almost block
banded). The orbit block and the collocation and continuity rows are placed by
:class:`~continuation.bvp.layout.OrbitLayout`, the layout periodic orbits use too (its
matrices ``D kron I``, the stage selection and the continuity rows are built here
from its index arrays). Equations, in this order::

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


def _collocation_jacobian(
    fns: dict[str, ca.Function],
    layout: ConnectionLayout,
    Xs: Any,
    P_eff: Any,
    h_rep: Any,
    T: Any,
    D: FloatArray,
    n_par: int,
) -> tuple[Any, Any]:
    r"""Exact Jacobians of the collocation rows in ``w`` and in ``P``.

    Row ``s n + i`` is component ``i`` of
    :math:`(1/(h_j T)) \sum_l D[k,l] X_{j,l} - f(X_{j,k}, P)` at stage ``s = j m + k``::

        d/dvec(X) = diag(1/(h T)) (Dbig^T kron I_n) - blockdiag(f_x(X_s)) Sel
        d/dp      = -f_p(X_s)   (unknown-parameter columns into w, the rest into P)

    ``Sel`` picks the stage values out of ``vec(X)``. Assembling this from the mapped
    ``f_x``/``f_p`` avoids forward-mode AD through the map with one sweep per colour.
    """
    n = layout.n
    M, Nm = layout.n_points, layout.n_stages
    # constant (D kron I) and selection matrices, (n Nm, n M): the one orbit layout
    orbit = layout.orbit
    Kd = _to_dm(orbit.derivative_matrix(D))
    Sel = _to_dm(orbit.stage_selection())
    scale = ca.vec(ca.repmat(1.0 / (h_rep * T), n, 1))  # (n Nm,)
    JF = compiled(fns["jac"]).map("jac_map", "serial", Nm, [1], [])(Xs, P_eff)  # (n, n Nm)
    bd_sparsity = ca.kron(ca.DM(ca.Sparsity.diag(Nm), 1.0), ca.DM.ones(n, n)).sparsity()
    BD = ca.MX(bd_sparsity, ca.vec(JF))
    J_orbit = ca.mtimes(ca.diag(scale), Kd) - ca.mtimes(BD, Sel)
    q = len(layout.unknown_param_index)
    n_mid = layout.n_unknowns - n * M - q
    if n_par:
        dfdp_map = compiled(fns["dfdp"]).map("dfdp_map", "serial", Nm, [1], [])
        DP = dfdp_map(Xs, P_eff)  # (n, n_par Nm)
        # stack the stage blocks vertically: row s n + i, column c = f_p(X_s)[i, c]
        R = ca.reshape(DP, n * n_par, Nm).T  # (Nm, n n_par), row s = vec(block s)
        V_perm = ca.reshape(R, Nm * n, n_par)  # row i Nm + s
        perm = [i * Nm + s for s in range(Nm) for i in range(n)]
        V = V_perm[perm, :]
        J_par = -V[:, list(layout.unknown_param_index)] if q else ca.MX(n * Nm, 0)
        mask = np.ones(n_par)
        mask[list(layout.unknown_param_index)] = 0.0
        J_P = -ca.mtimes(V, ca.DM(np.diag(mask)))
    else:
        J_par = ca.MX(n * Nm, 0)
        J_P = ca.MX(n * Nm, 0)
    J_w = ca.horzcat(J_orbit, ca.MX(n * Nm, n_mid), J_par)
    return J_w, J_P


#: The functions are expanded from MX to SX when the system's right-hand side has at
#: most this many instructions times the number of collocation points (the small
#: demos: 10^3-10^4; the ship's 12 000-instruction model on 360 points stays MX, whose
#: expansion would take minutes and much memory).
MAX_EXPANDED_POINT_INSTRUCTIONS = 100_000


class ConnectionFunctions:
    """Compiled residual and Jacobians of one :class:`ConnectionLayout` (see module doc).

    Build with :func:`build_connection_functions`, which caches per system and layout.
    Every function is built on first use from one expression graph.

    Attributes
    ----------
    layout : ConnectionLayout
    G, G_w, G_P, G_all : casadi.Function
        Residual, Jacobian in ``w`` (sparse), Jacobian in ``P`` (sparse), and all three
        in one function; their inputs are ``w, P`` and :meth:`ConnectionLayout.data_names`.
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
        h, T, shift = data["h"], data["T"], data["shift"]

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
        # h repeated for each stage: (1, N m)
        E = sp.kron(sp.eye(N), np.ones((1, m)), format="csc")
        h_rep = ca.mtimes(h.T, _to_dm(E))
        # the orbit layout of one state: X (n, M) times these gives the rows of all states
        point = OrbitLayout(1, N, m)
        Dbig = _to_dm(point.derivative_matrix(mesh.D).T)  # (M, N m)
        Cbig = _to_dm(point.continuity_matrix(mesh.e).T)  # (M, N)
        # the stage evaluations (most of the cost) by compiled copies when possible
        fmap = compiled(f_fun).map("fmap", "serial", N * m, [1], [])
        F = fmap(Xs, P_eff)
        colloc = ca.mtimes(X, Dbig) / ca.repmat(h_rep * T, n, 1) - F
        cont = ca.mtimes(X, Cbig)

        eqs = [ca.vec(cont)]
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
            b_rep = ca.DM(np.tile(mesh.b, N)).T  # (1, N m)
            wq = h_rep * b_rep
            phase = ca.sum2(ca.sum1((Xs - data["ref"]) * data["dref"]) * wq)
        else:
            i_state, i_node = layout.pin
            phase = X[i_state, i_node * (m + 1)] - data["pin"]
        g_rest = ca.vertcat(*eqs)
        g = ca.vertcat(ca.vec(colloc), g_rest, *([] if phase is None else [phase]))
        if g.shape[0] != layout.n_unknowns:
            raise ValueError(
                f"internal count mismatch: {g.shape[0]} equations for {layout.n_unknowns} unknowns"
            )
        names = ["w", "P", *layout.data_names()]
        inputs = [w, P, *(data[k] for k in names[2:])]
        self.G = ca.Function("G", inputs, [g], names, ["G"])
        # small systems: the functions are expanded to SX (one flat instruction list,
        # about half the evaluation time of the MX graph with its mapped calls)
        self._expand = f_fun.n_instructions() * N * m <= MAX_EXPANDED_POINT_INSTRUCTIONS
        if self._expand:
            self.G = self.G.expand()
        self.n_equations = int(g.shape[0])
        self.arg_sizes = tuple(int(self.G.nnz_in(i)) for i in range(self.G.n_in()))
        self._bG = _Buffered(self.G)
        # collocation rows and stage unknowns of each interval: the linear solves of
        # Newton and of the driver condense the stages (continuation.bvp.condense)
        self.condenser = StageCondenser(*layout.stage_blocks())
        # The Jacobians cost most of the construction (about 0.8 s of 1 s for the ship);
        # a residual-only user (finite differences of G in a model coefficient) never
        # needs them, so each is built on first use.
        self._graph = (fns, inputs, names, g, g_rest, phase, Xs, P_eff, h_rep, T, mesh.D,
                       n_par, w, P)  # fmt: skip
        self._jac: dict[str, Any] = {}

    def _expressions(self) -> tuple[Any, Any]:
        """The Jacobian expressions ``(dG/dw, dG/dP)`` (built once)."""
        if "expr" not in self._jac:
            (fns, _, _, _, g_rest, phase, Xs, P_eff, h_rep, T, D, n_par, w, P) = self._graph
            # Collocation rows: Jacobian assembled from the mapped df/dx and df/dp of
            # the system (exact, one evaluation of each per collocation point). Other
            # rows: AD. The integral phase row is dense in the orbit unknowns; a dense
            # row defeats the column colouring of a forward-mode Jacobian, so it is
            # differentiated on its own (one reverse sweep).
            Jc_w, Jc_P = _collocation_jacobian(fns, self.layout, Xs, P_eff, h_rep, T, D, n_par)
            last = [] if phase is None else [phase]
            Jw = ca.vertcat(Jc_w, ca.jacobian(g_rest, w), *(ca.jacobian(r, w) for r in last))
            Jp = ca.vertcat(Jc_P, ca.jacobian(g_rest, P), *(ca.jacobian(r, P) for r in last))
            self._jac["expr"] = (Jw, Jp)
        return self._jac["expr"]  # type: ignore[no-any-return]

    def _function(self, name: str) -> tuple[ca.Function, _Buffered]:
        """``G_w``, ``G_P``, ``G_all`` (G, G_w, G_P) or ``G_gw`` (G, G_w), built once."""
        hit = self._jac.get(name)
        if hit is None:
            _, inputs, names, g, *_ = self._graph
            Jw, Jp = self._expressions()
            outs = {"G_w": ([Jw], ["G_w"]), "G_P": ([Jp], ["G_P"]),
                    "G_all": ([g, Jw, Jp], ["G", "G_w", "G_P"]),
                    "G_gw": ([g, Jw], ["G", "G_w"])}[name]  # fmt: skip
            fn = ca.Function(name, inputs, outs[0], names, outs[1])
            if self._expand:
                fn = fn.expand()
            hit = (fn, _Buffered(fn))
            self._jac[name] = hit
        return hit

    def _template_of(self, which: str, name: str | None = None, out: int = 0) -> sp.csc_matrix:
        """CSC template of ``dG/dw`` (``"w"``) or ``dG/dP`` (``"p"``), one per layout.

        Read from output ``out`` of function ``name`` (default ``G_w`` / ``G_P``), the one
        about to be evaluated (all of them share the pattern). Every Jacobian shares the
        template's (canonical) index arrays, so the driver recognises the pattern and
        SciPy's format checks run once.
        """
        key = which + "_template"
        if key not in self._jac:
            fn = self._function(name or ("G_w" if which == "w" else "G_P"))[0]
            spw = fn.sparsity_out(out)
            pattern = (np.array(spw.row(), dtype=np.int32),
                       np.array(spw.colind(), dtype=np.int32), spw.shape)  # fmt: skip
            template = _template(pattern)
            if which == "w":
                template.condensed_lu = self.condenser.factor
            self._jac[which + "_pattern"] = pattern
            self._jac[key] = template
        return self._jac[key]  # type: ignore[no-any-return]

    @property
    def G_w(self) -> ca.Function:  # noqa: N802 (the paper's symbol)
        """Jacobian in ``w`` (built on first use)."""
        return self._function("G_w")[0]

    @property
    def G_P(self) -> ca.Function:  # noqa: N802
        """Jacobian in ``P`` (built on first use)."""
        return self._function("G_P")[0]

    @property
    def G_all(self) -> ca.Function:  # noqa: N802
        """Residual and both Jacobians in one function (built on first use)."""
        return self._function("G_all")[0]

    @property
    def _w_pattern(self) -> tuple[np.ndarray, np.ndarray, tuple[int, int]]:
        self._template_of("w")
        return self._jac["w_pattern"]  # type: ignore[no-any-return]

    @property
    def _p_pattern(self) -> tuple[np.ndarray, np.ndarray, tuple[int, int]]:
        self._template_of("p")
        return self._jac["p_pattern"]  # type: ignore[no-any-return]

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
            One 1-D float64 array per input, of length ``G.nnz_in(i)``.
        """
        out = []
        for i, a in enumerate(args):
            v = np.ascontiguousarray(np.asarray(a, dtype=float).ravel(order="F"))
            if v.size != self.arg_sizes[i]:
                raise ValueError(
                    f"input {self.G.name_in(i)!r} of G has {v.size} entries, expected "
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

    def residual(self, args: list[Any]) -> FloatArray:
        """``G(*args)`` as a flat array, shape ``(n_eq,)``."""
        return self._bG(self._flat(args))[0]

    def jacobian(self, args: list[Any]) -> sp.csc_matrix:
        """``dG/dw`` as SciPy CSC, shape ``(n_eq, n_eq)``."""
        template = self._template_of("w")
        return csc_with_data(template, self._function("G_w")[1](self._flat(args))[0])

    def residual_jacobian(self, args: list[Any]) -> tuple[FloatArray, sp.csc_matrix]:
        """``(G, dG/dw)`` in one evaluation."""
        template = self._template_of("w", "G_gw", 1)
        g, jw = self._function("G_gw")[1](self._flat(args))
        return g, csc_with_data(template, jw)

    def linearize(self, args: list[Any]) -> tuple[FloatArray, sp.csc_matrix, sp.csc_matrix]:
        """``(G, dG/dw, dG/dP)`` in one evaluation."""
        tw, tp = self._template_of("w", "G_all", 1), self._template_of("p", "G_all", 2)
        g, jw, jp = self._function("G_all")[1](self._flat(args))
        return g, csc_with_data(tw, jw), csc_with_data(tp, jp)

    def param_jacobian(self, args: list[Any]) -> sp.csc_matrix:
        """``dG/dP`` as SciPy CSC, shape ``(n_eq, n_params)``."""
        template = self._template_of("p")
        return csc_with_data(template, self._function("G_P")[1](self._flat(args))[0])


def _template(pattern: tuple[np.ndarray, np.ndarray, tuple[int, int]]) -> sp.csc_matrix:
    row, colind, shape = pattern
    A = sp.csc_matrix((np.ones(row.size), row, colind), shape=shape)
    A.has_canonical_format  # noqa: B018  (CasADi sparsities are sorted, no duplicates)
    return A


class _Buffered:
    """Evaluate a ``ca.Function`` on NumPy buffers (``Function.buffer``): no conversions.

    The inputs are 1-D float64 arrays of the functions' input sizes (checked by the
    caller); each call returns fresh output arrays of the outputs' nonzeros.
    """

    def __init__(self, fn: ca.Function) -> None:
        self._buf, self._trigger = fn.buffer()
        self._sizes = tuple(int(fn.nnz_out(i)) for i in range(fn.n_out()))

    def __call__(self, args: list[FloatArray]) -> list[FloatArray]:
        buf = self._buf
        for i, a in enumerate(args):
            buf.set_arg(i, memoryview(a))
        outs = [np.empty(k) for k in self._sizes]
        for i, o in enumerate(outs):
            buf.set_res(i, memoryview(o))
        self._trigger()
        return outs


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
