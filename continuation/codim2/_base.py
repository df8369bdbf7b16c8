r"""Shared machinery of the augmented two-parameter problems.

A codim-1 bifurcation curve of :math:`\dot x = f(x, p)` is continued in two
parameters: ``free2`` is the continuation parameter ``p`` of the
:class:`~continuation.problem.ContinuationProblem`, ``free1`` is solved for and
sits in the unknown vector ``z = (x, p1, extra...)``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar, Self

import numpy as np

from ..newton import NewtonResult, newton
from ..params import Params
from ..settings import NewtonSettings
from ..system import System, as_params
from ..typing import ComplexArray, FloatArray
from ._build import AugmentedFunctions, Recipe, augmented_functions, param_vector


@dataclass(frozen=True, eq=False)
class AugmentedProblem:
    """Base of :class:`FoldProblem` and :class:`HopfProblem` (not used directly).

    Parameters
    ----------
    system : System
        The dynamical system ``x' = f(x, p)``.
    params : Params
        Values of all parameters; the ``free1`` and ``free2`` entries are
        overwritten by the unknown ``p1 = z[n]`` and the continuation parameter.
    free1 : str
        The parameter solved for along the curve (the first parameter, the free
        parameter of the one-parameter branch the curve starts from).
    free2 : str
        The continuation parameter of the curve (``problem.free``).
    sparse : bool or None
        Return sparse ``dG/dz`` (``None``: automatically for ``n >= 100``).
    z0 : ndarray, shape (N,), optional
        A point on the curve (set by ``from_point`` / ``from_state``).
    p0 : float, optional
        The value of ``free2`` at ``z0``.
    """

    system: System
    params: Params
    free1: str
    free2: str
    sparse: bool | None = None
    z0: FloatArray | None = field(default=None, repr=False)
    p0: float | None = None
    _i1: int = field(init=False, repr=False)
    _i2: int = field(init=False, repr=False)

    kind: ClassVar[str] = ""
    n_extra: ClassVar[int] = 0
    extra_names: ClassVar[tuple[str, ...]] = ()
    _recipe: ClassVar[Recipe]

    def __post_init__(self) -> None:
        system = self.system
        for attr in ("state_names", "param_names", "f", "jacobian"):
            if not hasattr(system, attr):
                raise ValueError(f"`system` must be a System (missing {attr!r})")
        object.__setattr__(self, "params", as_params(system, self.params))
        if self.params.names != tuple(system.param_names):
            raise ValueError(
                f"`params` names {self.params.names} do not match the system's "
                f"{tuple(system.param_names)}"
            )
        names = tuple(system.param_names)
        for arg in ("free1", "free2"):
            val = getattr(self, arg)
            if val not in names:
                raise ValueError(f"`{arg}` must be one of {names}, got {val!r}")
        if self.free1 == self.free2:
            raise ValueError(f"`free2` must differ from `free1`, both are {self.free1!r}")
        if self.sparse is None:
            object.__setattr__(self, "sparse", len(system.state_names) >= 100)
        if self.z0 is not None:
            z0 = np.array(self.z0, dtype=float).reshape(-1)
            if z0.shape != (self.n_unknowns,) or not np.all(np.isfinite(z0)):
                raise ValueError(
                    f"`z0` must be a finite vector of shape ({self.n_unknowns},), got {z0.shape}"
                )
            z0.setflags(write=False)
            object.__setattr__(self, "z0", z0)
        if self.p0 is not None:
            if not np.isfinite(self.p0):
                raise ValueError(f"`p0` must be finite, got {self.p0}")
            object.__setattr__(self, "p0", float(self.p0))
        object.__setattr__(self, "_i1", names.index(self.free1))
        object.__setattr__(self, "_i2", names.index(self.free2))
        fns = augmented_functions(
            system, self.kind, type(self)._recipe, self.n_unknowns, self._i1, self._i2
        )
        object.__setattr__(self, "_fns", fns)
        object.__setattr__(self, "_memo_cache", {})

    # ----------------------------------------------------------------- layout
    @property
    def free(self) -> str:
        """The continuation parameter, ``free2``."""
        return self.free2

    @property
    def n(self) -> int:
        """Number of states ``n``."""
        return len(self.system.state_names)

    @property
    def n_unknowns(self) -> int:
        """``N = 2 n + 1 + n_extra`` (state, first parameter, extras, vector)."""
        return 2 * self.n + 1 + self.n_extra

    @property
    def functions(self) -> AugmentedFunctions:
        """The compiled residual and derivatives (exact when CasADi-traced)."""
        return self._fns  # type: ignore[attr-defined,no-any-return]

    def state(self, z: FloatArray) -> FloatArray:
        """The equilibrium ``x = z[:n]``, shape ``(n,)``."""
        return np.asarray(z, dtype=float)[: self.n]

    def p1(self, z: FloatArray) -> float:
        """The first parameter ``z[n]``."""
        return float(np.asarray(z, dtype=float)[self.n])

    def vector(self, z: FloatArray) -> FloatArray:
        """The critical vector ``v`` (last ``n`` entries of ``z``), shape ``(n,)``."""
        return np.asarray(z, dtype=float)[self.n + 1 + self.n_extra :]

    def param_vector(self, z: FloatArray, p: float) -> FloatArray:
        """Full parameter vector at ``(z, p)``, shape ``(m,)``."""
        return param_vector(self.params.values, self.p1(z), float(p), self._i1, self._i2)

    def params_at(self, z: FloatArray, p: float) -> Params:
        """Named parameters at ``(z, p)``."""
        return self.params.with_vector(self.param_vector(z, p))

    def state_jacobian(self, z: FloatArray, p: float) -> FloatArray:
        """``df/dx`` at the curve point, shape ``(n, n)``."""
        return np.asarray(self.system.jacobian(self.state(z), self.param_vector(z, p)))

    def _c(self) -> FloatArray:
        return np.zeros(self.n + 1)

    def _memo(self, tag: str, z: FloatArray, p: float, fn: Any) -> Any:
        """``fn()`` cached on ``(tag, z, p)``.

        The driver evaluates several test functions at the same point.
        """
        key = (tag, np.asarray(z, dtype=float).tobytes(), float(p))
        cache: dict[Any, Any] = self._memo_cache  # type: ignore[attr-defined]
        if key not in cache:
            if len(cache) > 32:
                cache.clear()
            cache[key] = fn()
        return cache[key]

    # ----------------------------------------------------------------- protocol
    def residual(self, z: FloatArray, p: float) -> FloatArray:
        """``G(z, p)``, shape ``(N,)``."""
        return self.functions.G(z, float(p), self.params.values, self._c())

    def jacobian(self, z: FloatArray, p: float) -> Any:
        """``dG/dz``, shape ``(N, N)``: dense, or SciPy CSC when ``self.sparse``."""
        if self.sparse:
            return self.functions.dGdz_sparse(z, float(p), self.params.values, self._c())
        return self.functions.dGdz(z, float(p), self.params.values, self._c())

    def dp(self, z: FloatArray, p: float) -> FloatArray:
        """``dG/dp`` with respect to ``free2``, shape ``(N,)``."""
        return self.functions.dGdp(z, float(p), self.params.values, self._c())

    # optional extensions read by the continuation driver
    #: the stability eigenvalues are those of ``df/dx``, not of ``dG/dz``
    jacobian_is_stability: ClassVar[bool] = False

    def linearize(self, z: FloatArray, p: float) -> tuple[FloatArray, Any, FloatArray]:
        """``(G, dG/dz, dG/dp)`` at ``(z, p)`` in one evaluation."""
        return self.functions.linearize(
            z, float(p), self.params.values, self._c(), bool(self.sparse)
        )

    @property
    def state_names(self) -> tuple[str, ...]:
        """Names of the entries of ``z``: states, ``free1``, extras, ``v_<state>``."""
        states = tuple(self.system.state_names)
        return (*states, self.free1, *self.extra_names, *(f"v_{s}" for s in states))

    def difference(self, z1: FloatArray, z2: FloatArray) -> FloatArray:
        """``z1 - z2`` with periodic states reduced modulo their period."""
        d = np.asarray(z1, dtype=float) - np.asarray(z2, dtype=float)
        if hasattr(self.system, "difference"):
            d[..., : self.n] = self.system.difference(
                np.asarray(z1, dtype=float)[..., : self.n],
                np.asarray(z2, dtype=float)[..., : self.n],
            )
        return d

    def stability(self, z: FloatArray, p: float) -> ComplexArray:
        """Eigenvalues of ``df/dx`` at the curve point, shape ``(n,)``."""
        return np.asarray(np.linalg.eigvals(self.state_jacobian(z, p)), dtype=complex)

    def record(self, z: FloatArray, p: float) -> Mapping[str, float]:
        """``{free1: p1}``; subclasses add more."""
        return {self.free1: self.p1(z)}

    # ----------------------------------------------------------------- starting
    @classmethod
    def from_state(
        cls,
        system: System,
        params: Params | Mapping[str, float],
        free1: str,
        free2: str,
        x: Any,
        *,
        refine: bool = True,
        newton_settings: NewtonSettings | None = None,
        sparse: bool | None = None,
        **start: Any,
    ) -> Self:
        """A problem started from a state ``x`` at (or near) its codim-1 point.

        Parameters
        ----------
        system : System
        params : Params or mapping
            Parameter values; ``params[free1]`` is the initial guess of the first
            parameter and ``params[free2]`` the starting continuation parameter.
        free1, free2 : str
            First (solved-for) and second (continuation) parameter names.
        x : array_like, shape (n,)
            The state at the point, or a guess of it.
        refine : bool
            Solve the augmented system at fixed ``free2`` by Newton's method
            (raises :class:`~continuation.errors.ConvergenceError` on failure).
        newton_settings : NewtonSettings, optional
        sparse : bool or None
        **start
            Options of the kind's start (:meth:`_start`): ``omega`` of a
            :class:`HopfProblem` (expected frequency: selects the eigenvalue nearest
            ``i omega``; default the complex eigenvalue with ``Im > 0`` and the
            smallest ``|Re|``); none for a :class:`FoldProblem`.

        Returns
        -------
        FoldProblem or HopfProblem
            With ``z0 = (x, p1, extra..., v)`` (``v`` from the Jacobian at ``x``: the
            unit null vector of a fold, a vector of the critical plane of a Hopf
            point) and ``p0 = params[free2]``.

        Raises
        ------
        ValueError
            If ``x`` or ``free1``/``free2`` are not valid, or ``J(x)`` has no
            eigenvalue of the kind (a Hopf start: no complex pair).
        """
        params, x, J = start_inputs(system, params, free1, free2, x)
        z0, fields = cls._start(x, params[free1], J, **start)
        p0 = params[free2]
        prob = cls(system, params, free1, free2, sparse=sparse, z0=z0, p0=p0, **fields)
        if refine:
            res = prob.solve(settings=newton_settings, throw=True)
            prob = cls(system, params, free1, free2, sparse=sparse, z0=res.z, p0=p0, **fields)
        return prob

    @classmethod
    def _start(cls, x: FloatArray, p1: float, J: FloatArray) -> tuple[FloatArray, dict[str, Any]]:
        """``z0`` at the state ``x`` (Jacobian ``J``) and the kind's further fields."""
        raise NotImplementedError(f"{cls.__name__} does not implement _start")  # pragma: no cover

    @classmethod
    def _point_start(cls, sp: Any) -> dict[str, Any]:
        """The options of :meth:`_start` taken from a located special point (none)."""
        return {}

    @classmethod
    def from_point(
        cls,
        branch: Any,
        sp: Any,
        free2: str,
        *,
        refine: bool = True,
        newton_settings: NewtonSettings | None = None,
        sparse: bool | None = None,
    ) -> AugmentedProblem:
        """Start the curve at a located special point of a one-parameter branch.

        Parameters
        ----------
        branch : Branch
            A branch of equilibria (its ``problem`` an ``EquilibriumProblem``).
        sp : SpecialPoint
            A located point of ``branch`` of this problem's kind (``"fold"`` for
            :class:`FoldProblem`, ``"hopf"`` for :class:`HopfProblem`).
        free2 : str
            The second parameter, continued along the curve; the branch's free
            parameter becomes ``free1``.
        refine : bool
            Newton-correct the augmented system at the start (raises
            :class:`~continuation.errors.ConvergenceError` on failure).
        newton_settings : NewtonSettings, optional
        sparse : bool or None

        Returns
        -------
        FoldProblem or HopfProblem
            With ``z0`` and ``p0 = params[free2]`` set.

        Raises
        ------
        ValueError
            If ``branch`` has no equilibrium problem, ``sp`` is not a located point
            of this kind on ``branch``, or ``free2`` is unknown or equals the
            branch's free parameter.
        """
        system, params, free1 = _check_start(branch, sp, free2, cls.kind)
        params = params.replace(**{free1: float(sp.p)})
        x = np.asarray(sp.x, dtype=float)
        return cls.from_state(
            system,
            params,
            free1,
            free2,
            x,
            refine=refine,
            newton_settings=newton_settings,
            sparse=sparse,
            **cls._point_start(sp),
        )

    # ----------------------------------------------------------------- solving
    def solve(
        self,
        z_guess: FloatArray | None = None,
        p: float | None = None,
        settings: NewtonSettings | None = None,
        *,
        throw: bool = True,
    ) -> NewtonResult:
        """Newton solve of ``G(z, p) = 0`` at fixed ``p`` from a nearby guess.

        Parameters
        ----------
        z_guess : ndarray, shape (N,), optional
            Starting guess (default ``self.z0``).
        p : float, optional
            Value of ``free2`` (default ``self.p0``).
        settings : NewtonSettings, optional
            Tolerances.
        throw : bool
            Raise :class:`~continuation.errors.ConvergenceError` on failure
            (default, as for every one-shot solve).

        Returns
        -------
        NewtonResult
        """
        z = self.z0 if z_guess is None else z_guess
        pv = self.p0 if p is None else p
        if z is None:
            raise ValueError("`z_guess` is required when the problem has no `z0`")
        if pv is None:
            raise ValueError("`p` is required when the problem has no `p0`")
        z = np.asarray(z, dtype=float)
        if z.shape != (self.n_unknowns,):
            raise ValueError(f"`z_guess` must have shape ({self.n_unknowns},), got {z.shape}")
        return newton(
            lambda w: self.residual(w, pv),
            lambda w: self.jacobian(w, pv),
            z,
            settings,
            throw=throw,
        )


