r"""Connecting orbits between saddle equilibria as a collocation boundary-value problem.

:class:`HeteroclinicProblem` describes an orbit :math:`x(t)` of :math:`\dot x = f(x, p)`
that leaves a saddle :math:`x_-` and arrives at a saddle :math:`x_+`, truncated to
:math:`t \in [0, T]` with the projection boundary conditions of Beyn (1990, "The
numerical computation of connecting orbits in dynamical systems", IMA J. Numer.
Anal. 10:379-405)::

    L_s(x_-)^T (x(0) - x_-) = 0      x(0) in the unstable eigenspace of A_- = f_x(x_-, p)
    L_u(x_+)^T (x(T) - x_+) = 0      x(T) in the stable eigenspace of A_+ = f_x(x_+, p)
    f(x_-, p) = 0,  f(x_+, p) = 0    the equilibria are unknowns too
    phase condition                  removes the time-shift invariance

where the columns of ``L_s(x_-)`` span the stable invariant subspace of ``A_-^T`` (the
orthogonal complement of the unstable eigenspace of ``A_-``) and those of
``L_u(x_+)`` the unstable invariant subspace of ``A_+^T``. The end point is either a
separate equilibrium (``saddle_to``) or the start shifted by whole periods of the
system's periodic states (``shift``; then ``x_+ = x_- + shift`` is not a separate
unknown), as for a front on a circle or a ship's wave-relative position; a zero
shift makes the orbit homoclinic.

Counting (Beyn 1990, sec. 2): with ``q`` unknown parameters the discretised system is
square only if ``dim W^u(x_-) + dim W^s(x_+) = n + 1 - q``; the constructor checks
this at the initial parameters and raises ``ValueError`` naming the numbers.

Projection bases: smooth, by Riccati equations
-----------------------------------------------
The bases are not frozen at a reference value: they are unknowns. A real Schur
decomposition of ``A^T`` at the initial (or last rebased) equilibrium gives an
orthogonal ``Q = [Q_1 Q_2]`` whose first ``k`` columns span the wanted invariant
subspace. Nearby, the subspace of the current ``A`` is ``range(Q_1 + Q_2 R)``, where
``R`` ((n-k) x k) solves the algebraic Riccati equation
``T21 + T22 R - R T11 - R T12 R = 0`` with ``T = Q^T A^T Q`` (Demmel, Dieci & Friedman
2000, "Computing connecting orbits via an improved algorithm for continuing
invariant subspaces", SIAM J. Sci. Comput. 22:81-94; Champneys, Kuznetsov &
Sandstede 1996, "A numerical toolbox for homoclinic bifurcation analysis", Int. J.
Bifurcation Chaos 6:867-887). ``R`` is part of the unknowns and the Riccati
equations part of the residual, so the whole residual is one smooth function of
``(z, p)`` with an exact CasADi Jacobian: Newton and the pseudo-arclength corrector
see no basis updates at all, not even between continuation steps. ``Q`` is refreshed
("rebased", ``R = 0``) only between solves (:meth:`HeteroclinicProblem.rebased`),
never inside one. The Riccati equation stays solvable while the subspace remains a
graph over ``Q_1`` (``record`` reports ``riccati_norm`` along a branch).

Phase condition
---------------
Default ``phase="integral"``: the discrete form of
:math:`\int_0^1 \langle x(\tau) - \hat x(\tau), \hat x'(\tau)\rangle d\tau = 0`
against a reference orbit :math:`\hat x` (the starting guess, or the last solution
after rebasing), by Gauss quadrature at the collocation points (Doedel & Friedman
1989, "Numerical computation of heteroclinic orbits", J. Comput. Appl. Math.
26:155-170). It selects the time shift closest (in L2) to the reference.
Alternatively :class:`PinPhase` fixes one state at one mesh node.
"""

from __future__ import annotations

import copy
import dataclasses
import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp

from ..newton import newton as _newton
from ..params import Params
from ..settings import NewtonSettings
from ..system import as_params
from ..typing import FloatArray
from .casadi_backend import ConnectionFunctions, ConnectionLayout, build_connection_functions
from .collocation import CollocationMesh
from .layout import phase_reference
from .result import ConnectionResult, ToResult

log = logging.getLogger(__name__)

HYPERBOLIC_TOL = 1e-8
#: Mesh of a problem given ``T`` but no ``mesh`` (the adaptive solve refines it).
DEFAULT_N_INTERVALS = 40
DEFAULT_DEGREE = 4


