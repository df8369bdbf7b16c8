r"""Fold (saddle-node) curves in two parameters: the Moore-Spence augmented system.

Unknowns ``z = (x, p1, v)`` (shape ``(2n+1,)``), continuation parameter
``p = p2``::

    G(z, p2) = ( f(x, p1, p2),  J(x, p1, p2) v,  (v.v - 1)/2 ) = 0

(Moore & Spence 1980, SIAM J. Numer. Anal. 17, 567-576). The Jacobian ``dG/dz``
holds the second derivatives ``d(J v)/dx`` and ``d(J v)/dp1``; with a CasADi trace
of the system they are exact.

Codim-2 test functions along the curve (Kuznetsov 2004, "Elements of Applied
Bifurcation Theory", 3rd ed., Sec. 8.2-8.4 and 10.2.2; Govaerts 2000, "Numerical
Methods for Bifurcations of Dynamical Equilibria", SIAM, Ch. 4), each smooth in
``z`` and changing sign at the point it detects:

``bt`` (Bogdanov-Takens)
    :math:`\psi_{BT} = \operatorname{tr}\operatorname{adj} J = e_{n-1}(\lambda)`,
    the product of the eigenvalues other than the fold's zero; it vanishes when a
    second eigenvalue reaches zero. Equivalently :math:`\psi_{BT} \propto w^T v`.
    (Both ``bt`` and ``cusp`` use the adjugate divided by the positive product of all
    singular values of ``J`` but the two smallest, :func:`scaled_adjugate`: same zeros
    and signs, no overflow for large ``n``.)
``cusp``
    :math:`\psi_{CP} = v^T \operatorname{adj}(J)\, B(v, v)`, proportional to the
    fold's quadratic normal-form coefficient :math:`a = w^T B(v, v) / (2 w^T v)`,
    with the left null vector taken from the adjugate so that it stays smooth
    through Bogdanov-Takens points.
``zh`` (zero-Hopf / fold-Hopf)
    :math:`\psi_{ZH} = \prod_{i<j} (\lambda_i + \lambda_j)` over the eigenvalues
    other than the zero one; a sign change with a purely imaginary pair at the
    located point is a zero-Hopf point (a real pair ``±mu`` is a neutral saddle
    and is discarded).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ..typing import FloatArray
from ._base import (
    AugmentedProblem,
    null_vector,
    scaled_adjugate,
    signed_product,
)
from ._build import fold_recipe


def _pair_sum_product(eigs: np.ndarray) -> float:
    """``prod_{i<j} (l_i + l_j)`` (real: the set is closed under conjugation).

    Evaluated by :func:`signed_product`, so that the ``m (m - 1) / 2`` factors of a
    large system do not overflow.
    """
    e = np.asarray(eigs, dtype=complex).reshape(-1)
    i, j = np.triu_indices(e.size, k=1)
    return signed_product(e[i] + e[j])


@dataclass(frozen=True, eq=False)
class FoldProblem(AugmentedProblem):
    """Continuation of a fold of equilibria in the parameters ``(free1, free2)``.

    See the module docstring for the equations. Build it with
    :meth:`from_point` (from a located fold of a one-parameter branch) or
    :meth:`from_state` (from a state near a fold), or directly with a known
    ``z0 = (x, p1, v)``.

    Examples
    --------
    >>> def rhs(x, p, ops):
    ...     return ops.stack([p[0] + p[1] * x[0] - x[0] ** 3])
    >>> sys_ = System(rhs, ("x",), ("b1", "b2"))
    >>> prob = FoldProblem.from_state(sys_, sys_.params(b1=-2.0, b2=3.0), "b1", "b2", [1.0])
    >>> round(prob.p1(prob.z0), 12)
    -2.0
    """

    kind: ClassVar[str] = "fold"
    n_extra: ClassVar[int] = 0
    _recipe = staticmethod(fold_recipe)
    test_names: ClassVar[tuple[str, ...]] = ("bt", "cusp", "zh")

    @classmethod
    def _start(cls, x: FloatArray, p1: float, J: FloatArray) -> tuple[FloatArray, dict[str, Any]]:
        """``z0 = (x, p1, v)``, ``v`` the unit null vector of ``J``; no further fields."""
        return np.concatenate([x, [p1], null_vector(J)]), {}

    # ----------------------------------------------------------------- codim 2
    def quadratic_coefficient(self, z: FloatArray, p: float) -> float:
        r"""Normal-form coefficient :math:`a = w^T B(v, v) / (2\, w^T v)` of the fold.

        The restriction to the centre manifold is :math:`\dot y = a y^2 + \ldots`
        with ``x = x* + y v``; ``a = 0`` at a cusp. Infinite at a Bogdanov-Takens
        point (``w^T v = 0``).
        """
        x, v = self.state(z), self.vector(z)
        Pv = self.param_vector(z, p)
        # the scaled adjugate: a positive multiple of adj(J), which cancels in the ratio,
        # without the overflow of a product of n - 1 singular values (stiff or large J)
        adj = scaled_adjugate(self.state_jacobian(z, p))
        w = adj.T @ v
        return float(w @ self.functions.bvv(x, Pv, v) / (2.0 * (w @ v)))

    def test_functions(self, z: FloatArray, p: float) -> dict[str, float]:
        """Values of the codim-2 test functions ``{"bt", "cusp", "zh"}`` at ``(z, p)``."""
        return dict(self._memo("tests", z, p, lambda: self._test_functions(z, p)))

    def _test_functions(self, z: FloatArray, p: float) -> dict[str, float]:
        x, v = self.state(z), self.vector(z)
        Pv = self.param_vector(z, p)
        J = self.state_jacobian(z, p)
        eigs = np.linalg.eigvals(J)
        adj = scaled_adjugate(J)  # adj(J) / (a positive scale): no overflow for large n
        k0 = int(np.argmin(np.abs(eigs)))
        rest = np.delete(eigs, k0)
        return {
            "bt": float(np.trace(adj)),
            "cusp": float(v @ adj @ self.functions.bvv(x, Pv, v) / max(float(v @ v), 1e-300)),
            "zh": _pair_sum_product(rest),
        }

    def test_function(self, name: str, z: FloatArray, p: float) -> float:
        """One codim-2 test function by name (see :attr:`test_names`)."""
        if name not in self.test_names:
            raise ValueError(f"`name` must be one of {self.test_names}, got {name!r}")
        return self.test_functions(z, p)[name]

    def classify(self, name: str, z: FloatArray, p: float, tol: float = 1e-6) -> str | None:
        """Confirm a located zero of test function ``name``; return its kind or None.

        ``zh`` zeros are kept only if an eigenvalue pair other than the fold's zero
        is purely imaginary (otherwise the zero marks a neutral saddle).
        """
        if name != "zh":
            return name
        eigs = np.linalg.eigvals(self.state_jacobian(z, p))
        rest = np.delete(eigs, int(np.argmin(np.abs(eigs))))
        scale = max(1.0, float(np.max(np.abs(eigs))))
        ok = np.any((np.abs(rest.real) <= tol * scale) & (np.abs(rest.imag) > tol * scale))
        return "zh" if ok else None


__all__ = ["FoldProblem"]
