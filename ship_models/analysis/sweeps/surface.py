"""The critical surface Fn*(H/lambda, lambda/L), with the surge-only threshold and checks."""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from continuation.status import Status
from continuation.sweep import SweepResult
from continuation.typing import FloatArray

from .context import _finite, _run, _vessel_ref
from .tasks import run_task

log = logging.getLogger(__name__)


@dataclass(frozen=True, eq=False)
class SurfaceSweep:
    r"""The critical surface :math:`Fn^*(H/\lambda, \lambda/L)` and the surge-only threshold.

    Attributes
    ----------
    chi_c_deg : float
    H_over_lambda : ndarray, shape (n_H,)
    lambda_over_L : ndarray, shape (n_L,)
    Fn : ndarray, shape (n_L, n_H)
        Critical Fn of the connection at ``chi_c`` (nan where it does not exist).
    Fn_surge : ndarray, shape (n_L, n_H)
        Surge-only threshold (``chi_c = 0``).
    reasons : tuple of str, shape (n_L,)
        Why each line of ``Fn`` ends (empty when complete).
    sweep : SweepResult
    checks : tuple of dict
        Sample points re-computed by bisection of the upslope branch's fate by
        simulation (:func:`~ship_models.analysis.critical_bisection.upslope_bisection`):
        ``H_over_lambda, lambda_over_L, Fn`` (connection), ``Fn_lower, Fn_upper``
        (bisection), ``difference`` (how far the connection's Fn lies outside the
        bracket, 0 inside), ``agrees`` (``difference <= agree_tol``).
        Where it does not agree the connection exists but is not where the fate of the
        branch switches (found at gentle waves: see the module notes).
    check_sweep : SweepResult or None
    thresholds : tuple of dict
        Sample points where the capsizing threshold (the lowest capsizing Fn,
        :func:`~ship_models.analysis.threshold.capsizing_threshold`) was computed:
        ``H_over_lambda, lambda_over_L, Fn_heteroclinic`` (the surface), ``Fn`` (the
        threshold), ``mechanism``, ``is_heteroclinic``: whether the surface *is* the
        capsizing threshold there.
    """

    chi_c_deg: float
    H_over_lambda: FloatArray
    lambda_over_L: FloatArray
    Fn: FloatArray
    Fn_surge: FloatArray
    reasons: tuple[str, ...]
    sweep: SweepResult
    checks: tuple[dict[str, Any], ...] = ()
    check_sweep: SweepResult | None = None
    thresholds: tuple[dict[str, Any], ...] = ()