@dataclass(frozen=True)
class PinPhase:
    """Phase condition ``x_state(t_pin) = value`` at the mesh node nearest ``at * T``.

    Parameters
    ----------
    state : str
        Name of the pinned state.
    value : float or None
        Pinned value; None takes the guess's value at that node when solving.
    at : float
        Position of the node in ``tau = t / T``, in ``[0, 1]`` (default the middle).
    """

    state: str
    value: float | None = None
    at: float = 0.5

    def __post_init__(self) -> None:
        if not (0.0 <= float(self.at) <= 1.0):
            raise ValueError(f"`at` of PinPhase must be in [0, 1], got {self.at!r}")
        if self.value is not None and not np.isfinite(self.value):
            raise ValueError(f"`value` of PinPhase must be finite, got {self.value!r}")


def _count(eigs: np.ndarray, scale: float) -> tuple[int, int, float]:
    re = eigs.real
    tol = HYPERBOLIC_TOL * max(1.0, scale)
    return int(np.sum(re > tol)), int(np.sum(re < -tol)), float(np.min(np.abs(re)))


def _hyperbolic_dims(A: FloatArray, name: str) -> tuple[int, int]:
    """``(dim W^u, dim W^s)`` of the equilibrium with Jacobian ``A``; ValueError if not hyperbolic.

    ``name`` names the equilibrium in the message (``"`saddle`"``, ``"end"``).
    """
    ev = np.linalg.eigvals(A)
    nu, ns, gap = _count(ev, float(np.max(np.abs(ev))))
    if nu + ns != ev.size:
        raise ValueError(
            f"{name} equilibrium is not hyperbolic (min |Re lambda| = {gap:.3g}); eigenvalues {ev}"
        )
    return nu, ns


def _schur_basis(A: FloatArray, which: str) -> tuple[FloatArray, int]:
    """Orthogonal ``Q`` whose first ``k`` columns span the ``which`` subspace of ``A^T``."""
    sort = "lhp" if which == "stable" else "rhp"
    _, Q, k = la.schur(np.asarray(A, dtype=float).T, output="real", sort=sort)
    return np.asarray(Q, dtype=float), int(k)


def _refine_equilibrium(system: Any, x0: FloatArray, pvec: FloatArray, name: str) -> FloatArray:
    if np.max(np.abs(system.f(x0, pvec))) <= 1e-13 * (1.0 + np.max(np.abs(x0))):
        return np.asarray(x0, dtype=float)  # already an equilibrium (maybe non-hyperbolic)
    res = _newton(
        lambda x: system.f(x, pvec),
        lambda x: system.jacobian(x, pvec),
        x0,
        NewtonSettings(tol=1e-11, max_iter=30, damping=True),
    )
    if not res.converged:
        raise ValueError(
            f"`{name}` is not near an equilibrium at the given parameters: {res.message}"
        )
    return np.asarray(res.z, dtype=float)