def start_inputs(
    system: System, params: Params | Mapping[str, float], free1: str, free2: str, x: Any
) -> tuple[Params, FloatArray, FloatArray]:
    r"""The checked inputs of ``from_state``: parameters, state and the Jacobian there.

    Returns
    -------
    params : Params
    x : ndarray, shape (n,)
    J : ndarray, shape (n, n)
        :math:`\partial f/\partial x` at ``(x, params)``.

    Raises
    ------
    ValueError
        A state of the wrong shape, or ``free1``/``free2`` not a parameter name.
    """
    params = as_params(system, params)
    x = system.check_state(x, "x") if hasattr(system, "check_state") else np.asarray(x)
    for arg, val in (("free1", free1), ("free2", free2)):
        if val not in params.names:
            raise ValueError(f"`{arg}` must be one of {params.names}, got {val!r}")
    return params, x, np.asarray(system.jacobian(x, params.values), dtype=float)


def _check_start(branch: Any, sp: Any, free2: str, kind: str) -> tuple[Any, Params, str]:
    """Validate ``(branch, sp, free2)``; return ``(system, params, free1)``."""
    problem = getattr(branch, "problem", None)
    if problem is None or not all(hasattr(problem, a) for a in ("system", "params", "free")):
        raise ValueError(
            "`branch` must be a branch of equilibria computed in this session "
            "(its `problem` must be an EquilibriumProblem with `system`, `params`, `free`)"
        )
    if not any(s is sp for s in getattr(branch, "special_points", ())):
        raise ValueError("`sp` is not one of `branch.special_points`")
    sp_kind = str(getattr(sp.kind, "value", sp.kind))
    if sp_kind != kind:
        raise ValueError(f"`sp` must be a {kind} point, got a {sp_kind!r} point")
    if not sp.located:
        raise ValueError(
            f"`sp` ({sp_kind} between p={sp.bracket[0]:.6g} and {sp.bracket[1]:.6g}) was "
            "not located; locate it first (e.g. tighter `detect.tol`, smaller `ds`)"
        )
    system = problem.system
    names = tuple(system.param_names)
    if free2 not in names:
        raise ValueError(f"`free2` must be one of {names}, got {free2!r}")
    if free2 == problem.free:
        raise ValueError(f"`free2` must differ from the branch's free parameter {problem.free!r}")
    if np.asarray(sp.x).shape != (len(system.state_names),):
        raise ValueError(
            f"`sp.x` must be a state of shape ({len(system.state_names)},), "
            f"got {np.asarray(sp.x).shape}"
        )
    return system, as_params(system, problem.params), problem.free


