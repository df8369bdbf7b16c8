"""Math namespaces that let a model write its right-hand side once.

A model's ``rhs(x, p, ops)`` uses only ``ops.<name>`` for elementary functions, so
the same source evaluates with NumPy floats (:data:`NUMPY_OPS`) and traces with
CasADi ``SX`` symbols (:data:`CASADI_OPS`), from which the engine takes exact
Jacobians. Indexing (``x[0]``), arithmetic and ``**`` work on both kinds of
operand, so they need no entry here.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np


@dataclass(frozen=True)
class Ops:
    """Elementary functions for one evaluation backend.

    Attributes
    ----------
    name : str
        ``"numpy"`` or ``"casadi"``.
    sin, cos, tan, exp, log, sqrt, tanh, arctan, abs, sign : callable
        Elementwise functions of one argument.
    atan2 : callable
        ``atan2(y, x)``.
    fmax, fmin : callable
        Elementwise maximum / minimum of two arguments.
    if_else : callable
        ``if_else(cond, a, b)``: ``a`` where ``cond`` is true, else ``b``.
    stack : callable
        Turns a sequence of scalars into a vector of shape ``(len(xs),)``.
    pi : float
        The number pi.
    """

    name: str
    sin: Callable[[Any], Any]
    cos: Callable[[Any], Any]
    tan: Callable[[Any], Any]
    exp: Callable[[Any], Any]
    log: Callable[[Any], Any]
    sqrt: Callable[[Any], Any]
    tanh: Callable[[Any], Any]
    arctan: Callable[[Any], Any]
    abs: Callable[[Any], Any]
    sign: Callable[[Any], Any]
    atan2: Callable[[Any, Any], Any]
    fmax: Callable[[Any, Any], Any]
    fmin: Callable[[Any, Any], Any]
    if_else: Callable[[Any, Any, Any], Any]
    stack: Callable[[Sequence[Any]], Any]
    pi: float = float(np.pi)


def _np_stack(xs: Sequence[Any]) -> Any:
    return np.array([np.asarray(v, dtype=float) for v in xs], dtype=float)


def _ca_stack(xs: Sequence[Any]) -> Any:
    return ca.vertcat(*xs)


#: The elementwise functions of :class:`Ops` by its names: ``(NumPy's name, CasADi's name)``.
_NAMES = {
    **{f: (f, f) for f in ("sin", "cos", "tan", "exp", "log", "sqrt", "tanh", "sign")},
    "arctan": ("arctan", "atan"),
    "abs": ("abs", "fabs"),
    "atan2": ("arctan2", "atan2"),
    "fmax": ("maximum", "fmax"),
    "fmin": ("minimum", "fmin"),
}


def _functions(module: Any, which: int) -> dict[str, Any]:
    """The functions of :data:`_NAMES` in ``module`` (``which``: 0 NumPy, 1 CasADi)."""
    return {f: getattr(module, names[which]) for f, names in _NAMES.items()}


NUMPY_OPS = Ops(
    name="numpy",
    **_functions(np, 0),
    if_else=lambda c, a, b: np.where(c, a, b),
    stack=_np_stack,
)

CASADI_OPS = Ops(
    name="casadi",
    **_functions(ca, 1),
    if_else=lambda c, a, b: ca.if_else(c, a, b),
    stack=_ca_stack,
)

__all__ = ["Ops", "NUMPY_OPS", "CASADI_OPS"]
