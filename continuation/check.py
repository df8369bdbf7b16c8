r"""Check a continuation problem against its contract: :func:`check_problem`.

The contract is written in :mod:`continuation.problem` (:class:`ContinuationProblem`
and the optional :class:`ProblemHooks`). :func:`check_problem` evaluates a problem at
one point ``(z, p)`` and reports every way it breaks that contract:

* shapes: ``residual`` ``(N,)``, ``jacobian`` ``(N, N)``, ``dp`` ``(N,)``, all finite;
* derivatives: ``G_z`` and ``G_p`` against central differences of ``residual``;
* hooks: ``linearize``, ``linearizer`` and ``bordered_evaluator`` give the same
  ``(G, G_z, G_p)`` as the three plain methods (to round-off);
  ``jacobian_is_stability`` means ``stability`` returns the eigenvalues of ``G_z``;
  ``difference(z, z) = 0``; ``state_names`` has ``N`` names; ``record`` maps names to
  floats; ``accept`` is idempotent; ``relabel`` of no points is no points; a sparse
  ``G_z`` comes with ``sparse`` set.

Finite-difference tolerance
---------------------------
Column ``j`` of ``G_z`` is compared with the central difference
:math:`D_h = (G(z + h e_j) - G(z - h e_j)) / (2 h)` at :math:`h/2`, with
:math:`h = \epsilon^{1/3} \max(1, |z_j|)` (the step that balances truncation and
round-off for central differences). Its error is bounded by (i) the truncation,
estimated by Richardson: :math:`|D_h - D_{h/2}|` (three times the leading term
:math:`h^2 |G'''| / 24` of :math:`D_{h/2}`), and (ii) the round-off
:math:`\eta / (h/2)` with :math:`\eta = 64 \epsilon S` the evaluation noise of ``G``
at the scale :math:`S = 1 + \max|G| + \max|G_z| \max(1, \max|z|)` of its terms. An
entry fails when it differs by more than ``safety`` (10) times that bound. When the
problem does not claim ``exact_jacobian`` its own derivatives may be finite
differences too: :math:`\sqrt{\epsilon} S` is added (the error of one-sided
differences at the optimal step).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from .problem import accept_hook, exact_jacobian, is_sparse, jacobian_is_stability, relabel
from .typing import FloatArray

_EPS = float(np.finfo(float).eps)
#: Multiple of the finite-difference error bound an entry may differ by.
SAFETY = 10.0
#: Relative agreement required of two evaluations of the same quantity (fast paths).
ROUNDOFF_RTOL = 1e-9


@dataclass(frozen=True)
class ProblemCheck:
    """Result of :func:`check_problem`.

    Attributes
    ----------
    failures : tuple of str
        One sentence per broken rule (empty: the problem keeps its contract).
    jacobian_ratio : float
        ``max |G_z - D| / bound`` over the entries (``<= SAFETY`` passes).
    dp_ratio : float
        The same for ``G_p``.
    """

    failures: tuple[str, ...]
    jacobian_ratio: float
    dp_ratio: float

    @property
    def ok(self) -> bool:
        """No rule broken."""
        return not self.failures


def _dense(A: Any) -> FloatArray:
    return np.asarray(A.toarray() if sp.issparse(A) else A, dtype=float)


def _central(
    G: Callable[[FloatArray, float], FloatArray], z: FloatArray, p: float, j: int, h: float
) -> FloatArray:
    """``(G(z + h e_j) - G(z - h e_j)) / (2 h)``; ``j = -1``: the step is in ``p``."""
    if j < 0:
        return (np.asarray(G(z, p + h)) - np.asarray(G(z, p - h))) / (2.0 * h)
    zp, zm = z.copy(), z.copy()
    zp[j] += h
    zm[j] -= h
    return (np.asarray(G(zp, p)) - np.asarray(G(zm, p))) / (2.0 * h)


def _fd_ratio(
    G: Callable[[FloatArray, float], FloatArray],
    z: FloatArray,
    p: float,
    j: int,
    analytic: FloatArray,
    scale: float,
    exact: bool,
) -> float:
    """Largest ``|analytic - D| / bound`` of one column (module notes)."""
    x = p if j < 0 else z[j]
    h = _EPS ** (1.0 / 3.0) * max(1.0, abs(x))
    d1 = _central(G, z, p, j, h)
    d2 = _central(G, z, p, j, h / 2.0)
    bound = np.abs(d1 - d2) + 64.0 * _EPS * scale / (h / 2.0)
    if not exact:
        bound = bound + np.sqrt(_EPS) * scale
    return float(np.max(np.abs(analytic - d2) / bound, initial=0.0))


def _close(a: Any, b: Any, scale: float) -> bool:
    a, b = _dense(a), _dense(b)
    return a.shape == b.shape and bool(np.all(np.abs(a - b) <= ROUNDOFF_RTOL * scale))


def _spectra_match(a: Any, b: Any, scale: float) -> bool:
    a = np.sort_complex(np.asarray(a, dtype=complex).ravel())
    b = np.sort_complex(np.asarray(b, dtype=complex).ravel())
    if a.shape != b.shape:
        return False
    dist = np.abs(a[:, None] - b[None, :])
    # each eigenvalue of one near one of the other (double eigenvalues split at sqrt(eps))
    tol = 1e-6 * scale
    return bool(np.all(dist.min(axis=1) <= tol) and np.all(dist.min(axis=0) <= tol))


def check_problem(problem: Any, z: Any, p: float) -> ProblemCheck:
    r"""Check ``problem`` against the contract of :mod:`continuation.problem` at ``(z, p)``.

    Parameters
    ----------
    problem : ContinuationProblem
        The problem (with any of the optional :class:`~continuation.problem.ProblemHooks`).
    z : array_like, shape (N,)
        Unknowns; best a point on (or near) a branch, where the derivatives matter.
    p : float
        Free-parameter value.

    Returns
    -------
    ProblemCheck
        ``ok`` when every rule holds; ``failures`` says which did not (module notes for
        the rules and the finite-difference tolerance).

    Notes
    -----
    The ``accept`` hook is run at ``(z, p)`` first, as the driver does at a row, so a
    problem with a moving reference is checked where it will be used. The check costs
    ``4 (N + 1)`` residual evaluations.
    """
    fails: list[str] = []
    z = np.array(z, dtype=float).reshape(-1)
    p = float(p)
    n = z.size
    if not isinstance(getattr(problem, "free", None), str):
        fails.append("`free` is not a parameter name (str)")
    n_unknowns = getattr(problem, "n_unknowns", None)
    if n_unknowns != n:
        fails.append(f"n_unknowns is {n_unknowns}, z has {n} entries")
        return ProblemCheck(tuple(fails), np.inf, np.inf)

    accept = accept_hook(problem)
    G0 = None
    if accept is not None:
        accept(z.copy(), p)
        G0 = np.array(problem.residual(z, p), dtype=float)
        accept(z.copy(), p)

    G = np.asarray(problem.residual(z, p), dtype=float)
    Gz_raw = problem.jacobian(z, p)
    Gz = _dense(Gz_raw)
    Gp = np.asarray(problem.dp(z, p), dtype=float)
    for name, arr, shape in (("residual", G, (n,)), ("jacobian", Gz, (n, n)), ("dp", Gp, (n,))):
        if arr.shape != shape:
            fails.append(f"{name} has shape {arr.shape}, expected {shape}")
        elif not np.all(np.isfinite(arr)):
            fails.append(f"{name} is not finite at the point")
    if fails:
        return ProblemCheck(tuple(fails), np.inf, np.inf)
    if G0 is not None and not _close(G0, G, 1.0 + np.max(np.abs(G))):
        fails.append("accept(z, p) is not idempotent: the residual changed on a second call")

    scale = (
        1.0
        + float(np.max(np.abs(G)))
        + float(np.max(np.abs(Gz))) * max(1.0, float(np.max(np.abs(z))))
    )
    exact = exact_jacobian(problem)
    residual = problem.residual
    jac_ratio = max((_fd_ratio(residual, z, p, j, Gz[:, j], scale, exact) for j in range(n)),
                    default=0.0)  # fmt: skip
    dp_ratio = _fd_ratio(residual, z, p, -1, Gp, scale, exact)
    what = "exact" if exact else "approximate"
    if jac_ratio > SAFETY:
        fails.append(
            f"jacobian ({what}) differs from central differences by {jac_ratio:.3g} times "
            "their error bound"
        )
    if dp_ratio > SAFETY:
        fails.append(
            f"dp ({what}) differs from central differences by {dp_ratio:.3g} times their "
            "error bound"
        )

    # -- the fast paths give the same values
    lin = getattr(problem, "linearize", None)
    if callable(lin):
        g, gz, gp = lin(z, p)
        if not (_close(g, G, scale) and _close(gz, Gz, scale) and _close(gp, Gp, scale)):
            fails.append("linearize differs from (residual, jacobian, dp)")
    make = getattr(problem, "linearizer", None)
    fn = make() if callable(make) else None
    if fn is not None:
        g, gz, gp = (np.array(_dense(a)) for a in fn(z, p))
        if not (_close(g, G, scale) and _close(gz, Gz, scale) and _close(gp, Gp, scale)):
            fails.append("linearizer() differs from (residual, jacobian, dp)")
    make = getattr(problem, "bordered_evaluator", None)
    ev = make() if callable(make) else None
    if ev is not None:
        c = np.linspace(1.0, 2.0, n + 1)
        ev.u[:] = np.append(z, p)
        ev.c[:] = c
        ev.h[:] = 0.0
        ev()
        r, M = np.array(ev.r), np.array(ev.M)
        border = np.column_stack([Gz, Gp])
        if not (_close(r[:n], G, scale) and _close(M[:n], border, scale)):
            fails.append("bordered_evaluator() differs from (residual, jacobian, dp)")

    # -- properties
    if sp.issparse(Gz_raw) and not is_sparse(problem):
        fails.append("jacobian is a sparse matrix but `sparse` is not set")
    stab = problem.stability(z, p)
    if stab is not None:
        stab = np.asarray(stab)
        if stab.ndim != 1:
            fails.append(f"stability returns an array of shape {stab.shape}, expected 1-D")
        elif jacobian_is_stability(problem) and not _spectra_match(
            stab, np.linalg.eigvals(Gz), scale
        ):
            fails.append("jacobian_is_stability is set but stability is not eig(jacobian)")
    elif jacobian_is_stability(problem):
        fails.append("jacobian_is_stability is set but stability returns None")
    rec = problem.record(z, p)
    if not isinstance(rec, Mapping):
        fails.append("record does not return a mapping")
    else:
        for k, v in rec.items():
            try:
                float(v)
            except (TypeError, ValueError):
                fails.append(f"record entry {k!r} is not a float")
    diff = getattr(problem, "difference", None)
    if callable(diff):
        d0 = np.asarray(diff(z, z), dtype=float)
        step = 1e-7 * np.linspace(1.0, 2.0, n)
        d1 = np.asarray(diff(z + step, z), dtype=float)
        if d0.shape != (n,) or np.any(d0 != 0.0) or not np.allclose(d1, step, rtol=1e-6):
            fails.append("difference(z1, z2) is not z1 - z2 near z")
    names = getattr(problem, "state_names", None)
    if names is not None and len(tuple(names)) != n:
        fails.append(f"state_names has {len(tuple(names))} names for {n} unknowns")
    if relabel(problem, ()) != ():
        fails.append("relabel of no special points returns points")
    return ProblemCheck(tuple(fails), jac_ratio, dp_ratio)


__all__ = ["ProblemCheck", "check_problem"]
