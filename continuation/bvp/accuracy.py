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

:func:`controlled` is the one loop (adapt, halve, lengthen) behind both
:func:`~continuation.bvp.solve.solve_connection` and
:func:`~continuation.bvp.landing_solve.solve_landing`: a landing differs only in how its
problem is re-solved (:class:`Resolves`) and in being lengthened at its end only (its
start is a point, not a saddle). A periodic orbit has no truncation: its mesh
adaptation (:func:`~continuation.periodic.adapt_mesh`) and the discretisation estimate
of its parameter at a period limit are the loop's two steps :func:`adapted` and
:func:`discretisation_changes`, with the cycle's re-solves
(:func:`continuation.periodic.solve.cycle_resolves`).
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..status import Status
from ..typing import FloatArray
from .collocation import CollocationMesh
from .result import ErrorEstimates

log = logging.getLogger(__name__)


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


def extended_mesh(
    mesh: CollocationMesh, T_factor: float, start: bool = True
) -> tuple[CollocationMesh, float, int]:
    """The mesh on ``[0, T_factor T]`` with the same resolution, and its offset.

    The old nodes (in ``t``) are shifted by ``off = (T_factor - 1) T / 2``; on each side
    ``ceil(off / h_end)`` intervals of about the end interval's length ``h_end`` are
    added (at most ``ceil((T_factor - 1) N / 2)`` per side, the mean resolution).
    With ``start=False`` (an orbit from a given point) all of ``(T_factor - 1) T`` is
    added at the end (at most ``ceil((T_factor - 1) N)`` intervals) and ``off = 0``.

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
    sides = 2 if start else 1
    off = (T_factor - 1.0) * T / sides  # added on each extended side
    cap = max(1, int(math.ceil((T_factor - 1.0) * mesh.n_intervals / sides)))
    k1 = min(cap, max(1, int(math.ceil(off / (tn[-1] - tn[-2]) - 1e-9))))
    right = T + np.linspace(0.0, off, k1 + 1)[1:]
    if not start:
        nodes = np.concatenate((tn, right)) / (T + off)
        nodes[-1] = 1.0
        return CollocationMesh(nodes.size - 1, mesh.degree, T + off, nodes), 0.0, 0
    k0 = min(cap, max(1, int(math.ceil(off / (tn[1] - tn[0]) - 1e-9))))
    left = np.linspace(-off, 0.0, k0 + 1)[:-1]
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


def extended_orbit(
    system: Any,
    pvec: FloatArray,
    mesh: CollocationMesh,
    x: FloatArray,
    mesh2: CollocationMesh,
    off: float,
    x_from: FloatArray | None,
    x_to: FloatArray,
) -> FloatArray:
    """The orbit ``x`` (on ``mesh``) at the points of ``mesh2``, shape ``(M2, n)``.

    The old interval sits at ``[off, off + T]`` of the new one. Before it the orbit is
    continued backwards along the unstable eigenspace of the start saddle ``x_from``,
    after it forwards along the stable eigenspace of the end saddle ``x_to`` (the
    linearised flow, exact to first order in the distance); ``x_from`` None: nothing is
    added before (``off = 0``).
    """
    s = mesh2.t - off
    T = mesh.T
    out = mesh.interpolate(x, np.clip(s, 0.0, T) / T)
    lo, hi = s < 0.0, s > T
    if np.any(lo) and x_from is not None:
        A = np.asarray(system.jacobian(x_from, pvec), dtype=float)
        out[lo] = x_from + _linear_flow(A, x[0] - x_from, s[lo], True)
    if np.any(hi):
        A = np.asarray(system.jacobian(x_to, pvec), dtype=float)
        out[hi] = x_to + _linear_flow(A, x[-1] - x_to, s[hi] - T, False)
    return out


def extended_guess(
    result: Any, mesh2: CollocationMesh, off: float
) -> tuple[FloatArray, FloatArray]:
    """``(t, x)`` on ``mesh2``: the orbit in the middle, linear flows at the saddles outside.

    See :func:`extended_orbit`.
    """
    pvec = np.array(result.params.values, dtype=float)
    x = extended_orbit(result.problem.system, pvec, result.mesh, result.x, mesh2, off,
                       result.x_from, result.x_to)  # fmt: skip
    return mesh2.t, x


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


@dataclass(frozen=True)
class Resolves:
    """How :func:`controlled` re-solves a result (each returns a new result).

    The results need ``success``, ``message``, ``mesh``, ``params`` (by name) and
    ``free`` (the names of the solved parameters): a
    :class:`~continuation.bvp.result.ConnectionResult`, a
    :class:`~continuation.bvp.result.LandingResult`, or a cycle's
    :class:`~continuation.periodic.solve.CycleSolve`.

    Attributes
    ----------
    adapt : callable
        ``adapt(result)``: one equidistribution of the mesh and a solve on it.
    refine : callable
        ``refine(result)``: the solve on the mesh with every interval halved.
    extend : callable or None
        ``extend(result, T_factor)``: the solve on ``[0, T_factor T]`` at the same
        resolution; None for an orbit without truncation (a cycle), which uses
        :func:`adapted` and :func:`discretisation_changes` but not :func:`controlled`.
    keep_on_adapt_failure : bool
        When an adaptation solve fails: True keeps the last result and goes on to the
        estimates (a landing), False returns the failure (a connection, a cycle).
    """

    adapt: Callable[[Any], Any]
    refine: Callable[[Any], Any]
    extend: Callable[[Any, float], Any] | None = None
    keep_on_adapt_failure: bool = False


def _changes(a: Any, b: Any, safety: float) -> dict[str, float]:
    return {u: safety * abs(b.params[u] - a.params[u]) for u in a.free}


def _worst(est: dict[str, float], tol: dict[str, float]) -> str | None:
    bad = [u for u in est if not est[u] <= tol[u]]
    return max(bad, key=lambda u: est[u] / max(tol[u], 1e-300)) if bad else None


def _keep_nothing(result: Any) -> None:
    """The default ``keep`` of :func:`adapted` and :func:`controlled`."""


def adapted(
    result: Any,
    rounds: int,
    how: Resolves,
    progress: Callable[[Any], None] | None = None,
    keep: Callable[[Any], None] = _keep_nothing,
) -> Any:
    """At most ``rounds`` equidistribution solves ``how.adapt``; stop once the nodes settle.

    The nodes have settled when no interior node moved by more than a tenth of the
    shorter of its two neighbouring intervals (old or new); a round that changed the
    number of intervals (a cycle's :func:`~continuation.periodic.adapt_mesh` with
    ``n_intervals``) is never the last for that reason.

    Parameters
    ----------
    result
        A converged solve (see :class:`Resolves`).
    rounds : int
    how : Resolves
    progress : callable, optional
        Called with every adaptation solve.
    keep : callable
        Called with every converged adaptation solve.

    Returns
    -------
    result
        The last converged solve, or the failed one (``how.keep_on_adapt_failure``
        False).
    """
    for _ in range(rounds):
        old = result.mesh.nodes
        new = how.adapt(result)
        if new.success:
            keep(new)
        if progress is not None:
            progress(new)
        if not new.success:
            return result if how.keep_on_adapt_failure else new
        result = new
        if result.mesh.nodes.size != old.size:
            continue
        h = np.minimum(np.diff(old), np.diff(result.mesh.nodes))
        move = np.abs(result.mesh.nodes - old)
        if np.all(move[1:-1] <= 0.1 * np.minimum(h[:-1], h[1:])):
            break
    return result


def discretisation_changes(
    result: Any,
    how: Resolves,
    safety: float,
    progress: Callable[[Any], None] | None = None,
) -> tuple[Any, dict[str, float] | None]:
    r"""The re-solve on the halved mesh and the discretisation estimates of ``result``.

    ``safety * |p(2N) - p(N)|`` for every solved parameter ``p`` (``result.free``), the
    solve ``p(2N)`` by ``how.refine`` (see the module docstring for the order
    :math:`O(h^{2m})` behind it).

    Returns
    -------
    fine
        The re-solve on the halved mesh.
    changes : dict of str to float or None
        The estimates; None where the re-solve failed.
    """
    fine = how.refine(result)
    if progress is not None:
        progress(fine)
    return fine, (_changes(result, fine, safety) if fine.success else None)


def _flagged(
    result: Any, status: Status, message: str, errors: ErrorEstimates | None = None
) -> Any:
    """``result`` with an accuracy status, its message and (if any) its estimates."""
    changes: dict[str, Any] = {"status": status, "message": message}
    if errors is not None:
        changes["errors"] = errors
    return dataclasses.replace(result, **changes)


def controlled(
    result: Any,
    acc: ConnectionAccuracy,
    how: Resolves,
    rounds: int | None = None,
    progress: Callable[[Any], None] | None = None,
    keep: Callable[[Any], None] = _keep_nothing,
    first_rounds: int | None = None,
) -> Any:
    r"""Adapt, refine and lengthen until both estimates meet ``acc``.

    1. ``rounds`` (default ``acc.adapt_rounds``; ``first_rounds`` on the starting mesh)
       equidistribution solves, fewer once the nodes stop moving.
    2. Discretisation estimate ``safety |p(2N) - p(N)|``; above ``atol + rtol |p|`` the
       halved mesh becomes the mesh (at most ``max_refinements`` times), back to 1.
    3. Truncation estimate ``safety |p(T_factor T) - p(T)|``; above the tolerance the
       longer problem is adopted (at most ``max_extensions`` times) and 1-3 repeat.

    Parameters
    ----------
    result : ConnectionResult or LandingResult
        A converged solve (``success``, ``params``, ``free``, ``mesh``, ``message``).
    acc : ConnectionAccuracy
    how : Resolves
        The re-solves of this kind of orbit.
    rounds, first_rounds : int, optional
    progress : callable, optional
        Called with every intermediate result.
    keep : callable
        Called with every converged result that may be returned (an interrupted
        caller returns the last).

    Returns
    -------
    result
        The solution on the last adapted mesh with ``errors`` set: ``SUCCESS``,
        ``DISCRETISATION_ERROR`` or ``TRUNCATION_ERROR`` (the message names the
        parameter, the estimate, the tolerance and what to change), or the failed
        adaptation solve.
    """
    if how.extend is None:
        raise ValueError("`how.extend` is needed: controlled() estimates the truncation error")
    rounds = acc.adapt_rounds if rounds is None else rounds
    for n_ext in range(acc.max_extensions + 1):
        # ---- discretisation: adapt, halve, compare; double the intervals if needed
        for n_ref in range(acc.max_refinements + 1):
            k = rounds if (n_ext or n_ref or first_rounds is None) else first_rounds
            result = adapted(result, k, how, progress, keep)
            if not result.success:
                return result
            tol = {u: acc.tolerance(result.params[u]) for u in result.free}
            fine, changes = discretisation_changes(result, how, acc.safety, progress)
            if changes is None:
                return _flagged(
                    result,
                    Status.DISCRETISATION_ERROR,
                    f"{Status.DISCRETISATION_ERROR.value} The re-solve on the halved mesh "
                    f"({fine.mesh.n_intervals} intervals) failed: {fine.message}",
                )
            e_d = changes
            bad = _worst(e_d, tol)
            if bad is None:
                break
            if n_ref == acc.max_refinements:
                return _flagged(
                    result,
                    Status.DISCRETISATION_ERROR,
                    f"discretisation error of {bad} estimated {e_d[bad]:.2e} > tolerance "
                    f"{tol[bad]:.2e} after {acc.max_refinements} doublings of the mesh "
                    f"({result.mesh.n_intervals} intervals, degree {result.mesh.degree}):"
                    " raise `max_refinements`, the degree or the starting intervals, or "
                    "loosen rtol/atol",
                    ErrorEstimates(e_d, {u: math.nan for u in e_d}, tol, fine.mesh.n_intervals),
                )
            log.info(
                "discretisation estimate %.2e > %.2e: %d intervals",
                e_d[bad],
                tol[bad],
                fine.mesh.n_intervals,
            )
            result = fine
            keep(fine)
        # ---- truncation: same resolution on a longer interval
        long = how.extend(result, acc.T_factor)
        if progress is not None:
            progress(long)
        if not long.success:
            return _flagged(
                result,
                Status.TRUNCATION_ERROR,
                f"{Status.TRUNCATION_ERROR.value} The re-solve on T = {long.mesh.T:.6g}"
                f" failed ({long.message}): the truncation error cannot be estimated; "
                "check the saddles and the guess, or try a different T",
                ErrorEstimates(
                    e_d, {u: math.nan for u in e_d}, tol, fine.mesh.n_intervals, long.mesh.T
                ),
            )
        e_T = _changes(result, long, acc.safety)
        errors = ErrorEstimates(e_d, e_T, tol, fine.mesh.n_intervals, long.mesh.T)
        bad = _worst(e_T, tol)
        if bad is None:
            return _flagged(
                result,
                Status.SUCCESS,
                f"{result.message}; error estimates within tolerance "
                + ", ".join(f"{u}: {e_d[u]:.1e} (mesh) + {e_T[u]:.1e} (T)" for u in e_d),
                errors,
            )
        if n_ext == acc.max_extensions:
            return _flagged(
                result,
                Status.TRUNCATION_ERROR,
                f"truncation error of {bad} estimated {e_T[bad]:.2e} > tolerance "
                f"{tol[bad]:.2e} at T = {result.mesh.T:.6g} (after {acc.max_extensions} "
                f"extensions): give a longer T (about {long.mesh.T * acc.T_factor:.4g}) "
                "or raise `max_extensions`, or loosen rtol/atol",
                errors,
            )
        log.info("truncation estimate %.2e > %.2e: T = %.6g", e_T[bad], tol[bad], long.mesh.T)
        result = long
        keep(long)
    raise AssertionError("unreachable")  # pragma: no cover


__all__ = [
    "ConnectionAccuracy",
    "Resolves",
    "adapted",
    "controlled",
    "discretisation_changes",
    "extended_mesh",
    "extended_orbit",
    "extended_problem",
    "refined_problem",
]