def null_vector(J: FloatArray) -> FloatArray:
    """Unit right singular vector of the smallest singular value of ``J``; shape ``(n,)``.

    The sign is fixed so that the largest-magnitude entry is positive.
    """
    _, _, vt = np.linalg.svd(np.asarray(J, dtype=float))
    v = vt[-1]
    k = int(np.argmax(np.abs(v)))
    return v if v[k] >= 0 else -v


def adjugate(J: FloatArray) -> FloatArray:
    r"""Adjugate (classical adjoint) of a square matrix via the SVD, shape ``(n, n)``.

    With :math:`J = U S V^T`, :math:`\operatorname{adj}(J) = \det(U)\det(V)\,
    V \operatorname{diag}(\prod_{j \ne i} s_j)\, U^T`. Well defined and smooth
    for singular ``J``: at a simple zero eigenvalue it is the rank-one matrix
    :math:`(\prod_{\lambda \ne 0} \lambda)\, v w^T / (w^T v)`.
    """
    J = np.asarray(J, dtype=float)
    n = J.shape[0]
    if n == 1:
        return np.ones((1, 1))
    u, s, vt = np.linalg.svd(J)
    prods = np.array([np.prod(np.delete(s, i)) for i in range(n)])
    sign = np.linalg.det(u) * np.linalg.det(vt)
    return np.asarray(sign * (vt.T * prods) @ u.T, dtype=float)


