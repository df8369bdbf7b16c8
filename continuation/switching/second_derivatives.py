r"""Second derivatives :math:`D^2G(u)[a, b]` of ``G: R^{N+1} -> R^N`` at a branch point.

From the CasADi trace of the model (forward-over-forward directional derivatives,
``casadi.jtimes``) for an :class:`~continuation.problem.EquilibriumProblem` of a traced
:class:`~continuation.system.System`, else from central differences of the Jacobian,
:math:`(A(u + h b) - A(u - h b))\, a / 2h` with :math:`A = [G_z\; G_p]`.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

import casadi as ca
import numpy as np

from ..problem import EquilibriumProblem, linearize
from ..typing import FloatArray

log = logging.getLogger(__name__)

_EPS = float(np.finfo(float).eps)

SecondDerivative = Callable[[FloatArray, FloatArray, FloatArray], FloatArray]


def _casadi_second_derivative(problem: EquilibriumProblem) -> SecondDerivative:
    """``(u, a, b) -> D^2G(u)[a, b]`` from the CasADi trace of the system's ``rhs``."""
    system = problem.system
    n = system.n_states
    idx = system.param_names.index(problem.free)
    U = ca.SX.sym("u", n + 1)
    a = ca.SX.sym("a", n + 1)
    b = ca.SX.sym("b", n + 1)
    vals = np.asarray(problem.params.values, dtype=float)
    P = ca.vertcat(*[U[n] if k == idx else ca.SX(float(v)) for k, v in enumerate(vals)])
    F = system.symbolic(U[0:n], P)
    d2 = ca.jtimes(ca.jtimes(F, U, a), U, b)
    fn = ca.Function("d2G", [U, a, b], [d2])

    def d2G(u: FloatArray, aa: FloatArray, bb: FloatArray) -> FloatArray:
        return np.asarray(fn(u, aa, bb), dtype=float).reshape(-1)

    return d2G


def _fd_second_derivative(problem: Any) -> SecondDerivative:
    """``(u, a, b) -> D^2G(u)[a, b]`` by central differences of ``[G_z G_p] a``."""

    def d2G(u: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
        n = u.size - 1
        h = _EPS ** (1.0 / 3.0) * max(1.0, float(np.max(np.abs(u)))) / float(np.max(np.abs(b)))
        out = []
        for sgn in (1.0, -1.0):
            uu = u + sgn * h * b
            _, Gz, Gp = linearize(problem, uu[:n], float(uu[n]))
            out.append(np.asarray(Gz @ a[:n]).reshape(-1) + Gp * a[n])
        return (out[0] - out[1]) / (2.0 * h)

    return d2G


def second_derivative(problem: Any) -> tuple[SecondDerivative, str]:
    """``(u, a, b) -> D^2G(u)[a, b]`` and its source.

    All shape (N + 1,), result shape (N,). The source: ``"casadi"`` or ``"finite
    differences"`` (the fallback when the problem is not an EquilibriumProblem of a traced
    system or CasADi cannot trace it twice).
    """
    system = getattr(problem, "system", None)
    if isinstance(problem, EquilibriumProblem) and getattr(system, "has_casadi", False):
        try:
            return _casadi_second_derivative(problem), "casadi"
        except Exception as exc:  # a model CasADi cannot trace twice: fall back
            log.info("no CasADi second derivatives (%s); using finite differences", exc)
    return _fd_second_derivative(problem), "finite differences"


__all__ = ["SecondDerivative", "second_derivative"]
