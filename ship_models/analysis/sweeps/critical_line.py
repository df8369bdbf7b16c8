"""The critical Fn of the connection over wave steepness at one wavelength and course."""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from continuation.errors import ContinuationError
from continuation.newton import newton
from continuation.settings import ContinuationSettings, NewtonSettings
from continuation.status import Status
from continuation.typing import FloatArray

from ...contracts import VesselModel
from .context import _finite
from .surge import surge_threshold

log = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class CriticalLine:
    r"""Critical Fn of the connection over :math:`H/\lambda` at one wavelength and course.

    Attributes
    ----------
    chi_c : float
        Course (rad).
    lambda_over_L : float
    H_over_lambda : ndarray, shape (K,)
        Requested steepnesses, increasing.
    Fn : ndarray, shape (K,)
        Critical Fn (nan where the connection was not found).
    converged : ndarray of bool, shape (K,)
    reason : str
        Why the line ends (empty if every point converged).
    H_end : float
        Smallest steepness the branch of connections reached (nan without a branch).
    start_H : float
        Steepness of the one-shot solve the branch started from.
    branch_status : str
    """

    chi_c: float
    lambda_over_L: float
    H_over_lambda: FloatArray
    Fn: FloatArray
    converged: np.ndarray
    reason: str
    H_end: float
    start_H: float
    branch_status: str

    def to_json(self) -> dict[str, Any]:
        """JSON-ready (``None`` for missing Fn)."""
        return {
            "chi_c_deg": math.degrees(self.chi_c),
            "lambda_over_L": self.lambda_over_L,
            "H_over_lambda": [float(h) for h in self.H_over_lambda],
            "Fn": [_finite(f) for f in self.Fn],
            "converged": [bool(c) for c in self.converged],
            "reason": self.reason,
            "H_end": _finite(self.H_end),
            "start_H": self.start_H,
            "branch_status": self.branch_status,
        }


def _interp_row(P: FloatArray, Z: FloatArray, h: float) -> FloatArray | None:
    for i in range(P.size - 1):
        a, b = P[i], P[i + 1]
        if a != b and min(a, b) <= h <= max(a, b):
            w = (h - a) / (b - a)
            return (1 - w) * Z[i] + w * Z[i + 1]
    j = int(np.argmin(np.abs(P - h))) if P.size else -1
    return Z[j].copy() if j >= 0 and abs(P[j] - h) < 1e-12 else None