def scaled_adjugate(J: FloatArray) -> FloatArray:
    r"""``adj(J)`` divided by the product of all singular values but the two smallest.

    With :math:`J = U S V^T` (``s_1 >= ... >= s_n``), ``adj(J) = det(U) det(V) V D U^T``
    with ``D_ii = prod_{j != i} s_j``. Dividing by the positive, continuous scale
    :math:`\prod_{j \le n-2} s_j = |\det J| / (s_{n-1} s_n)` gives
    ``D_ii = s_{n-1} s_n / s_i`` (``i <= n-2``), ``D_{n-1} = s_n``, ``D_n = s_{n-1}``:
    the same zeros and signs as the adjugate (the codim-2 test functions built from it
    keep their zeros and sign changes), but no overflow or underflow for large ``n``,
    where the plain adjugate is a product of ``n - 1`` singular values. Equal to
    :func:`adjugate` for ``n <= 2``.
    """
    J = np.asarray(J, dtype=float)
    n = J.shape[0]
    if n <= 2:
        return adjugate(J)
    u, s, vt = np.linalg.svd(J)
    d = np.empty(n)
    d[: n - 2] = s[n - 2] * s[n - 1] / np.maximum(s[: n - 2], np.finfo(float).tiny)
    d[n - 2], d[n - 1] = s[n - 1], s[n - 2]
    sign = np.linalg.det(u) * np.linalg.det(vt)
    return np.asarray(sign * (vt.T * d) @ u.T, dtype=float)


