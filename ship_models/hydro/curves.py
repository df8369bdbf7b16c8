r"""Measured curves as smooth, CasADi-traceable functions: cubic splines and polynomials.

A table ``(x_i, y_i)`` of a measured curve (resistance against speed, open-water
thrust coefficient against advance ratio, wake fraction against speed) is
interpolated by the cubic spline with knots at the data,

.. math::

    s(x) = a_0 + a_1 \xi + a_2 \xi^2 + a_3 \xi^3 + \sum_{k=1}^{N-2} c_k\,(\xi - \xi_k)_+^3,
    \qquad \xi = \frac{x - x_0}{x_{N-1} - x_0},

the truncated-power form of a C2 cubic spline (de Boor, C. 1978, "A Practical Guide
to Splines", Springer, ch. VIII). The :math:`N + 2` coefficients solve the
:math:`N` interpolation conditions plus two end conditions: a natural end
(:math:`s'' = 0`) or a clamped slope at each end. Evaluated with ``ops.fmax`` the
spline is exact in CasADi, so the continuation differentiates it exactly (it is C2:
its second derivative is continuous, its third jumps at the knots).

:class:`Polynomial1D` is the polynomial alternative (e.g. a published
:math:`K_T(J)` polynomial). Both carry the interval ``valid`` on which the data
stand: outside it the function is an extrapolation, which
:mod:`ship_models.validity` reports.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from continuation.ops import NUMPY_OPS, Ops
from continuation.typing import FloatArray


@dataclass(frozen=True)
class CubicSpline1D:
    """C2 cubic spline in truncated-power form (see module doc).

    Attributes
    ----------
    x0, scale : float
        ``xi = (x - x0) / scale``.
    poly : ndarray, shape (4,)
        ``a_0 .. a_3``.
    knots : ndarray, shape (K,)
        Interior knots ``xi_k`` in (0, 1).
    coeffs : ndarray, shape (K,)
        ``c_k``.
    valid : tuple of float
        ``(x_lo, x_hi)`` covered by the data.
    """

    x0: float
    scale: float
    poly: FloatArray
    knots: FloatArray
    coeffs: FloatArray
    valid: tuple[float, float]

    def evaluate(self, x: Any, ops: Ops = NUMPY_OPS) -> Any:
        """``s(x)`` for scalar (CasADi) or array (NumPy) ``x``."""
        xi = (x - self.x0) / self.scale
        a = self.poly
        out = a[0] + xi * (a[1] + xi * (a[2] + xi * a[3]))
        for k, c in zip(self.knots, self.coeffs, strict=True):
            out = out + c * ops.fmax(xi - k, 0.0) ** 3
        return out

    def derivative(self, x: Any, ops: Ops = NUMPY_OPS) -> Any:
        """``s'(x)``."""
        xi = (x - self.x0) / self.scale
        a = self.poly
        out = a[1] + xi * (2.0 * a[2] + 3.0 * xi * a[3])
        for k, c in zip(self.knots, self.coeffs, strict=True):
            out = out + 3.0 * c * ops.fmax(xi - k, 0.0) ** 2
        return out / self.scale

    def __call__(self, x: FloatArray | float) -> FloatArray:
        """NumPy evaluation at any shape."""
        return np.asarray(self.evaluate(np.asarray(x, dtype=float)), dtype=float)


def interpolating_spline(
    x: FloatArray,
    y: FloatArray,
    *,
    slope_start: float | None = None,
    slope_end: float | None = None,
) -> CubicSpline1D:
    """The C2 cubic spline through ``(x_i, y_i)`` (knots at the data).

    Parameters
    ----------
    x, y : array_like, shape (N,)
        Strictly increasing abscissae (N >= 2) and the values.
    slope_start, slope_end : float, optional
        Clamped end slopes ``s'(x_0)``, ``s'(x_{N-1})``; None (default): a natural end
        (``s'' = 0``).

    Returns
    -------
    CubicSpline1D

    Raises
    ------
    ValueError
        If the abscissae are not strictly increasing or fewer than two, or a value is
        not finite.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.ndim != 1 or x.shape != y.shape or x.size < 2:
        raise ValueError("`x` and `y` must be 1-D of the same length >= 2")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise ValueError("`x` and `y` must be finite")
    if np.any(np.diff(x) <= 0):
        raise ValueError("`x` must be strictly increasing")
    x0, scale = float(x[0]), float(x[-1] - x[0])
    xi = (x - x0) / scale
    knots = xi[1:-1]
    n = x.size

    def row_value(s: float) -> FloatArray:
        return np.concatenate([[1.0, s, s * s, s**3], np.maximum(s - knots, 0.0) ** 3])

    def row_d1(s: float) -> FloatArray:
        return np.concatenate([[0.0, 1.0, 2 * s, 3 * s * s], 3 * np.maximum(s - knots, 0.0) ** 2])

    def row_d2(s: float) -> FloatArray:
        return np.concatenate([[0.0, 0.0, 2.0, 6 * s], 6 * np.maximum(s - knots, 0.0)])

    rows = [row_value(s) for s in xi]
    rhs = list(y)
    for s, slope in ((0.0, slope_start), (1.0, slope_end)):
        if slope is None:
            rows.append(row_d2(s))
            rhs.append(0.0)
        else:
            rows.append(row_d1(s))
            rhs.append(float(slope) * scale)
    A = np.array(rows)
    coef = np.linalg.solve(A, np.array(rhs))
    assert coef.size == n + 2
    return CubicSpline1D(
        x0, scale, coef[:4].copy(), knots.copy(), coef[4:].copy(), (float(x[0]), float(x[-1]))
    )


@dataclass(frozen=True)
class Polynomial1D:
    r"""``p(x) = sum_i c_i x^i`` with the interval ``valid`` on which it was fitted.

    An optional C2 tail beyond ``tail_start``,
    :math:`p(x) + t\,(x - x_t)_+^3`, changes only the third derivative there (e.g. to
    continue a regression beyond its range by its quadratic Taylor part).
    """

    coeffs: FloatArray
    valid: tuple[float, float]
    tail_start: float = math.inf
    tail_cubic: float = 0.0

    def evaluate(self, x: Any, ops: Ops = NUMPY_OPS) -> Any:
        """Horner evaluation (NumPy or CasADi)."""
        out: Any = 0.0
        for c in self.coeffs[::-1]:
            out = out * x + float(c)
        if self.tail_cubic != 0.0 and math.isfinite(self.tail_start):
            out = out + self.tail_cubic * ops.fmax(x - self.tail_start, 0.0) ** 3
        return out

    def derivative(self, x: Any, ops: Ops = NUMPY_OPS) -> Any:
        """``p'(x)``."""
        out: Any = 0.0
        for i in range(len(self.coeffs) - 1, 0, -1):
            out = out * x + i * float(self.coeffs[i])
        if self.tail_cubic != 0.0 and math.isfinite(self.tail_start):
            out = out + 3.0 * self.tail_cubic * ops.fmax(x - self.tail_start, 0.0) ** 2
        return out

    def __call__(self, x: FloatArray | float) -> FloatArray:
        """NumPy evaluation."""
        return np.asarray(self.evaluate(np.asarray(x, dtype=float)), dtype=float)


__all__ = ["CubicSpline1D", "Polynomial1D", "interpolating_spline"]
