r"""Continuation problems :math:`G(z, p) = 0` in one free scalar parameter ``p``.

Every problem the engine continues (equilibria, fold and Hopf curves, connecting
orbits) implements :class:`ContinuationProblem`, so one pseudo-arclength driver
serves all of them.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar, Protocol, runtime_checkable

import numpy as np

from .typing import ComplexArray, FloatArray
from .params import Params
from .system import System


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
        if not isinstance(self.params, Params):
            vec = self.system.check_params(self.params)
            object.__setattr__(self, "params", Params(self.system.param_names, vec))
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

    # -- optional extensions used by the continuation driver (not part of the protocol) --
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
        """Fused evaluator of the bordered Newton system (dense problems with a CasADi
        trace; None otherwise), built once and cached; see
        :meth:`continuation.system.System.bordered_evaluator`."""
        ev = self.__dict__.get("_bordered", False)
        if ev is False:
            make = getattr(self.system, "bordered_evaluator", None)
            ev = None
            if make is not None and not self.sparse:
                ev = make(self._index, self.params.values)
            object.__setattr__(self, "_bordered", ev)
        return ev

    def step_kernel(self) -> Any:
        """The compiled pseudo-arclength step of this problem
        (:class:`continuation._kernel.StepKernel`: dense, CasADi trace, a few states, a
        short tape, Numba installed; :func:`continuation._tape.step_kernel_for`), built
        once and cached; None otherwise."""
        k = self.__dict__.get("_step_kernel", False)
        if k is False:
            from ._tape import step_kernel_for

            k = step_kernel_for(self)
            object.__setattr__(self, "_step_kernel", k)
        return k

    def difference(self, z1: FloatArray, z2: FloatArray) -> FloatArray:
        """``z1 - z2`` with periodic states reduced modulo their period."""
        return self.system.difference(z1, z2)


__all__ = ["ContinuationProblem", "EquilibriumProblem"]