#: bound on the log-magnitude of the factors of a test-function product other than
#: the smallest one (see :func:`signed_product`)
LOG_CLIP = 300.0


def signed_product(factors: Any) -> float:
    r"""``prod(factors)`` (real: the set is closed under conjugation), overflow-free.

    Computed as ``sign * |f_j| * exp(clip(sum_{k != j} log|f_k|, -LOG_CLIP, LOG_CLIP))``
    with ``f_j`` the factor of smallest modulus and the sign from the summed
    arguments. Where the clip is inactive this is the product itself; where it is
    active (products of thousands of eigenvalue sums for a discretised PDE, which
    overflow to inf/NaN in plain floating point) the value keeps the product's sign
    and is proportional to the smallest factor, so a factor crossing zero still gives
    a simple, locatable zero, and no sign change appears anywhere else.

    Parameters
    ----------
    factors : array_like, shape (m,) complex
        Closed under complex conjugation (so the product is real).

    Returns
    -------
    float
        1.0 for an empty set.
    """
    f = np.asarray(factors, dtype=complex).reshape(-1)
    if f.size == 0:
        return 1.0
    mag = np.abs(f)
    j = int(np.argmin(mag))
    if mag[j] == 0.0:
        return 0.0
    if not np.all(np.isfinite(mag)):
        return float("nan")
    logs = np.log(mag)
    rest = float(np.sum(logs) - logs[j])
    sign = 1.0 if math.cos(float(np.sum(np.angle(f)))) >= 0.0 else -1.0
    return sign * float(mag[j]) * math.exp(min(max(rest, -LOG_CLIP), LOG_CLIP))


__all__ = [
    "LOG_CLIP",
    "AugmentedProblem",
    "adjugate",
    "null_vector",
    "scaled_adjugate",
    "signed_product",
]
