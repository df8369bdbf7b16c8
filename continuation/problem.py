r"""Continuation problems :math:`G(z, p) = 0` in one free scalar parameter ``p``.

Every problem the engine continues (equilibria, fold and Hopf curves, connecting
orbits) implements :class:`ContinuationProblem`, so one pseudo-arclength driver
serves all of them.

The contract has two parts:

* :class:`ContinuationProblem`, the five methods and two attributes every problem has
  (checked by ``isinstance``);
* :class:`ProblemHooks`, the *optional* attributes the driver uses when a problem has
  them. Two kinds:

  - fast paths (``linearize``, ``linearizer``, ``bordered_evaluator``,
    ``step_kernel``) and properties (``jacobian_is_stability``, ``exact_jacobian``,
    ``sparse``, ``difference``, ``state_names``): they never change a result beyond
    round-off, only what it costs (or how rows are compared and labelled);
  - the life cycle: ``accept(z, p)`` after every accepted row (a problem with a
    moving reference, e.g. the phase condition of periodic orbits, updates it
    there) and ``relabel(specials)`` once on the finished branch's special points
    (e.g. folds of cycles named ``LPC1``, Floquet zeros turned into the ``pd``/``ns``
    kinds).

  The engine reads them only through the accessor functions at the end of this
  module (:func:`linearize`, :func:`linearizer`, :func:`bordered_evaluator`,
  :func:`step_kernel`, :func:`jacobian_is_stability`, :func:`exact_jacobian`,
  :func:`is_sparse`, :func:`difference`, :func:`accept_hook`, :func:`relabel`,
  :func:`record_function`, :func:`state_names`, :func:`param_values`): this module is
  the one place where a hook is looked up.

How a run starts is not a hook of the problem but a keyword of
:func:`~continuation.driver.continue_branch`, since it belongs to one run:
``start_fixed`` (the unknown held in the start correction instead of ``p``) and
``start_orient`` (the direction the first tangent points along, instead of the sign
of ``ds``). :func:`check_problem` (:mod:`continuation.check`) tests a problem against
this contract: shapes, derivatives against finite differences, hook consistency.

:class:`EquilibriumProblem` (equilibria of a :class:`~continuation.system.System`)
implements every fast path.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import partial
from typing import Any, ClassVar, Protocol, runtime_checkable

import numpy as np
import scipy.sparse as sp

from .branch import SpecialPoint
from .params import Params
from .system import System, as_params
from .typing import ComplexArray, FloatArray


@runtime_checkable
class ContinuationProblem(Protocol):
    r"""A system :math:`G(z, p) = 0`, :math:`G: R^N \times R \to R^N`.

    Attributes
    ----------
    free : str
        Name of the free (continuation) parameter.
    n_unknowns : int
        ``N``, the length of ``z``.
    """

    free: str

    @property
    def n_unknowns(self) -> int:
        """Length ``N`` of the unknown vector ``z``."""
        ...

    def residual(self, z: FloatArray, p: float) -> FloatArray:
        """``G(z, p)``, shape ``(N,)``."""
        ...

    def jacobian(self, z: FloatArray, p: float) -> Any:
        """``dG/dz``, shape ``(N, N)`` (ndarray or SciPy sparse)."""
        ...

    def dp(self, z: FloatArray, p: float) -> FloatArray:
        """``dG/dp``, shape ``(N,)``."""
        ...

    def stability(self, z: FloatArray, p: float) -> ComplexArray | None:
        """Eigenvalues that decide stability at ``(z, p)``, or None if not applicable."""
        ...

    def record(self, z: FloatArray, p: float) -> Mapping[str, float]:
        """Cheap named scalars stored at every branch point (may be empty)."""
        ...


@dataclass(frozen=True)
class EquilibriumProblem:
    r"""Equilibria :math:`f(x, p) = 0` of a :class:`System`, ``free`` parameter varying.

    Parameters
    ----------
    system : System
        The dynamical system.
    params : Params
        Values of all parameters; the ``free`` entry is overwritten by ``p``.
    free : str
        Name of the continuation parameter; must be one of ``system.param_names``.
    sparse : bool or None
        Use sparse Jacobians (``None``: automatically for ``n >= 100``).

    Notes
    -----
    ``z = x`` (shape ``(n,)``), ``G(z, p) = f(x, P(p))`` where ``P(p)`` is
    ``params`` with the free entry replaced by ``p``.
    """

    system: System
    params: Params
    free: str
    sparse: bool | None = None
    _index: int = field(init=False, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "params", as_params(self.system, self.params))
        if self.params.names != self.system.param_names:
            raise ValueError(
                f"`params` names {self.params.names} do not match the system's "
                f"{self.system.param_names}"
            )
        if self.free not in self.system.param_names:
            raise ValueError(f"`free` must be one of {self.system.param_names}, got {self.free!r}")
        object.__setattr__(self, "_index", self.system.param_names.index(self.free))
        if self.sparse is None:
            object.__setattr__(self, "sparse", self.system.n_states >= 100)

    @property
    def n_unknowns(self) -> int:
        """Number of states ``n``."""
        return self.system.n_states

    def param_vector(self, p: float) -> FloatArray:
        """Full parameter vector with the free entry set to ``p``, shape ``(m,)``."""
        v = np.array(self.params.values, dtype=float)
        v[self._index] = p
        return v

    def residual(self, z: FloatArray, p: float) -> FloatArray:
        """``f(x, P(p))``, shape ``(n,)``."""
        return self.system.f(z, self.param_vector(p))

    def jacobian(self, z: FloatArray, p: float) -> Any:
        """``df/dx``, dense ``(n, n)`` or sparse CSC when ``self.sparse``."""
        if self.sparse:
            return self.system.jacobian_sparse(z, self.param_vector(p))
        return self.system.jacobian(z, self.param_vector(p))

    def dp(self, z: FloatArray, p: float) -> FloatArray:
        """``df/dp_free``, shape ``(n,)``."""
        return np.asarray(self.system.dfdp(z, self.param_vector(p)))[:, self._index]

    def stability(self, z: FloatArray, p: float) -> ComplexArray:
        """Eigenvalues of ``df/dx``, shape ``(n,)``."""
        J = self.system.jacobian(z, self.param_vector(p))
        return np.asarray(np.linalg.eigvals(J), dtype=complex)

    def record(self, z: FloatArray, p: float) -> Mapping[str, float]:
        """No extra records for plain equilibria."""
        return {}

    # -- the optional hooks of ProblemHooks (not part of the protocol) --
    #: The stability eigenvalues are those of :meth:`jacobian`, so the driver may
    #: compute them from the Jacobian it already has instead of calling :meth:`stability`.
    jacobian_is_stability: ClassVar[bool] = True

    @property
    def state_names(self) -> tuple[str, ...]:
        """Names of the unknowns (the system's states)."""
        return self.system.state_names

    def linearize(self, z: FloatArray, p: float) -> tuple[Any, FloatArray, FloatArray]:
        """``(G, dG/dz, dG/dp)`` at ``(z, p)`` in one model evaluation.

        Returns
        -------
        G : ndarray, shape (n,)
        Gz : ndarray (n, n), or SciPy CSC matrix when ``self.sparse``
        Gp : ndarray, shape (n,)
        """
        pv = self.param_vector(p)
        lin = getattr(self.system, "linearize", None)
        if lin is None:  # a DynamicalSystem that is not a System
            return self.residual(z, p), self.jacobian(z, p), self.dp(z, p)
        f, J, Jp = lin(z, pv, sparse=bool(self.sparse))
        return f, J, Jp[:, self._index]

    def linearizer(self) -> Any:
        """Fast ``(z, p) -> (G, G_z, G_p)`` evaluator for the continuation corrector.

        Same values as :meth:`linearize`, from a CasADi function specialised to the free
        parameter, with its own buffers (built once per problem and cached on it); None
        when the system has no CasADi trace (then :meth:`linearize` is used).
        """
        fn = self.__dict__.get("_linearizer", False)
        if fn is False:
            make = getattr(self.system, "linearizer", None)
            fn = None
            if make is not None:
                fn = make(self._index, self.params.values, sparse=bool(self.sparse))
            object.__setattr__(self, "_linearizer", fn)
        return fn

    def bordered_evaluator(self) -> Any:
        """Fused evaluator of the bordered Newton system, built once and cached.

        Dense problems with a CasADi trace; None otherwise. See
        :meth:`continuation.system.System.bordered_evaluator`.
        """
        ev = self.__dict__.get("_bordered", False)
        if ev is False:
            make = getattr(self.system, "bordered_evaluator", None)
            ev = None
            if make is not None and not self.sparse:
                ev = make(self._index, self.params.values)
            object.__setattr__(self, "_bordered", ev)
        return ev

    def step_kernel(self) -> Any:
        """The compiled pseudo-arclength step of this problem, built once and cached.

        :class:`continuation._kernel.StepKernel` (dense, CasADi trace, a few states, a short
        tape; :func:`continuation._tape.step_kernel_for`); None otherwise.
        """
        k = self.__dict__.get("_step_kernel", False)
        if k is False:
            from ._tape import step_kernel_for

            k = step_kernel_for(self)
            object.__setattr__(self, "_step_kernel", k)
        return k

    def difference(self, z1: FloatArray, z2: FloatArray) -> FloatArray:
        """``z1 - z2`` with periodic states reduced modulo their period."""
        return self.system.difference(z1, z2)


class BorderedEvaluatorLike(Protocol):
    r"""What the corrector needs of ``problem.bordered_evaluator()`` (the fused path).

    One object per problem, not thread-safe; see
    :class:`continuation.system.BorderedEvaluator`, the implementation.

    Attributes
    ----------
    u : ndarray, shape (N + 1,)
        Input buffer: the point ``(z, p)`` is written here before each call.
    c : ndarray, shape (N + 1,)
        Border row of ``M``.
    h : ndarray, shape (1,)
        Level of the constraint ``c . u = h``.
    r : ndarray, shape (N + 1,)
        Bordered residual ``(G, c . u - h)`` after a call.
    M : ndarray, shape (N + 1, N + 1), Fortran order
        Bordered matrix ``[[G_z, G_p], [c^T]]`` after a call.
    rt : ndarray, shape (N + 1, 2), optional
        ``[r, e_{N+1}]`` in one Fortran array (``r`` a view of its first column), so
        that one ``gesv`` gives the Newton correction and the unnormalised tangent.
    norms : ndarray, shape (5,), or None
        ``(max |r|, r . r, max |u|, max |G|, sum M_ij^2)`` of the last call.
    run : callable, optional
        The compiled call itself (``ev()`` otherwise).
    """

    u: FloatArray
    c: FloatArray
    h: FloatArray
    r: FloatArray
    M: FloatArray
    norms: FloatArray | None

    def __call__(self) -> None:
        """Evaluate ``r`` and ``M`` (and ``norms``) at ``u``."""
        ...

    def lin(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Copies ``(G (N,), G_z (N, N), G_p (N,))`` of the last call."""
        ...


class ProblemHooks(Protocol):
    r"""Optional attributes and fast paths of a :class:`ContinuationProblem`.

    None is required; each is looked up by the accessor of the same name in this
    module, with the fallback given here. Implementing one must not change any result
    beyond round-off.

    Attributes
    ----------
    jacobian_is_stability : bool
        (default False) The stability eigenvalues are those of :meth:`jacobian`
        (equilibria). The driver then computes them from the Jacobian it already has
        (dense LAPACK or sparse shift-invert Arnoldi, :mod:`continuation.row_eigs`)
        instead of calling ``stability``, refuses steps across which two real
        eigenvalues cross zero, and checks sparse saddle indices against the rightmost
        eigenvalues. Not so for augmented (codim-2) problems, whose Jacobian is not the
        linearisation of the flow.
    sparse : bool
        (default False) ``G_z`` is a SciPy sparse matrix: the sparse linear algebra is
        used and BLAS is held to one thread (:mod:`continuation._threads`). A problem
        whose ``jacobian`` returns a sparse matrix must set it.
    state_names : tuple of str
        (default ``system.state_names``, else ``z0, z1, ...``) Names of the unknowns.
    params : Params
        (optional) All parameter values; stored on the branch.
    system : object
        (optional) The underlying system (``state_names``, ``period``).
    exact_jacobian : bool
        (default False) ``G_z`` and ``G_p`` are exact derivatives (automatic
        differentiation, not finite differences): the PALC step then predicts its
        final Newton iterate (Newton converges quadratically next to a regular point).
        A problem claiming it must pass :func:`check_problem` at a tight tolerance.
    """

    jacobian_is_stability: bool
    sparse: bool
    exact_jacobian: bool

    def accept(self, z: FloatArray, p: float) -> None:
        """Called by the driver after every accepted row ``(z, p)``, the start included.

        It runs after the step's special points were located and before the ``progress`` callback.
        For problems with a moving reference (the phase condition of periodic orbits). Must not
        change ``G`` at ``(z, p)`` itself beyond what re-anchoring the reference implies. Fallback:
        nothing.
        """
        ...

    def relabel(self, specials: Sequence[SpecialPoint]) -> tuple[SpecialPoint, ...]:
        """Called by the driver once on the finished branch's special points.

        They come labelled ``F1``, ``H1``, ``BP1``... in branch order; the hook may rename them,
        change their kind, add data or drop spurious ones. Fallback: unchanged.
        """
        ...

    def linearize(self, z: FloatArray, p: float) -> tuple[FloatArray, Any, FloatArray]:
        """``(G (N,), G_z (N, N) dense or sparse, G_p (N,))`` in one evaluation.

        Fallback: ``(residual, jacobian, dp)``, three calls.
        """
        ...

    def linearizer(
        self,
    ) -> Callable[[FloatArray, float], tuple[FloatArray, Any, FloatArray]] | None:
        """A fast evaluator ``(z, p) -> (G, G_z, G_p)`` with the values of :meth:`linearize`.

        Built once; None: use :meth:`linearize`. May be cached in the instance ``__dict__`` as
        ``_linearizer``.
        """
        ...

    def bordered_evaluator(self) -> BorderedEvaluatorLike | None:
        """The fused evaluator of the bordered Newton system (dense problems; built once).

        None: no fused path. May be cached in the instance ``__dict__`` as ``_bordered``. The
        corrector then runs one compiled call and one LAPACK ``gesv`` per Newton iteration
        (:func:`continuation.algorithms.corrector.correct`).
        """
        ...

    def step_kernel(self) -> Any:
        """The compiled pseudo-arclength step (:class:`continuation._kernel.StepKernel`) or None.

        Used by :class:`~continuation.algorithms.palc.PALC` with ``kernel=True``; a step the kernel
        does not accept is redone in Python.
        """
        ...

    def difference(self, z1: FloatArray, z2: FloatArray) -> FloatArray:
        """``z1 - z2``, shape ``(N,)``, with periodic unknowns reduced modulo their period.

        Used by closed-loop detection and distances. Fallback: ``z1 - z2``.
        """
        ...


# ---------------------------------------------------------------------------- accessors
# The engine's only look-ups of the optional hooks of ProblemHooks.
def jacobian_is_stability(problem: Any) -> bool:
    """``problem.jacobian_is_stability`` (default False)."""
    return bool(getattr(problem, "jacobian_is_stability", False))


def exact_jacobian(problem: Any) -> bool:
    """``problem.exact_jacobian`` (default False): ``G_z`` and ``G_p`` are exact.

    Exact: automatic differentiation, not finite differences, so that Newton's method converges
    quadratically next to a regular solution.
    """
    return bool(getattr(problem, "exact_jacobian", False))


def accept_hook(problem: Any) -> Callable[[FloatArray, float], None] | None:
    """``problem.accept`` (called after every accepted row), or None."""
    fn = getattr(problem, "accept", None)
    return fn if callable(fn) else None


def relabel(problem: Any, specials: Sequence[SpecialPoint]) -> tuple[SpecialPoint, ...]:
    """``problem.relabel(specials)`` if the problem has it, else ``specials``."""
    fn = getattr(problem, "relabel", None)
    return tuple(specials) if not callable(fn) else tuple(fn(tuple(specials)))


def is_sparse(problem: Any) -> bool:
    """``problem.sparse`` (default False)."""
    return bool(getattr(problem, "sparse", False))


def linearize(problem: Any, z: FloatArray, p: float) -> tuple[FloatArray, Any, FloatArray]:
    """``(G, G_z, G_p)`` at ``(z, p)``: one call of ``problem.linearize`` if it has one."""
    lin = getattr(problem, "linearize", None)
    if lin is not None:
        G, Gz, Gp = lin(z, p)
    else:
        G, Gz, Gp = problem.residual(z, p), problem.jacobian(z, p), problem.dp(z, p)
    G = np.asarray(G, dtype=float).reshape(-1)
    Gp = np.asarray(Gp, dtype=float).reshape(-1)
    if not sp.issparse(Gz):
        Gz = np.asarray(Gz, dtype=float)
    return G, Gz, Gp


def has_linearize(problem: Any) -> bool:
    """The problem has its own ``linearize`` (one evaluation for ``G, G_z, G_p``)."""
    return bool(getattr(problem, "linearize", None))


def linearizer(problem: Any) -> Callable[[FloatArray, float], tuple[FloatArray, Any, FloatArray]]:
    """The problem's fast evaluator (``problem.linearizer()``) or :func:`linearize`."""
    fn = getattr(problem, "__dict__", {}).get("_linearizer")  # cached by the problem
    if fn is None:
        get = getattr(problem, "linearizer", None)
        fn = get() if get is not None else None
    if fn is None:
        return partial(linearize, problem)
    return fn  # type: ignore[no-any-return]


def bordered_evaluator(problem: Any) -> Any:
    """The problem's fused bordered evaluator (``problem.bordered_evaluator()``) or None."""
    ev = getattr(problem, "__dict__", {}).get("_bordered", False)
    if ev is False:
        get = getattr(problem, "bordered_evaluator", None)
        ev = get() if get is not None else None
    return ev


def step_kernel(problem: Any) -> Any:
    """The problem's compiled step (``problem.step_kernel()``) or None."""
    get = getattr(problem, "step_kernel", None)
    return get() if get is not None else None


def difference(problem: Any) -> Callable[[FloatArray, FloatArray], FloatArray] | None:
    """``problem.difference`` if it has one, else None (plain ``z1 - z2``)."""
    diff = getattr(problem, "difference", None)
    return diff if callable(diff) else None


def has_periodic_states(problem: Any) -> bool:
    """``problem.difference`` may differ from ``z1 - z2``.

    True when the problem has one and its system does not declare all periods zero
    (``system.period``).
    """
    if difference(problem) is None:
        return False
    period = getattr(getattr(problem, "system", None), "period", None)
    return period is None or bool(np.any(np.asarray(period) > 0))


def record_function(problem: Any) -> Callable[[FloatArray, float], Mapping[str, float]] | None:
    """``problem.record``, or None when it is :class:`EquilibriumProblem`'s.

    That one is always empty, so not worth a call per row.
    """
    if getattr(type(problem), "record", None) is EquilibriumProblem.record:
        return None
    return problem.record  # type: ignore[no-any-return]


def state_names(problem: Any, n: int) -> tuple[str, ...]:
    """Names of the ``n`` unknowns.

    ``problem.state_names``, else ``problem.system.state_names``, else ``("z0", ..., "z{n-1}")``.
    """
    names = getattr(problem, "state_names", None)
    if names is None and hasattr(problem, "system"):
        names = getattr(problem.system, "state_names", None)
    names = tuple(names) if names is not None else ()
    return names if len(names) == n else tuple(f"z{k}" for k in range(n))


def param_values(problem: Any, p0: float) -> dict[str, float]:
    """``{name: value}`` of ``problem.params`` (if any) with the free one set to ``p0``."""
    params = getattr(problem, "params", None)
    out: dict[str, float] = {}
    if params is not None and hasattr(params, "names") and hasattr(params, "values"):
        out = {str(k): float(v) for k, v in zip(params.names, params.values, strict=False)}
    out[str(problem.free)] = float(p0)
    return out


__all__ = [
    "BorderedEvaluatorLike",
    "ContinuationProblem",
    "EquilibriumProblem",
    "ProblemHooks",
    "accept_hook",
    "bordered_evaluator",
    "difference",
    "exact_jacobian",
    "has_linearize",
    "has_periodic_states",
    "is_sparse",
    "jacobian_is_stability",
    "linearize",
    "linearizer",
    "param_values",
    "record_function",
    "relabel",
    "state_names",
    "step_kernel",
]