def critical_line(
    model: VesselModel,
    chi_c: float,
    lambda_over_L: float,
    H_over_lambda: Sequence[float],
    *,
    tol: float = 1e-9,
    ds: float = 0.004,
    ds_max: float = 0.01,
    max_steps: int = 60,
) -> CriticalLine:
    r"""Critical Fn over steepness: the connection continued in :math:`H/\lambda`.

    1. Solve the connection (:func:`~ship_models.analysis.critical_bvp.critical_fn_bvp`)
       at the steepest requested wave, its guess Fn the surge-only threshold there
       (:func:`surge_threshold`).
    2. Continue it in ``H_over_lambda`` down to the gentlest requested wave
       (:func:`continuation.bvp.continue_connection`, ``Fn`` an unknown), exactly as
       :func:`~ship_models.analysis.critical_curve.critical_curve` continues it in ``chi_c``.
    3. Correct every requested steepness by Newton at fixed ``H_over_lambda`` from the
       branch rows around it; a point counts only if the crest saddle there has one
       unstable eigenvalue.

    The line is the connection; whether it is also where the fate switches must be
    checked by simulation (see the module notes: not so at gentle waves).

    Where the branch stops before the gentlest wave, the rest of the line is nan and
    ``reason`` says where and why: the branch status, and the crest saddle's unstable
    eigenvalue at the last point (falling to zero: the saddle merges with the
    surf-riding point, there is no surf-riding in gentler waves).

    Parameters
    ----------
    model : VesselModel
    chi_c : float
        Course (rad).
    lambda_over_L : float
    H_over_lambda : sequence of float, shape (K,)
    tol : float
        Newton tolerance (continuation corrector and point corrections).
    ds, ds_max : float
        Pseudo-arclength steps.
    max_steps : int
        Steps of the branch at most.

    Returns
    -------
    CriticalLine
    """
    from continuation.bvp import continue_connection

    from ..critical_bvp import critical_fn_bvp

    hs = np.sort(np.asarray(H_over_lambda, dtype=float).reshape(-1))
    if hs.size == 0 or not np.all(np.isfinite(hs)) or np.any(hs <= 0):
        raise ValueError(f"`H_over_lambda` must be positive numbers, got {H_over_lambda!r}")
    if not (math.isfinite(lambda_over_L) and lambda_over_L > 0):
        raise ValueError(f"`lambda_over_L` must be positive, got {lambda_over_L!r}")
    Fn = np.full(hs.size, np.nan)
    ok = np.zeros(hs.size, dtype=bool)
    h0 = float(hs[-1])

    def result(reason: str, h_end: float, status: str) -> CriticalLine:
        return CriticalLine(chi_c, lambda_over_L, hs, Fn, ok, reason, h_end, h0, status)

    base = model.default_params().replace(chi_c=chi_c, lambda_over_L=lambda_over_L)
    from ship_models.surge import SurgeModel

    st = surge_threshold(SurgeModel(model.data), h0, lambda_over_L)
    if not st.success:
        return result(f"no start at H/lambda = {h0:g}: surge model: {st.message}", math.nan, "")
    fa, fb = st.Fn_range
    try:
        start = critical_fn_bvp(
            chi_c, model=model, params=base.replace(H_over_lambda=h0), Fn_guess=st.Fn,
            guess_bracket=(fa + 0.05 * (fb - fa), fb - 0.05 * (fb - fa)), tol=min(tol, 1e-10),
        )  # fmt: skip
    except (ContinuationError, ValueError) as exc:
        return result(f"no connection at H/lambda = {h0:g}: {exc}", math.nan, "")
    if not start.success:
        return result(f"no connection at H/lambda = {h0:g}: {start.message}", math.nan, "")
    if hs.size == 1:
        Fn[0], ok[0] = start.Fn, True
        return result("", h0, "")
    margin = 0.25 * float(np.min(np.diff(hs))) if hs.size > 1 else 1e-3
    settings = ContinuationSettings(
        ds=ds, ds_max=ds_max, p_min=float(hs[0]) - margin, p_max=h0 + margin,
        max_steps=max_steps, newton=NewtonSettings(tol=tol, step_tol=1e-8, max_iter=8),
    )  # fmt: skip
    branch = continue_connection(start.orbit, "H_over_lambda", settings, direction="both")
    if branch.status is Status.INTERRUPTED:
        raise KeyboardInterrupt
    prob = branch.problem
    P = np.asarray(branch.p, dtype=float)
    Z = np.asarray(branch.x, dtype=float)
    corr = NewtonSettings(tol=tol, step_tol=1e-8, max_iter=15, damping=True)

    def saddle_rate(z: FloatArray, h: float) -> tuple[int, float]:
        parts = prob.unpack(z)
        w = np.linalg.eigvals(model.jacobian(parts["x_from"], prob.param_vector(z, h)))
        return int(np.sum(w.real > 0)), float(np.max(w.real))

    failed: list[str] = []
    for k, h in enumerate(hs):
        z0 = _interp_row(P, Z, float(h))
        if z0 is None:
            continue
        r = newton(lambda z, h=h: prob.residual(z, h), lambda z, h=h: prob.jacobian(z, h), z0, corr)
        if not r.converged:
            failed.append(f"Newton failed at H/lambda = {h:g}: {r.message}")
            continue
        n_unst, _ = saddle_rate(r.z, float(h))
        if n_unst != 1:
            failed.append(f"crest saddle with {n_unst} unstable eigenvalues at H/lambda = {h:g}")
            continue
        Fn[k] = float(prob.unpack(r.z)["params"]["Fn"])
        ok[k] = True
    # rows of the branch that are valid connections: crest saddle of index 1
    rows = [saddle_rate(Z[i], float(P[i])) for i in range(P.size)]
    valid = np.array([n == 1 for n, _ in rows])
    h_end = float(P[valid].min()) if valid.any() else math.nan
    reasons = list(failed)
    if valid.any() and hs[0] < h_end - 1e-12:
        j = int(np.argmin(np.where(valid, P, np.inf)))
        j0 = int(np.argmin(np.abs(P - h0)))
        rate, rate0 = rows[j][1], rows[j0][1]
        fn_end = float(prob.unpack(Z[j])["params"]["Fn"])
        why = (
            f"the connection ends near H/lambda = {h_end:.5g} (Fn = {fn_end:.5f}; branch "
            f"{branch.status.name}, lowest H/lambda on it {float(P.min()):.5g}): the crest "
            f"saddle's unstable eigenvalue falls to {rate:.3g} 1/s there "
            f"({rate0:.3g} at H/lambda = {h0:g})"
        )
        if not valid.all():
            why += (
                "; beyond, the branch's end equilibrium has no unstable direction: the crest "
                "saddle merges with the surf-riding point (saddle-node), no surf-riding in "
                "gentler waves at this speed"
            )
        elif rate < 0.2 * rate0:
            why += "; it is merging with the surf-riding point: no surf-riding in gentler waves"
        reasons.append(why)
    return result("; ".join(reasons), h_end, branch.status.name)