@dataclass(frozen=True, eq=False)
class HeteroclinicProblem(ToResult[ConnectionResult]):
    r"""A connecting orbit from saddle ``x_-`` to saddle ``x_+`` (equations: module docstring).

    Implements the :class:`~continuation.problem.ContinuationProblem` protocol with
    ``z`` the discretised orbit, the equilibria, the Riccati unknowns and the
    solved parameters ``free``; the continuation parameter is ``vary`` (the names of
    :func:`~continuation.equilibria.continue_equilibria`: ``free`` is what is solved).
    The driver's protocol attribute ``free`` (its continuation parameter) is served by
    the adapter :func:`continued` that :func:`~continuation.bvp.solve.continue_connection`
    builds.

    Parameters
    ----------
    system : System
        The dynamical system; it must have a CasADi trace (``rhs(x, p, ops)``).
    params : Params or mapping or array_like
        Values of all parameters; the entries of ``free`` are initial guesses.
    free : str or sequence of str
        Parameters solved for (``q`` of them; the connection count must close).
    saddle_from : array_like, shape (n,)
        Guess of the start saddle ``x_-``; refined by Newton at construction.
    saddle_to : array_like, shape (n,), optional
        Guess of a separate end saddle ``x_+``.
    shift : array_like, shape (n,) or mapping of str to float, optional
        ``x_+ = x_- + shift``; nonzero only on periodic states, as whole multiples of
        their period (a mapping names states: ``{"theta": 2 * pi}``). Give exactly one
        of ``saddle_to`` and ``shift``. ``shift=0`` asks for a homoclinic orbit
        (``x_+ = x_-``); then the constant solution ``x = x_-`` also satisfies every
        equation but the phase condition, so start from a good guess.
    mesh : CollocationMesh, optional
        Intervals, degree and truncation time ``T``. Give ``mesh`` or ``T``; without
        either the constructor raises (a connection has no natural default ``T``;
        :func:`~continuation.bvp.find.find_connection` picks one from the saddles'
        eigenvalues).
    T : float, optional
        Truncation time; with ``mesh`` omitted the mesh is 40 uniform intervals of
        degree 4 on ``[0, T]`` (the adaptive solve refines it). Given with ``mesh`` it
        must equal ``mesh.T``.
    vary : str or None
        The continuation parameter (None for one-shot solves).
    phase : "integral" or PinPhase
        The phase condition.
    reference : ndarray, shape (M, n), optional
        Reference orbit on the mesh's ``M`` points for ``phase="integral"``; set by
        :func:`~continuation.bvp.solve.solve_connection` from the guess.
    bases : tuple of ndarray, optional
        Reference Schur bases ``(Q_minus, Q_plus)``, each ``(n, n)``; computed at the
        saddles when omitted.

    Raises
    ------
    ValueError
        For unknown parameter or state names, wrong shapes, a saddle guess that is not
        near an equilibrium, a non-hyperbolic equilibrium, a shift that is not a whole
        number of periods, or a dimension count that does not close.
    """

    system: Any
    params: Params
    free: tuple[str, ...]
    saddle_from: FloatArray
    saddle_to: FloatArray | None = None
    shift: FloatArray | None = None
    mesh: CollocationMesh = None  # type: ignore[assignment]  # None: set in __post_init__
    T: float | None = None
    vary: str | None = None
    phase: str | PinPhase = "integral"
    reference: FloatArray | None = field(default=None, repr=False)
    bases: tuple[FloatArray, FloatArray] | None = field(default=None, repr=False)
    # derived
    layout: ConnectionLayout = field(init=False, repr=False)
    dims: dict[str, int] = field(init=False, repr=False)
    _fns: list[ConnectionFunctions] = field(init=False, repr=False, default_factory=list)

    # ------------------------------------------------------------------ validation
    def __post_init__(self) -> None:
        system, params, unk = _checked_orbit_fields(self)
        n = system.n_states
        if self.vary is not None:
            if self.vary not in system.param_names:
                raise ValueError(f"`vary` must be one of {system.param_names}, got {self.vary!r}")
            if self.vary in unk:
                raise ValueError(f"`vary` {self.vary!r} is also a solved (`free`) parameter {unk}")
        # end point
        pvec = np.array(params.values, dtype=float)
        x_from = _refine_equilibrium(
            system, system.check_state(self.saddle_from, "saddle_from"), pvec, "saddle_from"
        )
        if (self.saddle_to is None) == (self.shift is None):
            raise ValueError("give exactly one of `saddle_to` and `shift`")
        if self.shift is not None:
            shift = _shift_vector(system, self.shift)
            object.__setattr__(self, "shift", shift)
            x_to = x_from + shift
            separate = False
        else:
            x_to = _refine_equilibrium(
                system, system.check_state(self.saddle_to, "saddle_to"), pvec, "saddle_to"
            )
            separate = True
            if np.max(np.abs(x_to - x_from)) < 1e-8 * (1 + np.max(np.abs(x_from))):
                raise ValueError(
                    "`saddle_to` converged to the same equilibrium as `saddle_from`; for a "
                    "homoclinic orbit give `shift=0` instead"
                )
        object.__setattr__(self, "saddle_from", x_from)
        if separate:
            object.__setattr__(self, "saddle_to", x_to)
        # hyperbolicity and counting
        A_m = system.jacobian(x_from, pvec)
        A_p = system.jacobian(x_to, pvec)
        nu_m, _ = _hyperbolic_dims(A_m, "`saddle_from`")
        _, ns_p = _hyperbolic_dims(A_p, "end")
        q = len(unk)
        if nu_m + ns_p != n + 1 - q:
            raise ValueError(
                f"connection count does not close: dim W^u(x_-) + dim W^s(x_+) = {nu_m} + {ns_p}"
                f" = {nu_m + ns_p}, but an orbit with {q} solved parameter(s) {unk} in "
                f"dimension n = {n} needs n + 1 - q = {n + 1 - q}"
            )
        if nu_m == 0:
            raise ValueError("`saddle_from` has no unstable direction: no orbit can leave it")
        if ns_p == 0:
            raise ValueError("the end equilibrium has no stable direction: no orbit can reach it")
        _set_mesh(
            self, "give `T=` (the truncation interval) or `mesh=`; there is no "
            "default T (find_connection picks T from the saddles' eigenvalues)"
        )  # fmt: skip
        # phase
        pin = None
        if isinstance(self.phase, PinPhase):
            i_state = system.state_index(self.phase.state)
            i_node = int(np.argmin(np.abs(self.mesh.nodes - self.phase.at)))
            pin = (i_state, i_node)
        elif self.phase != "integral":
            raise ValueError(f"`phase` must be 'integral' or a PinPhase, got {self.phase!r}")
        object.__setattr__(
            self,
            "dims",
            {"n": n, "unstable_from": nu_m, "stable_to": ns_p, "free": q},
        )
        # bases
        if self.bases is None:
            Qm, km = _schur_basis(A_m, "stable")
            Qp, kp = _schur_basis(A_p, "unstable")
            object.__setattr__(self, "bases", (Qm, Qp))
        else:
            Qm, Qp = (np.asarray(b, dtype=float) for b in self.bases)
            if Qm.shape != (n, n) or Qp.shape != (n, n):
                raise ValueError(f"`bases` must be two ({n}, {n}) arrays")
            object.__setattr__(self, "bases", (Qm, Qp))
            km, kp = n - nu_m, n - ns_p
        if km != n - nu_m or kp != n - ns_p:  # pragma: no cover - Schur/eig disagreement
            raise ValueError("Schur ordering disagrees with the eigenvalue count")
        object.__setattr__(
            self,
            "layout",
            ConnectionLayout(
                n=n,
                n_intervals=self.mesh.n_intervals,
                degree=self.mesh.degree,
                separate_to=separate,
                k_minus=km,
                k_plus=kp,
                unknown_param_index=tuple(system.param_index(u) for u in unk),
                pin=pin,
            ),
        )
        if self.reference is not None:
            ref = np.asarray(self.reference, dtype=float)
            if ref.shape != (self.mesh.n_points, n):
                raise ValueError(
                    f"`reference` must have shape ({self.mesh.n_points}, {n}), got {ref.shape}"
                )
            ref = ref.copy()
            ref.setflags(write=False)
            object.__setattr__(self, "reference", ref)

    # ------------------------------------------------------------------ structure
    @property
    def functions(self) -> ConnectionFunctions:
        """The compiled CasADi functions (built once per system and layout, cached)."""
        if not self._fns:
            self._fns.append(build_connection_functions(self.system, self.layout))
        return self._fns[0]

    @property
    def n_unknowns(self) -> int:
        """Length of ``z``."""
        return self.layout.n_unknowns

    @property
    def n_states(self) -> int:
        """State dimension ``n``."""
        return int(self.system.n_states)

    @property
    def state_names(self) -> tuple[str, ...]:
        """Names of the states."""
        return tuple(self.system.state_names)

    def replace(self, **changes: Any) -> HeteroclinicProblem:
        """A copy with some fields changed (re-validated; derived data recomputed).

        A new ``mesh`` brings its own ``T``; a new ``T`` alone keeps the nodes.
        """
        return dataclasses.replace(self, **_mesh_changes(self, changes))

    def with_vary(self, vary: str | None) -> HeteroclinicProblem:
        """The same problem with continuation parameter ``vary``."""
        return self.replace(vary=vary)

    # ------------------------------------------------------------------ packing
    def pack(
        self,
        X: FloatArray,
        x_from: FloatArray | None = None,
        x_to: FloatArray | None = None,
        unknown_values: Sequence[float] | None = None,
        R_minus: FloatArray | None = None,
        R_plus: FloatArray | None = None,
    ) -> FloatArray:
        """Assemble ``z`` from the orbit ``X`` (M, n) and the other blocks.

        Omitted blocks default to the problem's data (saddles, parameter guesses, R = 0).
        """
        lay, sl = self.layout, self.layout.slices()
        z = lay.orbit_unknowns(X)
        z[sl["x_from"]] = self.saddle_from if x_from is None else x_from
        if lay.separate_to:
            z[sl["x_to"]] = self.saddle_to if x_to is None else x_to
        if R_minus is not None:
            z[sl["R_minus"]] = np.asarray(R_minus, dtype=float).reshape(-1, order="F")
        if R_plus is not None:
            z[sl["R_plus"]] = np.asarray(R_plus, dtype=float).reshape(-1, order="F")
        if unknown_values is None:
            unknown_values = [self.params[u] for u in self.free]
        z[sl["params"]] = np.asarray(unknown_values, dtype=float)
        return z

    def unpack(self, z: FloatArray) -> dict[str, Any]:
        """Split ``z``: ``X`` (M, n), ``x_from``, ``x_to``, ``R_minus``, ``R_plus``, ``params``."""
        lay, sl = self.layout, self.layout.slices()
        z = lay.checked(z)
        n = lay.n
        x_from = z[sl["x_from"]]
        x_to = z[sl["x_to"]] if lay.separate_to else x_from + np.asarray(self.shift)
        km, kp = lay.k_minus, lay.k_plus
        return {
            "X": lay.orbit_of(z),
            "x_from": x_from,
            "x_to": x_to,
            "R_minus": z[sl["R_minus"]].reshape((n - km, km), order="F"),
            "R_plus": z[sl["R_plus"]].reshape((n - kp, kp), order="F"),
            "params": lay.solved_params(z, self.free),
        }

    def param_vector(self, z: FloatArray, p: float | None = None) -> FloatArray:
        """Full parameter vector: ``params``, ``vary`` set to ``p``, ``free`` from ``z``."""
        v = self.layout.full_params(self.params.values, z)
        if self.vary is not None and p is not None:  # (never a `free` one: __post_init__)
            v[self.system.param_index(self.vary)] = float(p)
        return v

    # ------------------------------------------------------------------ residual
    def _data(self) -> list[Any]:
        """The numeric non-unknown inputs (h, T, Qm, Qp, shift, ref, dref, pin)."""
        lay, mesh = self.layout, self.mesh
        n = lay.n
        if lay.pin is None:
            if self.reference is None:
                raise ValueError(
                    "the integral phase condition needs a `reference` orbit; solve with "
                    "solve_connection(problem, guess) or set problem.replace(reference=...)"
                )
            ref, dref = (a.T for a in phase_reference(mesh, self.reference))
            pin = 0.0
        else:
            ref = np.zeros((n, lay.n_stages))
            dref = ref
            if not isinstance(self.phase, PinPhase) or self.phase.value is None:
                raise ValueError("PinPhase value is unresolved; solve with solve_connection")
            pin = float(self.phase.value)
        shift = np.zeros(n) if self.shift is None else np.asarray(self.shift)
        Qm, Qp = self.bases  # type: ignore[misc]
        return [mesh.h, mesh.T, Qm, Qp, shift, ref, dref, pin]

    def _args(self, z: FloatArray, p: float | None) -> list[Any]:
        z = self.layout.checked(z)
        cache = self.__dict__.get("_data_cache")
        if cache is None:  # flattened once: the evaluator reads NumPy buffers
            cache = self.functions.flat_args([z, self.param_vector(z, p), *self._data()])[2:]
            object.__setattr__(self, "_data_cache", cache)
        return [np.ascontiguousarray(z), self.param_vector(z, p), *cache]

    def residual(self, z: FloatArray, p: float | None = None) -> FloatArray:
        """``G(z, p)``, shape ``(N_z,)`` (``p``: value of ``vary``; ignored if ``vary`` is None)."""
        return self.functions.residual(self._args(z, p))

    def jacobian(self, z: FloatArray, p: float | None = None) -> sp.csc_matrix:
        """Exact ``dG/dz`` as SciPy CSC, shape ``(N_z, N_z)``."""
        return self.functions.jacobian(self._args(z, p))

    def dp(self, z: FloatArray, p: float | None = None) -> FloatArray:
        """Exact ``dG/dp`` for the ``vary`` parameter, shape ``(N_z,)``."""
        if self.vary is None:
            raise ValueError("`vary` is None: set a continuation parameter with with_vary(name)")
        J = self.functions.param_jacobian(self._args(z, p))
        return _csc_column(J, self.system.param_index(self.vary))

    def linearize(
        self, z: FloatArray, p: float | None = None
    ) -> tuple[FloatArray, sp.csc_matrix, FloatArray]:
        """``(G, dG/dz, dG/dp)`` in one CasADi evaluation (used by the PALC driver)."""
        if self.vary is None:
            raise ValueError("`vary` is None: set a continuation parameter with with_vary(name)")
        g, jz, jp = self.functions.linearize(self._args(z, p))
        return g, jz, _csc_column(jp, self.system.param_index(self.vary))

    def stability(self, z: FloatArray, p: float | None = None) -> None:
        """Connections carry no stability eigenvalues here; returns None."""
        return None

    def record(self, z: FloatArray, p: float | None = None) -> dict[str, float]:
        """Unknown parameters, end distances to the saddles and the Riccati norms."""
        parts = self.unpack(z)
        out = {k: float(v) for k, v in parts["params"].items()}
        X = parts["X"]
        out["dist_from"] = float(np.linalg.norm(X[0] - parts["x_from"]))
        out["dist_to"] = float(np.linalg.norm(X[-1] - parts["x_to"]))
        rm = float(np.max(np.abs(parts["R_minus"]))) if parts["R_minus"].size else 0.0
        rp = float(np.max(np.abs(parts["R_plus"]))) if parts["R_plus"].size else 0.0
        out["riccati_norm"] = max(rm, rp)
        return out

    # ------------------------------------------------------------------ starting data
    def initial_vector(self, guess: Any) -> tuple[HeteroclinicProblem, FloatArray]:
        """Interpolate ``guess`` onto the mesh; resolve the phase reference / pinned value.

        Parameters
        ----------
        guess : ConnectionResult, (t, x) pair, object with ``t`` and ``x`` or ``y``, or ndarray
            ``t`` (K,) strictly increasing, ``x`` (K, n) or (n, K) (:func:`_states_layout`:
            the axis of length K is time; a square ambiguous array raises), in the
            time of the system. A
            guess whose time span ``T_g = t[-1] - t[0]`` equals ``T`` is shifted onto
            ``[0, T]``. One whose span differs is *not* stretched (that would rescale
            time, slowing or speeding up the orbit by ``T / T_g``, and a stretched orbit
            is far from any solution) but centred:
            ``x(t) = x_g(t[0] + clip(t - (T - T_g) / 2, 0, T_g))``, i.e. held at its end
            values (next to the saddles) on a longer interval, or cut symmetrically on
            a shorter one, as :func:`~continuation.bvp.solve.check_convergence` does.
            So an unstable-manifold trajectory cut at its closest approach to the
            target can be given as it is, for any ``T``. A bare array has no time axis
            and is taken as equally spaced on ``[0, T]``. A :class:`ConnectionResult`
            also gives the unknown parameters and the saddles.

        Returns
        -------
        problem : HeteroclinicProblem
            This problem with ``reference`` (integral phase) or the pin value set.
        z0 : ndarray, shape (N_z,)
        """
        from .result import ConnectionResult

        n = self.n_states
        mesh = self.mesh
        x_from = x_to = None
        unknown_values = None
        if isinstance(guess, ConnectionResult):
            if guess.x.shape[1] != n:
                raise ValueError(f"`guess` has {guess.x.shape[1]} states, expected {n}")
            T_g = float(guess.mesh.T)
            X0 = guess.mesh.interpolate(guess.x, _guess_times(T_g, mesh) / T_g)
            x_from, x_to = guess.x_from, guess.x_to
            unknown_values = [guess.params[u] for u in self.free]
        else:
            t, x = _as_trajectory(guess, n)
            if isinstance(guess, np.ndarray):  # no time axis: equally spaced on [0, T]
                t = t * mesh.T
            s_g = t[0] + _guess_times(float(t[-1] - t[0]), mesh)
            X0 = np.column_stack([np.interp(s_g, t, x[:, i]) for i in range(n)])
        prob = self
        if self.layout.pin is None:
            if self.reference is None:
                prob = _with_phase_data(self, reference=X0)
        elif self.phase.value is None:  # type: ignore[union-attr]
            i_state, i_node = self.layout.pin
            value = float(X0[i_node * (mesh.degree + 1), i_state])
            prob = _with_phase_data(self, phase=dataclasses.replace(self.phase, value=value))  # type: ignore[type-var]
        z0 = prob.pack(X0, x_from=x_from, x_to=x_to, unknown_values=unknown_values)
        return prob, z0

    def rebased(
        self, z: FloatArray, p: float | None = None
    ) -> tuple[HeteroclinicProblem, FloatArray]:
        """Refresh the Schur bases and the phase reference at the solution ``z``.

        Returns a new problem whose ``params`` hold the solved unknown parameters (and
        ``p`` for ``vary``), whose saddle guesses are the solved equilibria, whose bases
        are the Schur bases at those equilibria (so ``R = 0``) and whose integral-phase
        reference is the solution itself; and the matching ``z``.
        """
        parts = self.unpack(z)
        pvec = self.param_vector(z, p)
        params = self.params.with_vector(pvec)
        A_m = self.system.jacobian(parts["x_from"], pvec)
        A_p = self.system.jacobian(parts["x_to"], pvec)
        Qm, _ = _schur_basis(A_m, "stable")
        Qp, _ = _schur_basis(A_p, "unstable")
        changes: dict[str, Any] = {
            "params": params,
            "saddle_from": parts["x_from"],
            "bases": (Qm, Qp),
        }
        if self.layout.separate_to:
            changes["saddle_to"] = parts["x_to"]
        if self.layout.pin is None:
            changes["reference"] = parts["X"]
        new = _replace_fast(self, **changes)
        z_new = new.pack(parts["X"], parts["x_from"], parts["x_to"], list(parts["params"].values()))
        return new, z_new

    def _result_parts(
        self, z: FloatArray, p: float | None
    ) -> tuple[type[ConnectionResult], float | None, dict[str, Any]]:
        """A :class:`ConnectionResult` at ``vary = p`` (:meth:`ToResult.to_result`)."""
        parts = self.unpack(z)
        params = self.params.with_vector(self.param_vector(z, p))
        return ConnectionResult, p, {"params": params, "x_from": parts["x_from"],
                                     "x_to": parts["x_to"]}  # fmt: skip