def surface_sweep(
    vessel: str = "purse_seiner",
    chi_c_deg: float = 10.0,
    *,
    H_over_lambda: Sequence[float] = tuple(np.linspace(0.02, 0.11, 10)),
    lambda_over_L: Sequence[float] = tuple(np.linspace(0.75, 2.5, 8)),
    tol: float = 1e-9,
    surge_tol: float = 1e-8,
    check: int = 0,
    check_tol: float = 1e-6,
    agree_tol: float = 1e-5,
    check_t_max: float = 1800.0,
    thresholds: int = 0,
    **run: Any,
) -> SurfaceSweep:
    r"""The critical surface: one continuation task in :math:`H/\lambda` per wavelength.

    Per wavelength two tasks: :func:`critical_line` at ``chi_c_deg`` and the surge-only
    thresholds (:func:`surge_threshold`) at the same steepnesses. Then ``check`` sample
    points of the surface (spread over the converged ones) are re-computed by bisection
    by simulation, one task each, in a bracket of +-2e-3 around the connection's Fn,
    to ``check_tol``; they agree when the connection's Fn is within ``agree_tol`` of the
    bracket (the bisection itself starts the manifold ``1e-6`` off the saddle and
    integrates at ``rtol = 1e-9``: a few 1e-6 in Fn were seen at gentle waves).

    Returns
    -------
    SurfaceSweep
    """
    vessel = _vessel_ref(vessel)
    hs = np.sort(np.asarray(H_over_lambda, dtype=float).reshape(-1))
    ls = np.sort(np.asarray(lambda_over_L, dtype=float).reshape(-1))
    for name, a in (("H_over_lambda", hs), ("lambda_over_L", ls)):
        if a.size == 0 or not np.all(np.isfinite(a)) or np.any(a <= 0):
            raise ValueError(f"`{name}` must be positive numbers, got {a.tolist()!r}")
    hl = [float(h) for h in hs]
    keys = []
    for lL in ls:
        keys.append({"task": "line", "lambda_over_L": float(lL), "chi_c_deg": float(chi_c_deg),
                     "H_over_lambda": hl, "tol": float(tol), "vessel": vessel})  # fmt: skip
        keys.append({"task": "surge-line", "lambda_over_L": float(lL), "H_over_lambda": hl,
                     "tol": float(surge_tol), "vessel": vessel})  # fmt: skip
    res = _run(run_task, keys, vessel, "surface", run)
    Fn = np.full((ls.size, hs.size), np.nan)
    Fs = np.full((ls.size, hs.size), np.nan)
    reasons = [""] * ls.size
    index = {float(v): i for i, v in enumerate(ls)}
    for r in res.records:
        i = index[r.key["lambda_over_L"]]
        if not r.done:
            if r.key["task"] == "line":
                reasons[i] = f"task failed: {r.errors[-1] if r.errors else ''}"
            continue
        vals = np.array([np.nan if f is None else f for f in r.value["Fn"]], dtype=float)
        if r.key["task"] == "line":
            Fn[i] = vals
            reasons[i] = r.value["reason"]
        else:
            Fs[i] = vals
    checks: list[dict[str, Any]] = []
    check_res = None
    if isinstance(check, bool) or not isinstance(check, int) or check < 0:
        raise ValueError(f"`check` must be a non-negative integer, got {check!r}")
    pts = [(i, j) for i in range(ls.size) for j in range(hs.size) if np.isfinite(Fn[i, j])]
    if check and pts and res.status is not Status.INTERRUPTED:
        pick = [pts[int(k)] for k in np.unique(np.linspace(0, len(pts) - 1, check).round())]
        ck = [
            {"task": "bisect", "lambda_over_L": float(ls[i]), "H_over_lambda": float(hs[j]),
             "chi_c_deg": float(chi_c_deg), "Fn_bracket": [Fn[i, j] - 2e-3, Fn[i, j] + 2e-3],
             "tol": float(check_tol), "t_max": float(check_t_max), "vessel": vessel}
            for i, j in pick
        ]  # fmt: skip
        check_res = _run(run_task, ck, vessel, "surface checks", run)
        for r in check_res.records:
            i, j = (
                index[r.key["lambda_over_L"]],
                int(np.argmin(np.abs(hs - r.key["H_over_lambda"]))),
            )
            v = r.value if r.done else {}
            ok = r.done and v.get("status") == "SUCCESS"
            f = float(Fn[i, j])
            diff = max(v["Fn_lower"] - f, f - v["Fn_upper"], 0.0) if ok else math.nan
            checks.append(
                {"lambda_over_L": float(ls[i]), "H_over_lambda": float(hs[j]), "Fn": f,
                 "Fn_lower": v.get("Fn_lower"), "Fn_upper": v.get("Fn_upper"),
                 "status": v.get("status", "FAILED"), "message": v.get("message", ""),
                 "difference": _finite(diff), "agrees": bool(diff <= agree_tol) if ok else None}
            )  # fmt: skip
    ths: list[dict[str, Any]] = []
    if isinstance(thresholds, bool) or not isinstance(thresholds, int) or thresholds < 0:
        raise ValueError(f"`thresholds` must be a non-negative integer, got {thresholds!r}")
    if thresholds and pts and res.status is not Status.INTERRUPTED:
        pick = [pts[int(k)] for k in np.unique(np.linspace(0, len(pts) - 1, thresholds).round())]
        tk = [
            {"task": "threshold", "lambda_over_L": float(ls[i]), "H_over_lambda": float(hs[j]),
             "chi_c_deg": float(chi_c_deg), "Fn_heteroclinic": float(Fn[i, j]), "vessel": vessel}
            for i, j in pick
        ]  # fmt: skip
        th_res = _run(run_task, tk, vessel, "surface thresholds", run)
        for r in th_res.records:
            v = r.value if r.done else {}
            ths.append({"lambda_over_L": r.key["lambda_over_L"],
                        "H_over_lambda": r.key["H_over_lambda"],
                        "Fn_heteroclinic": r.key["Fn_heteroclinic"], "Fn": v.get("Fn"),
                        "error": v.get("error"), "mechanism": v.get("mechanism"),
                        "is_heteroclinic": v.get("is_heteroclinic"),
                        "status": v.get("status", "FAILED"),
                        "message": v.get("message", "")})  # fmt: skip
    return SurfaceSweep(
        float(chi_c_deg),
        hs,
        ls,
        Fn,
        Fs,
        tuple(reasons),
        res,
        tuple(checks),
        check_res,
        tuple(ths),
    )
