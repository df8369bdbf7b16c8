r"""Accuracy control of a connecting-orbit solve: adaptive mesh and error estimates.

:class:`ConnectionAccuracy` holds the settings; the functions here build the two
re-solves behind the error estimates of the solved parameters ``p``:

* discretisation: the adapted mesh with every interval halved
  (:meth:`CollocationMesh.refined`, the nodes of the adapted mesh kept), estimate
  ``safety * |p(2N) - p(N)|``. Gauss collocation of degree ``m`` gives parameters
  to :math:`O(h^{2m})` (Ascher, Mattheij & Russell 1995, ch. 5), so the change is
  :math:`(1 - 2^{-2m})` times the error of ``p(N)`` once ``h`` is in the asymptotic
  range; ``safety`` (default 2) covers the pre-asymptotic range.
* truncation: ``[0, T]`` lengthened to ``[0, T_factor T]`` with the same resolution
  (:func:`extended_mesh`: the interior nodes kept, intervals as long as the end
  intervals added at both ends), estimate ``safety * |p(T_factor T) - p(T)|``. The
  truncation error of projection boundary conditions decays exponentially in ``T``
  (Beyn 1990, "The numerical computation of connecting orbits in dynamical systems",
  IMA J. Numer. Anal. 10:379-405), so ``|p(T) - p^*| = |p(T) - p(T_f T)| +
  O(|p(T_f T) - p^*|)`` is dominated by the change. Keeping the resolution keeps the
  discretisation error of the two solves equal, so the change measures truncation
  alone.

The mesh itself is adapted as in AUTO-07p (Doedel et al.): the nodes equidistribute
:math:`h_j^{m+1} |x^{(m+1)}|`, the local error of collocation of degree ``m``, with
:math:`x^{(m+1)}` from differences of the piecewise-constant ``m``-th derivative
(:meth:`CollocationMesh.equidistributed`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..typing import FloatArray
from .collocation import CollocationMesh


@dataclass(frozen=True)
class ConnectionAccuracy:
    r"""Settings of the adaptive solve and of the error estimates of the solved parameters.

    A result is ``SUCCESS`` only if, for every solved parameter ``p``, both estimates
    (see the module docstring) are at most ``atol + rtol * |p|``.

    Parameters
    ----------
    rtol : float
        Relative tolerance of both estimates (default ``1e-6``).
    atol : float
        Absolute tolerance of both estimates (default ``1e-8``).
    adapt_rounds : int
        Equidistribution rounds on each mesh size (default 2; fewer when the nodes stop
        moving: largest move below a tenth of the local interval; none on the starting
        mesh when the guess is a result estimated on exactly that mesh).
    max_refinements : int
        How often the number of intervals may be doubled when the discretisation
        estimate fails (default 3: at most 8 times the starting intervals).
    max_extensions : int
        How often ``T`` may be multiplied by ``T_factor`` when the truncation estimate
        fails (default 2).
    T_factor : float
        Lengthening of ``T`` for the truncation estimate (default 1.5).
    safety : float
        Factor on both changes (default 2).
    estimate : bool
        False: a plain Newton solve on the given mesh, no adaptation and no estimates
        (``result.errors`` is None; ``SUCCESS`` then only means Newton converged).
    """

    rtol: float = 1e-6
    atol: float = 1e-8
    adapt_rounds: int = 2
    max_refinements: int = 3
    max_extensions: int = 2
    T_factor: float = 1.5
    safety: float = 2.0
    estimate: bool = True

    def __post_init__(self) -> None:
        for name in ("rtol", "atol"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise ValueError(f"`{name}` must be a finite number >= 0, got {v!r}")
        if self.rtol == 0 and self.atol == 0:
            raise ValueError("`rtol` and `atol` cannot both be 0")
        for name in ("adapt_rounds", "max_refinements", "max_extensions"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 0:
                raise ValueError(f"`{name}` must be an integer >= 0, got {v!r}")
        if not (math.isfinite(self.T_factor) and self.T_factor > 1):
            raise ValueError(f"`T_factor` must be > 1, got {self.T_factor!r}")
        if not (math.isfinite(self.safety) and self.safety >= 1):
            raise ValueError(f"`safety` must be >= 1, got {self.safety!r}")

    def tolerance(self, value: float) -> float:
        """``atol + rtol * |value|``."""
        return float(self.atol + self.rtol * abs(value))


def extended_mesh(mesh: CollocationMesh, T_factor: float) -> tuple[CollocationMesh, float, int]:
    """The mesh on ``[0, T_factor T]`` with the same resolution, and its offset.

    The old nodes (in ``t``) are shifted by ``off = (T_factor - 1) T / 2``; on each side
    ``ceil(off / h_end)`` intervals of about the end interval's length ``h_end`` are
    added (at most ``ceil((T_factor - 1) N / 2)`` per side, the mean resolution).

    Returns
    -------
    mesh : CollocationMesh
    off : float
        Time shift of the old interval inside the new one.
    k_left : int
        Intervals added on the left (old node ``j`` is new node ``j + k_left``).
    """
    T = mesh.T
    tn = mesh.nodes * T
    off = 0.5 * (T_factor - 1.0) * T
    cap = max(1, int(math.ceil(0.5 * (T_factor - 1.0) * mesh.n_intervals)))
    k0 = min(cap, max(1, int(math.ceil(off / (tn[1] - tn[0]) - 1e-9))))
    k1 = min(cap, max(1, int(math.ceil(off / (tn[-1] - tn[-2]) - 1e-9))))
    left = np.linspace(-off, 0.0, k0 + 1)[:-1]
    right = T + np.linspace(0.0, off, k1 + 1)[1:]
    T2 = T + 2.0 * off
    nodes = (np.concatenate((left, tn, right)) + off) / T2
    nodes[0], nodes[-1] = 0.0, 1.0
    return CollocationMesh(nodes.size - 1, mesh.degree, T2, nodes), off, k0


def _linear_flow(A: FloatArray, d: FloatArray, s: FloatArray, unstable: bool) -> FloatArray:
    """``Re(V exp(Lambda s) c)`` for the (un)stable part ``c`` of ``d = V c``; shape (K, n)."""
    lam, V = np.linalg.eig(A)
    c = np.linalg.solve(V, d.astype(complex))
    keep = lam.real > 0 if unstable else lam.real < 0
    c = np.where(keep, c, 0.0)
    lam = np.where(keep, lam, 0.0)  # the dropped modes would overflow exp at large |s|
    return np.real((V[None, :, :] * np.exp(np.outer(s, lam))[:, None, :]) @ c)


def extended_guess(
    result: Any, mesh2: CollocationMesh, off: float
) -> tuple[FloatArray, FloatArray]:
    """``(t, x)`` on ``mesh2``: the orbit in the middle, linear flows at the saddles outside.

    Before ``t = 0`` the orbit is continued backwards along the unstable eigenspace
    of the start saddle, after ``T`` forwards along the stable eigenspace of the end
    saddle (the linearised flow, exact to first order in the distance).
    """
    prob = result.problem
    system = prob.system
    pvec = np.array(result.params.values, dtype=float)
    t2 = mesh2.t
    s = t2 - off
    T = result.mesh.T
    x = result.interpolate(np.clip(s, 0.0, T))
    lo, hi = s < 0.0, s > T
    if np.any(lo):
        A = np.asarray(system.jacobian(result.x_from, pvec), dtype=float)
        x[lo] = result.x_from + _linear_flow(A, result.x[0] - result.x_from, s[lo], True)
    if np.any(hi):
        A = np.asarray(system.jacobian(result.x_to, pvec), dtype=float)
        x[hi] = result.x_to + _linear_flow(A, result.x[-1] - result.x_to, s[hi] - T, False)
    return t2, x


def extended_problem(result: Any, T_factor: float) -> tuple[Any, tuple[FloatArray, FloatArray]]:
    """The problem of ``result`` on the longer interval and its guess (same resolution)."""
    prob = result.problem
    mesh2, off, _ = extended_mesh(prob.mesh, T_factor)
    changes: dict[str, Any] = {"mesh": mesh2, "reference": None}
    if prob.layout.pin is not None:
        at = (prob.phase.at * prob.mesh.T + off) / mesh2.T
        changes["phase"] = dataclasses.replace(prob.phase, at=at)
    return prob.replace(**changes), extended_guess(result, mesh2, off)


def refined_problem(result: Any) -> Any:
    """The problem of ``result`` on its mesh with every interval halved."""
    return result.problem.replace(mesh=result.problem.mesh.refined(), reference=None)


__all__ = ["ConnectionAccuracy", "extended_mesh", "extended_problem", "refined_problem"]
