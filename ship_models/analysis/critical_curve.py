r"""The critical curve: critical Fn against the autopilot course (Umeda 1999, Fig. 23).

The heteroclinic connection of :mod:`ship_models.analysis.critical_bvp` (crest saddle
to the same saddle one wavelength back, ``Fn`` unknown) is continued in ``chi_c`` by
pseudo-arclength (:func:`continuation.bvp.continue_connection`), and every requested
course is then corrected exactly.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from continuation.bvp import continue_connection
from continuation.bvp.simplified import JacobianCache, simplified_newton
from continuation.errors import ContinuationError
from continuation.newton import newton
from continuation.settings import ContinuationSettings, NewtonSettings
from continuation.status import Status
from continuation.typing import FloatArray

from .critical_bvp import critical_fn_bvp
from .critical_result import CriticalFn
from .params import course, ship_model

log = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class CriticalCurve:
    """Critical ``Fn`` against the course: the paper's Fig. 23 line.

    Attributes
    ----------
    chi_c : ndarray, shape (K,)
        Requested courses (rad).
    Fn : ndarray, shape (K,)
        Critical ``Fn`` at each course (nan where not computed).
    residual_norm : ndarray, shape (K,)
        ``max |G|`` of the connection at each course.
    converged : ndarray of bool, shape (K,)
        Whether the point was corrected to the requested course.
    n_unstable : ndarray of int, shape (K,)
        Unstable eigenvalues of the crest saddle at each course (1 for a valid
        codimension-one connection; -1 where not computed).
    branch : Branch or None
        The pseudo-arclength branch of connections in ``chi_c``.
    start : CriticalFn
        The one-shot solve the branch started from.
    status : Status
    message : str
    elapsed : float
        Wall time (s), the start solve included.
    """

    chi_c: FloatArray
    Fn: FloatArray
    residual_norm: FloatArray
    converged: np.ndarray
    n_unstable: np.ndarray
    branch: Any
    start: CriticalFn
    status: Status
    message: str
    elapsed: float = 0.0
    orbits: tuple[FloatArray, ...] = field(default=(), repr=False)

    @property
    def success(self) -> bool:
        """True when every requested course converged."""
        return self.status is Status.SUCCESS

    @property
    def chi_c_deg(self) -> FloatArray:
        """Courses in degrees."""
        return np.degrees(self.chi_c)

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "chi_c_deg": [round(float(c), 9) for c in self.chi_c_deg],
            "Fn": [None if not np.isfinite(f) else float(f) for f in self.Fn],
            "residual_norm": [float(r) for r in self.residual_norm],
            "converged": [bool(c) for c in self.converged],
            "n_unstable": [int(k) for k in self.n_unstable],
            "status": self.status.name,
            "message": self.message,
            "elapsed_s": self.elapsed,
            "start": self.start.to_json(),
        }

    def to_csv(self, path: str | Path) -> Path:
        """Write ``chi_c_deg, Fn_critical, residual_norm, converged`` rows."""
        path = Path(path)
        rows = ["chi_c_deg,Fn_critical,residual_norm,converged"]
        for c, f, r, ok in zip(
            self.chi_c_deg, self.Fn, self.residual_norm, self.converged, strict=True
        ):
            rows.append(f"{c:.6g},{f:.10f},{r:.3e},{int(bool(ok))}")
        path.write_text("\n".join(rows) + "\n")
        return path


def critical_curve(
    chi_c_values: Sequence[float] | FloatArray | None = None,
    *,
    model: Any = None,
    params: Any = None,
    start: CriticalFn | None = None,
    ds: float = 0.02,
    ds_max: float = 0.1,
    tol: float = 1e-9,
    keep_orbits: bool = False,
    throw: bool = False,
    progress: Callable[[Any], None] | None = None,
    **bvp_options: Any,
) -> CriticalCurve:
    r"""Critical ``Fn`` over a range of courses by continuing the connection in ``chi_c``.

    One connection is solved at the course of the requested range closest to its
    middle (:func:`critical_fn_bvp`, or ``start``), then continued with
    pseudo-arclength (:func:`continuation.bvp.continue_connection`, both directions)
    across the range with ``Fn`` an unknown of the boundary-value problem. Every
    requested course is then corrected exactly: the two branch rows around it give a
    linear predictor in ``chi_c`` and Newton solves the connection at that fixed
    course (same mesh, same compiled functions).

    Parameters
    ----------
    chi_c_values : array_like, shape (K,), optional
        Courses (rad); default 0, 1, ..., 30 degrees.
    model, params
        As for :func:`critical_fn_bvp`.
    start : CriticalFn, optional
        A converged connection at one course inside the range.
    ds, ds_max : float
        Pseudo-arclength step (initial and largest).
    tol : float
        Newton tolerance of the continuation corrector and of the corrections.
    keep_orbits : bool
        Store the orbit ``x (M, 8)`` of every corrected course in ``orbits``.
    throw : bool
        Raise :class:`~continuation.errors.ContinuationError` if a course fails.
    progress : callable, optional
        Called with every accepted branch point.
    **bvp_options
        Passed to :func:`critical_fn_bvp` for the start solve.

    Returns
    -------
    CriticalCurve
        ``status`` ``SUCCESS``, a failure status (some courses nan) or ``INTERRUPTED``.
    """
    t_start = time.perf_counter()
    if chi_c_values is None:
        chis = np.radians(np.arange(0.0, 31.0))
    else:
        chis = np.atleast_1d(np.asarray(chi_c_values, dtype=float))
        if chis.ndim != 1 or chis.size == 0:
            raise ValueError("`chi_c_values` must be a non-empty 1-D array of courses (rad)")
        for c in chis:
            course(c, "chi_c_values")
    if not (math.isfinite(ds) and ds > 0 and math.isfinite(ds_max) and ds_max >= ds):
        raise ValueError(f"`ds` and `ds_max` must satisfy 0 < ds <= ds_max, got {ds}, {ds_max}")
    m = ship_model(model)
    lo_c, hi_c = float(chis.min()), float(chis.max())
    if start is None:
        mid = chis[np.argmin(np.abs(chis - 0.5 * (lo_c + hi_c)))]
        start = critical_fn_bvp(float(mid), model=m, params=params, **bvp_options)
    elif not isinstance(start, CriticalFn):
        raise ValueError(f"`start` must be a CriticalFn, got {type(start).__name__}")
    nan = np.full(chis.size, np.nan)
    if not start.success:
        msg = f"the start connection did not converge: {start.message}"
        if throw:
            raise ContinuationError(msg)
        return CriticalCurve(
            chis, nan, nan.copy(), np.zeros(chis.size, bool), np.full(chis.size, -1), None, start,
            start.status, msg, time.perf_counter() - t_start,
        )  # fmt: skip
    margin = max(0.25 * (hi_c - lo_c) / max(chis.size - 1, 1), 1e-3)
    settings = ContinuationSettings(
        ds=ds,
        ds_max=ds_max,
        p_min=min(lo_c, start.chi_c) - margin,
        p_max=max(hi_c, start.chi_c) + margin,
        max_steps=400,
        newton=NewtonSettings(tol=tol, step_tol=1e-8, max_iter=8),
    )
    direction = (
        "both" if lo_c < start.chi_c < hi_c else ("forward" if start.chi_c <= lo_c else "backward")
    )
    branch = continue_connection(
        start.orbit, "chi_c", settings, direction=direction, progress=progress
    )
    prob = branch.problem
    P = np.asarray(branch.p, dtype=float)
    Z = np.asarray(branch.x, dtype=float)
    Fn = nan.copy()
    res_n = nan.copy()
    ok = np.zeros(chis.size, dtype=bool)
    n_unst = np.full(chis.size, -1, dtype=int)
    orbits: list[FloatArray] = []
    status = branch.status if branch.status is Status.INTERRUPTED else Status.SUCCESS
    corr = NewtonSettings(tol=tol, step_tol=1e-8, max_iter=15, damping=True)
    chord_settings = NewtonSettings(tol=tol, step_tol=1e-8, max_iter=12)
    jac_cache = JacobianCache()
    try:
        for k, c in enumerate(chis):
            z0 = _predict(P, Z, float(c))
            if z0 is None:
                continue
            # one factorised Jacobian serves neighbouring courses while it contracts fast
            r = simplified_newton(
                lambda z, c=c: prob.residual(z, c),
                lambda z, c=c: prob.jacobian(z, c),
                z0,
                chord_settings,
                cache=jac_cache,
            )
            if not r.converged:
                jac_cache.clear()
                r = newton(
                    lambda z, c=c: prob.residual(z, c), lambda z, c=c: prob.jacobian(z, c), z0, corr
                )
            if not r.converged:
                log.warning("course %.3g deg did not converge: %s", math.degrees(c), r.message)
                continue
            parts = prob.unpack(r.z)
            pv = prob.param_vector(r.z, float(c))
            n_unst[k] = int(np.sum(np.linalg.eigvals(m.jacobian(parts["x_from"], pv)).real > 0))
            if n_unst[k] != 1:
                log.warning(
                    "course %.3g deg: the crest saddle has %d unstable eigenvalues",
                    math.degrees(c),
                    n_unst[k],
                )
                continue
            Fn[k] = float(parts["params"]["Fn"])
            res_n[k] = float(r.residual_norm)
            ok[k] = True
            if keep_orbits:
                orbits.append(np.asarray(parts["X"], dtype=float))
    except KeyboardInterrupt:
        status = Status.INTERRUPTED
    n_ok = int(ok.sum())
    if status is Status.SUCCESS and n_ok < chis.size:
        status = Status.NEWTON_FAILED if branch.status.ok else branch.status
    message = f"{n_ok}/{chis.size} courses; branch: {branch.status.name} ({len(P)} points)"
    if throw and status is not Status.SUCCESS and status is not Status.INTERRUPTED:
        raise ContinuationError(f"critical curve incomplete: {message}")
    return CriticalCurve(
        chis, Fn, res_n, ok, n_unst, branch, start, status, message,
        time.perf_counter() - t_start, tuple(orbits),
    )  # fmt: skip


def _predict(P: FloatArray, Z: FloatArray, c: float) -> FloatArray | None:
    """Linear interpolation of the branch rows ``Z`` at ``chi_c = c`` (first bracketing pair)."""
    if P.size == 0:
        return None
    for i in range(P.size - 1):
        a, b = P[i], P[i + 1]
        if min(a, b) <= c <= max(a, b) and a != b:
            w = (c - a) / (b - a)
            return (1 - w) * Z[i] + w * Z[i + 1]
    j = int(np.argmin(np.abs(P - c)))
    if abs(P[j] - c) < 1e-12:
        return Z[j].copy()
    return None


__all__ = ["CriticalCurve", "critical_curve"]