def _as_params(system: Any, params: Any) -> Params:
    """``params`` as :class:`Params` of ``system`` (:func:`continuation.system.as_params`)."""
    params = as_params(system, params)
    if params.names != system.param_names:
        raise ValueError(
            f"`params` names {params.names} do not match the system's {system.param_names}"
        )
    return params


def _solved_names(system: Any, free: Any) -> tuple[str, ...]:
    """The names of the solved parameters (``free``) as a tuple, checked."""
    unk = (free,) if isinstance(free, str) else tuple(str(u) for u in free)
    for u in unk:
        if u not in system.param_names:
            raise ValueError(
                f"`free` names unknown parameter {u!r}; valid names are {system.param_names}"
            )
    if len(set(unk)) != len(unk):
        raise ValueError(f"`free` must be unique, got {unk}")
    return unk


def _checked_orbit_fields(problem: Any) -> tuple[Any, Params, tuple[str, ...]]:
    """The checks a connection and a landing share: ``(system, params, free)``.

    ``system`` must have a CasADi trace; ``params`` (as :class:`Params`) and ``free`` (as
    a tuple of names) are set on the (frozen) ``problem``.
    """
    system = problem.system
    if not hasattr(system, "casadi_functions") or not getattr(system, "has_casadi", False):
        raise ValueError(
            "`system` must be a continuation.System with a CasADi trace "
            "(write rhs(x, p, ops) with ops functions)"
        )
    params = _as_params(system, problem.params)
    object.__setattr__(problem, "params", params)
    unk = _solved_names(system, problem.free)
    object.__setattr__(problem, "free", unk)
    return system, params, unk


