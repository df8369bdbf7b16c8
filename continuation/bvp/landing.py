r"""An orbit from a given start point onto the stable manifold of a saddle (a "landing").

:class:`LandingProblem` describes an orbit :math:`x(t)` of :math:`\dot x = f(x, p)`
that starts at a given point :math:`x_0(s)` (which may depend on a continuation
parameter ``s`` that is not a parameter of the system) and ends on the stable
manifold of a hyperbolic equilibrium :math:`x_e` (shifted by whole periods of the
periodic states, :math:`x_+ = x_e + \Delta`), truncated to :math:`t \in [0, T]`::

    x(0) = x_0(s)                          the start point (n equations)
    L_u(x_+)^T (x(T) - x_+) = 0            x(T) in the stable eigenspace of f_x(x_+, p)
    f(x_e, p) = 0                          the equilibrium is an unknown too
    Riccati equation of L_u                the projection basis is an unknown too

``L_u`` spans the unstable invariant subspace of :math:`A_+^T` (the orthogonal
complement of the stable eigenspace of :math:`A_+ = f_x(x_+, p)`); as in
:mod:`continuation.bvp.connection` it is ``Q_1 + Q_2 R`` with a reference Schur basis
``Q`` and Riccati unknowns ``R`` (Demmel, Dieci & Friedman 2000), so the residual is
one smooth function of the unknowns with an exact CasADi Jacobian. With the start
fixed there is no time-shift invariance and no phase condition.

Counting: the equations close when the number of solved parameters ``q`` equals
``dim W^u(x_e)`` (the codimension of the stable manifold: a point is put on a
codimension-``q`` manifold by ``q`` parameters). The constructor checks this.

Truncation: ``T`` is fixed and the end distance :math:`|x(T) - x_+|` is free (it is
recorded). A point of the stable *eigenspace* at distance ``d`` is off the stable
manifold by :math:`O(d^2)`, and the orbit approaches the equilibrium like
:math:`e^{\mu T}` (``mu`` the slowest stable rate present), so the error of the
solved parameters decays exponentially in ``T`` (Beyn 1990, "The numerical
computation of connecting orbits in dynamical systems", IMA J. Numer. Anal.
10:379-405, for the same projection condition at one end).
:func:`~continuation.bvp.landing_solve.solve_landing` estimates it by a re-solve on a
longer interval, extended at the end only (the start is a point, not a saddle).

Unknowns and equations (``M = N (m + 1) + 1`` points, ``k = dim W^u(x_e)``)::

    w = [ vec(X) (n M),  x_e (n),  vec(R) ((n-k) k),  solved parameters (q = k) ]
    collocation (n N m), continuity (n N), start (n), equilibrium (n),
    Riccati ((n-k) k), end projection (k)
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np
import scipy.sparse as sp

from ..linalg import csc_with_data
from ..params import Params
from ..typing import FloatArray
from .casadi_backend import (
    _Buffered,
    _collocation_jacobian,
    _continuity_matrix,
    _derivative_matrix,
    _riccati,
    _stage_columns,
    _template,
    _to_dm,
)
from .collocation import CollocationMesh
from .condense import StageCondenser
from .connection import (
    DEFAULT_DEGREE,
    DEFAULT_N_INTERVALS,
    _as_trajectory,
    _count,
    _refine_equilibrium,
    _schur_basis,
)

#: Relative step of the central difference of ``x_0(s)`` when no derivative is given.
FD_STEP = 1e-5


@dataclass(frozen=True)
class LandingLayout:
    """Sizes and positions of the unknowns of a discretised landing orbit.

    Attributes
    ----------
    n, n_intervals, degree : int
        State dimension, ``N`` and ``m`` of the mesh.
    k_plus : int
        ``dim W^u(x_e)``: end conditions (and solved parameters).
    unknown_param_index : tuple of int
        Positions of the solved parameters in the full parameter vector.
    """

    n: int
    n_intervals: int
    degree: int
    k_plus: int
    unknown_param_index: tuple[int, ...]

    @property
    def n_points(self) -> int:
        """``M = N (m + 1) + 1``."""
        return self.n_intervals * (self.degree + 1) + 1

    @property
    def n_stages(self) -> int:
        """``N m`` collocation points."""
        return self.n_intervals * self.degree

    def slices(self) -> dict[str, slice]:
        """Slices of the blocks ``orbit``, ``x_eq``, ``R``, ``params`` in ``w``."""
        n, k = self.n, self.k_plus
        sizes = [("orbit", n * self.n_points), ("x_eq", n), ("R", (n - k) * k),
                 ("params", len(self.unknown_param_index))]  # fmt: skip
        out, pos = {}, 0
        for name, size in sizes:
            out[name] = slice(pos, pos + size)
            pos += size
        return out

    @property
    def n_unknowns(self) -> int:
        """Length of ``w``."""
        return self.slices()["params"].stop

    @property
    def start_rows(self) -> slice:
        """Rows of the start condition ``x(0) - x_0`` in ``G``."""
        a = self.n * (self.n_stages + self.n_intervals)
        return slice(a, a + self.n)


class LandingFunctions:
    """Compiled residual ``G(w, P, h, T, Q, shift, x0)`` and Jacobian ``G_w`` of a layout."""

    def __init__(self, system: Any, layout: LandingLayout) -> None:
        fns = system.casadi_functions()
        f_fun, jac_fun = fns["f"], fns["jac"]
        n, N, m, k = layout.n, layout.n_intervals, layout.degree, layout.k_plus
        M, n_par = layout.n_points, system.n_params
        sl = layout.slices()
        mesh = CollocationMesh(N, m, 1.0)
        w = ca.MX.sym("w", layout.n_unknowns)
        P = ca.MX.sym("P", n_par)
        h = ca.MX.sym("h", N)
        T = ca.MX.sym("T")
        Q = ca.MX.sym("Q", n, n)
        shift = ca.MX.sym("shift", n)
        x0 = ca.MX.sym("x0", n)
        upar = w[sl["params"]]
        pos = {i: j for j, i in enumerate(layout.unknown_param_index)}
        P_eff = ca.vertcat(*[upar[pos[i]] if i in pos else P[i] for i in range(n_par)])
        X = ca.reshape(w[sl["orbit"]], n, M)
        x_eq = w[sl["x_eq"]]
        x_to = x_eq + shift
        Xs = X[:, _stage_columns(N, m)]
        E = sp.kron(sp.eye(N), np.ones((1, m)), format="csc")
        h_rep = ca.mtimes(h.T, _to_dm(E))
        F = f_fun.map("fmap", "serial", N * m, [1], [])(Xs, P_eff)
        colloc = (
            ca.mtimes(X, _to_dm(_derivative_matrix(N, m, mesh.D))) / ca.repmat(h_rep * T, n, 1) - F
        )
        cont = ca.mtimes(X, _to_dm(_continuity_matrix(N, m, mesh.e)))
        ric, Y = _riccati(jac_fun(x_to, P_eff), Q, k, ca.reshape(w[sl["R"]], n - k, k))
        rest = [ca.vec(cont), X[:, 0] - x0, f_fun(x_eq, P_eff)]
        if k < n:
            rest.append(ca.vec(ric))
        rest.append(ca.mtimes(Y.T, X[:, M - 1] - x_to))
        g_rest = ca.vertcat(*rest)
        g = ca.vertcat(ca.vec(colloc), g_rest)
        if g.shape[0] != layout.n_unknowns:  # pragma: no cover - counting checked before
            raise ValueError(f"internal count mismatch: {g.shape[0]} != {layout.n_unknowns}")
        Jc_w, _ = _collocation_jacobian(fns, layout, Xs, P_eff, h_rep, T, mesh.D, n_par)  # type: ignore[arg-type]
        Jw = ca.vertcat(Jc_w, ca.jacobian(g_rest, w))
        inputs = [w, P, h, T, Q, shift, x0]
        names = ["w", "P", "h", "T", "Q", "shift", "x0"]
        G = ca.Function("G", inputs, [g], names, ["G"])
        G_all = ca.Function("G_all", inputs, [g, Jw], names, ["G", "G_w"])
        spw = G_all.sparsity_out(1)
        self.template = _template(
            (np.array(spw.row(), dtype=np.int32), np.array(spw.colind(), dtype=np.int32),
             spw.shape)
        )  # fmt: skip
        stage = np.array(_stage_columns(N, m)).reshape(N, m)
        cols_s = (stage[:, :, None] * n + np.arange(n)).reshape(N, m * n)
        rows_s = np.arange(N * m * n).reshape(N, m * n)
        self.template.condensed_lu = StageCondenser(rows_s, cols_s).factor
        self.sizes = tuple(int(G.nnz_in(i)) for i in range(G.n_in()))
        self._G, self._all = _Buffered(G), _Buffered(G_all)

    def _flat(self, args: list[Any]) -> list[FloatArray]:
        out = [np.ascontiguousarray(np.asarray(a, dtype=float).ravel(order="F")) for a in args]
        for v, size in zip(out, self.sizes, strict=True):
            if v.size != size:  # pragma: no cover - shapes are the problem's own
                raise ValueError(f"landing input has {v.size} entries, expected {size}")
        return out

    def residual(self, args: list[Any]) -> FloatArray:
        """``G``, shape ``(N_w,)``."""
        return self._G(self._flat(args))[0]

    def linearize(self, args: list[Any]) -> tuple[FloatArray, sp.csc_matrix]:
        """``(G, dG/dw)``."""
        g, jw = self._all(self._flat(args))
        return g, csc_with_data(self.template, jw)


_FUNCTIONS: dict[tuple[int, LandingLayout], tuple[Any, LandingFunctions]] = {}


def _functions(system: Any, layout: LandingLayout) -> LandingFunctions:
    key = (id(system), layout)
    hit = _FUNCTIONS.get(key)
    if hit is None or hit[0] is not system:
        if len(_FUNCTIONS) > 32:
            _FUNCTIONS.clear()
        hit = (system, LandingFunctions(system, layout))
        _FUNCTIONS[key] = hit
    return hit[1]


StartFn = Callable[[float], Any]


@dataclass(frozen=True, eq=False)
class LandingProblem:
    r"""An orbit from ``x_0(s)`` onto the stable manifold of ``x_e + shift`` (module doc).

    Parameters
    ----------
    system : System
        The dynamical system, with a CasADi trace (``rhs(x, p, ops)``).
    params : Params or mapping or array_like
        Values of all parameters; the entries of ``free`` are initial guesses.
    free : str or sequence of str
        Parameters solved for; as many as the equilibrium has unstable eigenvalues.
    start : callable or array_like, shape (n,)
        The start point: ``start(s) -> (n,)`` or a fixed point.
    saddle : array_like, shape (n,)
        Guess of the equilibrium ``x_e``; refined by Newton at construction.
    shift : mapping of str to float or array_like, shape (n,), optional
        The orbit ends at ``x_e + shift``: whole periods of periodic states
        (``{"theta": 2 * pi}``); default none.
    mesh : CollocationMesh, optional
        Intervals, degree and ``T``; or give ``T`` (then 40 intervals of degree 4).
    T : float, optional
        Length of the orbit (fixed; the end distance is free).
    s : float
        Value of the start parameter (ignored for a fixed ``start``).
    start_name : str
        Name of the start parameter (the continuation parameter of
        :func:`~continuation.bvp.landing_solve.continue_landing`).
    start_derivative : callable, optional
        ``dx_0/ds (s) -> (n,)``; default a central difference of ``start``.
    bases : ndarray, shape (n, n), optional
        Reference Schur basis at the end equilibrium (computed when omitted).

    Raises
    ------
    ValueError
        For unknown names, wrong shapes, a start that is not finite, a saddle guess
        that is not near an equilibrium, a non-hyperbolic equilibrium, a shift that is
        not a whole number of periods, or a count that does not close.
    """

    system: Any
    params: Params
    free: tuple[str, ...]
    start: Any
    saddle: FloatArray
    shift: Any = None
    mesh: CollocationMesh = None  # type: ignore[assignment]  # None: set in __post_init__
    T: float | None = None
    s: float = 0.0
    start_name: str = "s"
    start_derivative: StartFn | None = field(default=None, repr=False)
    bases: FloatArray | None = field(default=None, repr=False)
    layout: LandingLayout = field(init=False, repr=False)
    _cache: dict[float, FloatArray] = field(init=False, repr=False, default_factory=dict)

    def __post_init__(self) -> None:
        system = self.system
        if not getattr(system, "has_casadi", False):
            raise ValueError(
                "`system` must be a continuation.System with a CasADi trace "
                "(write rhs(x, p, ops) with ops functions)"
            )
        n = system.n_states
        params = self.params
        if not isinstance(params, Params):
            params = Params(system.param_names, system.check_params(params, "params"))
        if params.names != system.param_names:
            raise ValueError(f"`params` names {params.names} are not {system.param_names}")
        object.__setattr__(self, "params", params)
        unk = (self.free,) if isinstance(self.free, str) else tuple(str(u) for u in self.free)
        for u in unk:
            if u not in system.param_names:
                raise ValueError(
                    f"`free` names unknown parameter {u!r}; valid names are {system.param_names}"
                )
        if len(set(unk)) != len(unk) or not unk:
            raise ValueError(f"`free` must be one or more distinct parameters, got {unk}")
        object.__setattr__(self, "free", unk)
        try:
            s = float(self.s)
        except (TypeError, ValueError):
            raise ValueError(f"`s` must be a finite number, got {self.s!r}") from None
        if not math.isfinite(s):
            raise ValueError(f"`s` must be a finite number, got {self.s!r}")
        object.__setattr__(self, "s", s)
        if not isinstance(self.start_name, str) or not self.start_name:
            raise ValueError(f"`start_name` must be a non-empty string, got {self.start_name!r}")
        if not callable(self.start):
            x0 = system.check_state(self.start, "start")
            object.__setattr__(self, "start", x0)
        self.x0(s)  # validates the start callable's output
        pvec = np.array(params.values, dtype=float)
        x_eq = system.check_state(self.saddle, "saddle")
        x_eq = _refine_equilibrium(system, x_eq, pvec, "saddle")
        object.__setattr__(self, "saddle", x_eq)
        shift = _shift_vector(system, self.shift)
        object.__setattr__(self, "shift", shift)
        A = system.jacobian(x_eq + shift, pvec)
        ev = np.linalg.eigvals(A)
        nu, ns, gap = _count(ev, float(np.max(np.abs(ev))))
        if nu + ns != n:
            raise ValueError(
                f"`saddle` equilibrium is not hyperbolic (min |Re lambda| = {gap:.3g}); "
                f"eigenvalues {ev}"
            )
        if nu != len(unk):
            raise ValueError(
                f"landing count does not close: the equilibrium has dim W^u = {nu} unstable "
                f"direction(s), so {nu} parameter(s) must be solved, got `free` = {unk}"
            )
        if ns == 0:
            raise ValueError("the equilibrium has no stable direction: no orbit can land on it")
        if self.mesh is None:
            if self.T is None:
                raise ValueError("give `T=` (the length of the orbit) or `mesh=`")
            object.__setattr__(
                self, "mesh", CollocationMesh(DEFAULT_N_INTERVALS, DEFAULT_DEGREE, self.T)
            )
        if not isinstance(self.mesh, CollocationMesh):
            raise ValueError(f"`mesh` must be a CollocationMesh, got {type(self.mesh).__name__}")
        if self.T is not None and abs(float(self.T) - self.mesh.T) > 1e-12 * self.mesh.T:
            raise ValueError(f"`T` = {self.T!r} disagrees with `mesh.T` = {self.mesh.T!r}")
        object.__setattr__(self, "T", self.mesh.T)
        if self.bases is None:
            Q, k = _schur_basis(A, "unstable")
        else:
            Q = np.asarray(self.bases, dtype=float)
            if Q.shape != (n, n):
                raise ValueError(f"`bases` must be an ({n}, {n}) array, got {Q.shape}")
            k = nu
        object.__setattr__(self, "bases", Q)
        object.__setattr__(
            self, "layout",
            LandingLayout(n, self.mesh.n_intervals, self.mesh.degree, int(k),
                          tuple(system.param_index(u) for u in unk)),
        )  # fmt: skip

    # ------------------------------------------------------------------ start point
    def x0(self, s: float | None = None) -> FloatArray:
        """The start point ``x_0(s)``, shape ``(n,)`` (cached per ``s``)."""
        if not callable(self.start):
            return self.start
        s = self.s if s is None else float(s)
        hit = self._cache.get(s)
        if hit is None:
            try:
                hit = np.asarray(self.start(s), dtype=float).reshape(-1)
            except (TypeError, ValueError) as exc:
                raise ValueError(f"`start({s!r})` failed: {exc}") from None
            if hit.shape != (self.system.n_states,) or not np.all(np.isfinite(hit)):
                raise ValueError(
                    f"`start({s!r})` must return {self.system.n_states} finite numbers, got {hit}"
                )
            if len(self._cache) > 64:
                self._cache.clear()
            self._cache[s] = hit
        return hit

    def dx0(self, s: float | None = None) -> FloatArray:
        """``dx_0/ds``, shape ``(n,)`` (zero for a fixed start)."""
        if not callable(self.start):
            return np.zeros(self.system.n_states)
        s = self.s if s is None else float(s)
        if self.start_derivative is not None:
            return np.asarray(self.start_derivative(s), dtype=float).reshape(-1)
        h = FD_STEP * max(1.0, abs(s))
        return (self.x0(s + h) - self.x0(s - h)) / (2.0 * h)

    # ------------------------------------------------------------------ structure
    @property
    def functions(self) -> LandingFunctions:
        """The compiled functions of this layout (cached per system and layout)."""
        return _functions(self.system, self.layout)

    @property
    def n_unknowns(self) -> int:
        """Length of ``z``."""
        return self.layout.n_unknowns

    @property
    def state_names(self) -> tuple[str, ...]:
        """Names of the states."""
        return tuple(self.system.state_names)

    def replace(self, **changes: Any) -> LandingProblem:
        """A copy with some fields changed (a new ``mesh`` brings its ``T``)."""
        if "mesh" in changes and "T" not in changes:
            changes["T"] = None
        elif "T" in changes and "mesh" not in changes and changes["T"] is not None:
            changes["mesh"] = self.mesh.with_T(float(changes["T"]))
        new = dataclasses.replace(self, **changes)
        if callable(self.start) and new.start is self.start:
            new._cache.update(self._cache)
        return new

    # ------------------------------------------------------------------ packing
    def pack(self, X: FloatArray, x_eq: FloatArray | None = None,
             values: Any = None, R: FloatArray | None = None) -> FloatArray:  # fmt: skip
        """``z`` from the orbit ``X`` (M, n), the equilibrium, the parameters and ``R``."""
        lay, sl = self.layout, self.layout.slices()
        X = np.asarray(X, dtype=float)
        if X.shape != (lay.n_points, lay.n):
            raise ValueError(f"`X` must have shape ({lay.n_points}, {lay.n}), got {X.shape}")
        z = np.zeros(lay.n_unknowns)
        z[sl["orbit"]] = X.reshape(-1)
        z[sl["x_eq"]] = self.saddle if x_eq is None else x_eq
        if R is not None:
            z[sl["R"]] = np.asarray(R, dtype=float).reshape(-1, order="F")
        vals = [self.params[u] for u in self.free] if values is None else values
        z[sl["params"]] = np.asarray(vals, dtype=float)
        return z

    def unpack(self, z: FloatArray) -> dict[str, Any]:
        """``X`` (M, n), ``x_eq``, ``x_end`` (= x_eq + shift), ``R``, ``params`` of ``z``."""
        lay, sl = self.layout, self.layout.slices()
        z = np.asarray(z, dtype=float)
        if z.shape != (lay.n_unknowns,):
            raise ValueError(f"`z` must have shape ({lay.n_unknowns},), got {z.shape}")
        k = lay.k_plus
        return {
            "X": z[sl["orbit"]].reshape(lay.n_points, lay.n),
            "x_eq": z[sl["x_eq"]],
            "x_end": z[sl["x_eq"]] + self.shift,
            "R": z[sl["R"]].reshape((lay.n - k, k), order="F"),
            "params": dict(zip(self.free, z[sl["params"]].tolist(), strict=True)),
        }

    def param_vector(self, z: FloatArray) -> FloatArray:
        """The full parameter vector with the solved parameters from ``z``."""
        v = np.array(self.params.values, dtype=float)
        v[list(self.layout.unknown_param_index)] = np.asarray(z)[self.layout.slices()["params"]]
        return v

    # ------------------------------------------------------------------ residual
    def _args(self, z: FloatArray, s: float | None) -> list[Any]:
        z = np.asarray(z, dtype=float)
        if z.shape != (self.layout.n_unknowns,):
            raise ValueError(f"`z` must have shape ({self.layout.n_unknowns},), got {z.shape}")
        return [z, np.array(self.params.values, dtype=float), self.mesh.h, self.mesh.T,
                self.bases, self.shift, self.x0(s)]  # fmt: skip

    def residual(self, z: FloatArray, s: float | None = None) -> FloatArray:
        """``G(z, s)``, shape ``(N_z,)`` (``s`` default the problem's)."""
        return self.functions.residual(self._args(z, s))

    def jacobian(self, z: FloatArray, s: float | None = None) -> sp.csc_matrix:
        """Exact ``dG/dz`` (CSC), shape ``(N_z, N_z)``."""
        return self.functions.linearize(self._args(z, s))[1]

    def dp(self, z: FloatArray, s: float | None = None) -> FloatArray:
        """``dG/ds = -dx_0/ds`` on the start rows, shape ``(N_z,)``."""
        out = np.zeros(self.layout.n_unknowns)
        out[self.layout.start_rows] = -self.dx0(s)
        return out

    def linearize(self, z: FloatArray, s: float | None = None) -> tuple[Any, Any, FloatArray]:
        """``(G, dG/dz, dG/ds)``."""
        g, J = self.functions.linearize(self._args(z, s))
        return g, J, self.dp(z, s)

    def record(self, z: FloatArray, s: float | None = None) -> dict[str, float]:
        """Solved parameters, the end distance ``|x(T) - x_+|`` and the Riccati norm."""
        parts = self.unpack(z)
        out = {k: float(v) for k, v in parts["params"].items()}
        out["end_distance"] = float(np.linalg.norm(parts["X"][-1] - parts["x_end"]))
        out["riccati_norm"] = float(np.max(np.abs(parts["R"]))) if parts["R"].size else 0.0
        return out

    # ------------------------------------------------------------------ starting data
    def initial_vector(self, guess: Any) -> FloatArray:
        """``z`` from a guess.

        A :class:`~continuation.bvp.landing_solve.LandingResult`, a ``(t, x)`` pair, an
        object with ``t`` and ``x``/``y``, or an (K, n) array.

        The guess is read in its own time from its start (``t[0]``); where it is shorter
        than ``T`` it is held at its last value. A bare array is taken as equally
        spaced on ``[0, T]``.
        """
        mesh = self.mesh
        x_eq, values = None, None
        if hasattr(guess, "problem") and hasattr(guess, "mesh") and hasattr(guess, "x_eq"):
            T_g = float(guess.mesh.T)
            X = guess.mesh.interpolate(guess.x, np.clip(mesh.t, 0.0, T_g) / T_g)
            x_eq = np.asarray(guess.x_eq, dtype=float) - self.shift
            values = [guess.params[u] for u in self.free]
            return self.pack(X, x_eq, values)
        t, x = _as_trajectory(guess, self.system.n_states)
        if isinstance(guess, np.ndarray):
            t = t * mesh.T
        tt = np.clip(t[0] + mesh.t, t[0], t[-1])
        X = np.column_stack([np.interp(tt, t, x[:, i]) for i in range(x.shape[1])])
        return self.pack(X)

    def rebased(self, z: FloatArray, s: float | None = None) -> tuple[LandingProblem, FloatArray]:
        """The problem with the Schur basis, ``params``, ``saddle`` and ``s`` of ``z``."""
        parts = self.unpack(z)
        pvec = self.param_vector(z)
        Q, _ = _schur_basis(self.system.jacobian(parts["x_end"], pvec), "unstable")
        new = self.replace(
            params=self.params.with_vector(pvec), saddle=parts["x_eq"], bases=Q,
            s=self.s if s is None else float(s),
        )  # fmt: skip
        return new, new.pack(parts["X"], parts["x_eq"], list(parts["params"].values()))


def _shift_vector(system: Any, shift: Any) -> FloatArray:
    n = system.n_states
    if shift is None:
        vec = np.zeros(n)
    elif isinstance(shift, Mapping):
        vec = np.zeros(n)
        for k, v in shift.items():
            vec[system.state_index(k)] = float(v)
    else:
        vec = np.asarray(shift, dtype=float).reshape(-1)
        if vec.shape != (n,):
            raise ValueError(f"`shift` must have shape ({n},), got {vec.shape}")
    if not np.all(np.isfinite(vec)):
        raise ValueError(f"`shift` must be finite, got {vec}")
    period = np.asarray(system.period, dtype=float)
    for i in np.flatnonzero(vec):
        if period[i] <= 0:
            raise ValueError(
                f"`shift` is nonzero on state {system.state_names[i]!r}, which is not periodic"
            )
        r = vec[i] / period[i]
        if abs(r - round(r)) > 1e-9 * max(1.0, abs(r)):
            raise ValueError(
                f"`shift` of state {system.state_names[i]!r} is {vec[i]}, not a whole multiple "
                f"of its period {period[i]}"
            )
    vec.setflags(write=False)
    return vec


__all__ = ["LandingFunctions", "LandingLayout", "LandingProblem"]
