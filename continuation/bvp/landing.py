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

The landing is a connection whose start condition differs: it is discretised by the
connections' collocation core (:class:`~continuation.bvp.casadi_backend.ConnectionLayout`
with ``start_point=True``, the same residual, Jacobians, condensation and caches).
Unknowns and equations (``M = N (m + 1) + 1`` points, ``k = dim W^u(x_e)``)::

    w = [ vec(X) (n M),  x_e (n),  vec(R) ((n-k) k),  solved parameters (q = k) ]
    collocation (n N m), continuity (n N), start (n), equilibrium (n),
    Riccati ((n-k) k), end projection (k)
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..arguments import finite_number
from ..params import Params
from ..typing import FloatArray
from .casadi_backend import ConnectionFunctions, ConnectionLayout, build_connection_functions
from .collocation import CollocationMesh
from .connection import (
    _as_trajectory,
    _checked_orbit_fields,
    _hyperbolic_dims,
    _mesh_changes,
    _refine_equilibrium,
    _schur_basis,
    _set_mesh,
    _shift_vector,
)
from .result import LandingResult, ToResult

#: Relative step of the central difference of ``x_0(s)`` when no derivative is given.
FD_STEP = 1e-5


StartFn = Callable[[float], Any]


@dataclass(frozen=True, eq=False)
class LandingProblem(ToResult[LandingResult]):
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
    layout: ConnectionLayout = field(init=False, repr=False)
    _cache: dict[float, FloatArray] = field(init=False, repr=False, default_factory=dict)

    def __post_init__(self) -> None:
        system, params, unk = _checked_orbit_fields(self)
        n = system.n_states
        if not unk:
            raise ValueError(f"`free` must be one or more distinct parameters, got {unk}")
        s = finite_number("s", self.s)
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
        shift = np.zeros(n) if self.shift is None else _shift_vector(system, self.shift)
        shift.setflags(write=False)
        object.__setattr__(self, "shift", shift)
        A = system.jacobian(x_eq + shift, pvec)
        nu, ns = _hyperbolic_dims(A, "`saddle`")
        if nu != len(unk):
            raise ValueError(
                f"landing count does not close: the equilibrium has dim W^u = {nu} unstable "
                f"direction(s), so {nu} parameter(s) must be solved, got `free` = {unk}"
            )
        if ns == 0:
            raise ValueError("the equilibrium has no stable direction: no orbit can land on it")
        mesh = _set_mesh(self, "give `T=` (the length of the orbit) or `mesh=`")
        if self.bases is None:
            Q, k = _schur_basis(A, "unstable")
        else:
            Q = np.asarray(self.bases, dtype=float)
            if Q.shape != (n, n):
                raise ValueError(f"`bases` must be an ({n}, {n}) array, got {Q.shape}")
            k = nu
        object.__setattr__(self, "bases", Q)
        layout = ConnectionLayout(
            n=n,
            n_intervals=mesh.n_intervals,
            degree=mesh.degree,
            separate_to=False,
            k_minus=0,
            k_plus=int(k),
            unknown_param_index=tuple(system.param_index(u) for u in unk),
            pin=None,
            start_point=True,
        )
        object.__setattr__(self, "layout", layout)

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
    def functions(self) -> ConnectionFunctions:
        """The compiled functions of this layout (cached per system and layout)."""
        return build_connection_functions(self.system, self.layout)

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
        new = dataclasses.replace(self, **_mesh_changes(self, changes))  # type: ignore[arg-type]
        if callable(self.start) and new.start is self.start:
            new._cache.update(self._cache)
        return new

    # ------------------------------------------------------------------ packing
    def pack(self, X: FloatArray, x_eq: FloatArray | None = None,
             values: Any = None, R: FloatArray | None = None) -> FloatArray:  # fmt: skip
        """``z`` from the orbit ``X`` (M, n), the equilibrium, the parameters and ``R``."""
        lay, sl = self.layout, self.layout.slices()
        z = lay.orbit_unknowns(X)
        z[sl["x_to"]] = self.saddle if x_eq is None else x_eq
        if R is not None:
            z[sl["R_plus"]] = np.asarray(R, dtype=float).reshape(-1, order="F")
        vals = [self.params[u] for u in self.free] if values is None else values
        z[sl["params"]] = np.asarray(vals, dtype=float)
        return z

    def unpack(self, z: FloatArray) -> dict[str, Any]:
        """``X`` (M, n), ``x_eq``, ``x_end`` (= x_eq + shift), ``R``, ``params`` of ``z``."""
        lay, sl = self.layout, self.layout.slices()
        z = lay.checked(z)
        k = lay.k_plus
        return {
            "X": lay.orbit_of(z),
            "x_eq": z[sl["x_to"]],
            "x_end": z[sl["x_to"]] + self.shift,
            "R": z[sl["R_plus"]].reshape((lay.n - k, k), order="F"),
            "params": lay.solved_params(z, self.free),
        }

    def param_vector(self, z: FloatArray) -> FloatArray:
        """The full parameter vector with the solved parameters from ``z``."""
        return self.layout.full_params(self.params.values, z)

    # ------------------------------------------------------------------ residual
    def _args(self, z: FloatArray, s: float | None) -> list[Any]:
        z = self.layout.checked(z)
        return [z, np.array(self.params.values, dtype=float), self.mesh.h, self.mesh.T,
                self.bases, self.shift, self.x0(s)]  # fmt: skip

    def residual(self, z: FloatArray, s: float | None = None) -> FloatArray:
        """``G(z, s)``, shape ``(N_z,)`` (``s`` default the problem's)."""
        return self.functions.residual(self._args(z, s))

    def jacobian(self, z: FloatArray, s: float | None = None) -> sp.csc_matrix:
        """Exact ``dG/dz`` (CSC), shape ``(N_z, N_z)``."""
        return self.functions.jacobian(self._args(z, s))

    def dp(self, z: FloatArray, s: float | None = None) -> FloatArray:
        """``dG/ds = -dx_0/ds`` on the start rows, shape ``(N_z,)``."""
        out = np.zeros(self.layout.n_unknowns)
        out[self.layout.start_rows] = -self.dx0(s)
        return out

    def linearize(self, z: FloatArray, s: float | None = None) -> tuple[Any, Any, FloatArray]:
        """``(G, dG/dz, dG/ds)``."""
        g, J = self.functions.residual_jacobian(self._args(z, s))
        return g, J, self.dp(z, s)

    def record(self, z: FloatArray, s: float | None = None) -> dict[str, float]:
        """Solved parameters, the end distance ``|x(T) - x_+|`` and the Riccati norm."""
        parts = self.unpack(z)
        out = {k: float(v) for k, v in parts["params"].items()}
        out["end_distance"] = float(np.linalg.norm(parts["X"][-1] - parts["x_end"]))
        out["riccati_norm"] = float(np.max(np.abs(parts["R"]))) if parts["R"].size else 0.0
        return out

    def _result_parts(
        self, z: FloatArray, s: float | None
    ) -> tuple[type[LandingResult], float | None, dict[str, Any]]:
        """A :class:`LandingResult` at start parameter ``s`` (:meth:`ToResult.to_result`).

        The connection's result (:class:`~continuation.bvp.result.OrbitResult`) with its
        start condition recorded: ``x_from`` the start point ``x_0(s)``, ``s`` and
        ``start_name``.
        """
        s = self.s if s is None else float(s)
        params = self.params.with_vector(self.param_vector(z))
        return LandingResult, s, {"params": params, "x_from": self.x0(s),
                                  "x_to": self.unpack(z)["x_end"], "s": s,
                                  "start_name": self.start_name}  # fmt: skip

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


__all__ = ["LandingProblem"]