def _set_mesh(problem: Any, missing: str) -> CollocationMesh:
    """:func:`_resolve_mesh` of ``problem.mesh``/``problem.T``, set on ``problem`` (both)."""
    mesh = _resolve_mesh(problem.mesh, problem.T, missing)
    object.__setattr__(problem, "mesh", mesh)
    object.__setattr__(problem, "T", mesh.T)
    return mesh


def _resolve_mesh(mesh: Any, T: float | None, missing: str) -> CollocationMesh:
    """The mesh of a problem given ``mesh`` or ``T`` (then the default intervals/degree)."""
    if mesh is None:
        if T is None:
            raise ValueError(missing)
        mesh = CollocationMesh(DEFAULT_N_INTERVALS, DEFAULT_DEGREE, T)
    if not isinstance(mesh, CollocationMesh):
        raise ValueError(f"`mesh` must be a CollocationMesh, got {type(mesh).__name__}")
    if T is not None and abs(float(T) - mesh.T) > 1e-12 * mesh.T:
        raise ValueError(f"`T` = {T!r} disagrees with `mesh.T` = {mesh.T!r}")
    return mesh


def _shift_vector(system: Any, shift: Any) -> FloatArray:
    """The end shift ``x_+ - x_e`` as a vector: whole periods of periodic states only."""
    n = system.n_states
    if isinstance(shift, Mapping):
        vec = np.zeros(n)
        for k, v in shift.items():
            vec[system.state_index(k)] = float(v)
    elif np.ndim(shift) == 0:
        if float(shift) != 0.0:
            raise ValueError(
                f"a scalar `shift` must be 0 (a homoclinic orbit), got {shift!r}; give a "
                "mapping such as {'theta': 2 * pi} for a shift by periods"
            )
        vec = np.zeros(n)
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
                f"`shift` is nonzero on state {system.state_names[i]!r}, which is not "
                "periodic (declare it with System(..., periodic={...}))"
            )
        ratio = vec[i] / period[i]
        if abs(ratio - round(ratio)) > 1e-9 * max(1.0, abs(ratio)):
            raise ValueError(
                f"`shift` of state {system.state_names[i]!r} is {vec[i]}, not a whole "
                f"multiple of its period {period[i]}"
            )
    # a zero shift is a homoclinic orbit, x_+ = x_-
    vec.setflags(write=False)
    return vec


def _guess_times(T_g: float, mesh: CollocationMesh) -> FloatArray:
    """Times in ``[0, T_g]`` of a guess at the mesh's points (see ``initial_vector``).

    ``tau * T_g`` when ``T_g == T`` (to 1e-9 relative); otherwise the guess is centred
    on ``[0, T]`` at its own time scale and held at its end values outside.
    """
    if abs(T_g - mesh.T) <= 1e-9 * max(abs(mesh.T), 1.0):
        return np.clip(mesh.tau * T_g, 0.0, T_g)
    log.info("guess spans %.6g, mesh T = %.6g: guess centred, not stretched", T_g, mesh.T)
    return np.clip(mesh.tau * mesh.T - 0.5 * (mesh.T - T_g), 0.0, T_g)


def _mesh_changes(prob: HeteroclinicProblem, changes: dict[str, Any]) -> dict[str, Any]:
    """Keep ``mesh`` and ``T`` consistent in ``replace``."""
    changes = dict(changes)
    if "mesh" in changes and "T" not in changes:
        changes["T"] = None
    elif "T" in changes and "mesh" not in changes and changes["T"] is not None:
        changes["mesh"] = prob.mesh.with_T(float(changes["T"]))
    return changes


def _csc_column(A: sp.csc_matrix, j: int) -> FloatArray:
    """Column ``j`` of a CSC matrix as a dense vector, shape ``(A.shape[0],)``."""
    out = np.zeros(A.shape[0])
    a, b = A.indptr[j], A.indptr[j + 1]
    out[A.indices[a:b]] = A.data[a:b]
    return out


def _with_phase_data(prob: HeteroclinicProblem, **changes: Any) -> HeteroclinicProblem:
    """A copy with a new ``reference`` or pinned ``phase`` value only, not re-validated.

    Neither enters the checks of ``__post_init__`` (saddles, spectra, counts, layout),
    which are not repeated; the reference's shape is checked, as there. The compiled
    functions are shared (same layout).
    """
    if not set(changes) <= {"reference", "phase"}:
        raise ValueError(f"only `reference` and `phase` may change here, got {sorted(changes)}")
    new = copy.copy(prob)
    if "phase" in changes:
        phase = changes["phase"]
        if not (isinstance(phase, PinPhase) and isinstance(prob.phase, PinPhase)
                and phase.state == prob.phase.state and phase.at == prob.phase.at):  # fmt: skip
            return prob.replace(**changes)  # a new pin moves the pinned node: re-validate
        object.__setattr__(new, "phase", phase)
    if "reference" in changes:
        ref = changes["reference"]
        if ref is not None:
            ref = np.array(ref, dtype=float)
            if ref.shape != (prob.mesh.n_points, prob.n_states):
                raise ValueError(
                    f"`reference` must have shape ({prob.mesh.n_points}, {prob.n_states}), "
                    f"got {ref.shape}"
                )
            ref.setflags(write=False)
        object.__setattr__(new, "reference", ref)
    object.__setattr__(new, "_fns", prob._fns if prob._fns else [])
    return new


def _replace_fast(prob: HeteroclinicProblem, **changes: Any) -> HeteroclinicProblem:
    """``dataclasses.replace`` that keeps the compiled functions of an unchanged layout."""
    new = dataclasses.replace(prob, **_mesh_changes(prob, changes))
    if new.layout == prob.layout and prob._fns:
        new._fns.append(prob._fns[0])
    return new


def _states_layout(x: FloatArray, K: int | None, n: int) -> FloatArray:
    """``x`` as (K, n): accept (K, n) or SciPy's (n, K); refuse an ambiguous square array.

    Rule: with times (``K`` known) the axis of length ``K`` is time; without, the axis
    of length ``n`` is the state. When both axes fit (``K == n``, or a bare (n, n)
    array) the layout cannot be told and a ValueError asks for more samples.
    """
    if x.ndim != 2:
        raise ValueError(f"`guess` states must be a 2-D array (K, n) or (n, K), got {x.shape}")
    if K is None:
        fits_kn, fits_nk = x.shape[1] == n, x.shape[0] == n
    else:
        fits_kn = x.shape == (K, n)
        fits_nk = x.shape == (n, K)
    if fits_kn and fits_nk:
        raise ValueError(
            f"`guess` of shape {x.shape} is ambiguous: both (K, n) and (n, K) fit with n = {n}; "
            "give more (or fewer) than n time samples"
        )
    if fits_nk:
        return np.ascontiguousarray(x.T)
    return x


def _as_trajectory(guess: Any, n: int) -> tuple[FloatArray, FloatArray]:
    """Normalise a guess to ``(t (K,), x (K, n))``; raise ValueError naming ``guess``."""
    if isinstance(guess, np.ndarray) and guess.ndim == 2:
        x = _states_layout(np.asarray(guess, dtype=float), None, n)
        t = np.linspace(0.0, 1.0, x.shape[0])
    elif hasattr(guess, "t") and (hasattr(guess, "x") or hasattr(guess, "y")):
        # ``y``: a SciPy solve_ivp / solve_bvp result, states as (n, K)
        t = np.asarray(guess.t, dtype=float).reshape(-1)
        xs = guess.x if hasattr(guess, "x") else guess.y
        x = _states_layout(np.asarray(xs, dtype=float), t.size, n)
    elif isinstance(guess, (tuple, list)) and len(guess) == 2:
        t = np.asarray(guess[0], dtype=float).reshape(-1)
        x = _states_layout(np.asarray(guess[1], dtype=float), t.size, n)
    else:
        raise ValueError(
            "`guess` must be a ConnectionResult, a (t, x) pair, an object with `t` and `x`, "
            f"or an (K, n) / (n, K) array; got {type(guess).__name__}"
        )
    if x.ndim != 2 or x.shape != (t.size, n):
        raise ValueError(
            f"`guess` states must have shape (len(t), n) = ({t.size}, {n}), got {x.shape}"
        )
    if t.size < 2:
        raise ValueError("`guess` needs at least two time points")
    if np.any(np.diff(t) <= 0):
        raise ValueError("`guess` times must be strictly increasing")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(x))):
        raise ValueError("`guess` contains NaN or inf")
    return t, x


__all__ = ["HeteroclinicProblem", "PinPhase"]
