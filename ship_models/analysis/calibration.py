r"""Explicit calibration: one coefficient solved so that the critical Fn hits a target.

With a measured (or published) critical Froude number :math:`Fn^\dagger` at one
course, :func:`calibrate` solves the connection of
:mod:`ship_models.analysis.critical_bvp` with ``Fn`` *fixed* at the target and one
named coefficient :math:`\theta` of the vessel *unknown*: the same collocation
residual :math:`G(z; \theta) = 0`, where the unknown slot of ``Fn`` in ``z`` now
holds :math:`\theta`. Newton's method on that bordered system uses the exact
:math:`G_z` (CasADi) with its ``Fn`` column replaced by :math:`G_\theta` (a forward
difference of the residual with the model rebuilt at :math:`\theta + h`, as in
:mod:`ship_models.analysis.sensitivity`), starting from the first-order predictor
:math:`\theta_0 + (Fn^\dagger - Fn^*)/(dFn^*/d\theta)`,
:math:`z_0 + (dz/d\theta)\,\Delta\theta`.

The discretisation (mesh, truncation time, phase reference) is that of the starting
connection; the calibrated vessel is then checked by a fresh
:func:`~ship_models.analysis.critical_bvp.critical_fn_bvp` solve and, if that misses the
target by more than ``target_tol``, the bordered solve is repeated on the fresh
connection's discretisation.

A calibrated value is never a prediction: the written vessel file records the
coefficient with status ``calibrated`` and a source naming the target, its course
and where the target came from, and keeps the value it replaced in that source.

Functions of :mod:`ship_models.analysis.critical_bvp` used: ``critical_fn_bvp`` and
``critical_curve`` (and the ``CriticalFn`` / ``CriticalCurve`` results).
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from continuation.casadi_compile import uncompiled
from continuation.typing import FloatArray

from ..contracts import VesselModel
from ..estimation import build_vessel_model
from ..registry import vessel_model
from ..vessel import Coefficient, VesselData, dump_vessel, load_vessel
from .critical_bvp import critical_fn_bvp
from .critical_curve import CriticalCurve, critical_curve
from .critical_result import CriticalFn
from .sensitivity.adjoint import _fn_index
from .sensitivity.factors import FACTORS, SYSTEM_PARAMS
from .sensitivity.rebuild import model_at

log = logging.getLogger(__name__)

#: Default provenance of the paper's critical Fn at chi_c = 10 deg.
PAPER_TARGET_SOURCE = (
    "Umeda (1999), J Mar Sci Technol 4:16-26, discussion of Figs. 10-15 (chi_c = 10 deg): "
    "'between Fn = 0.3247 and Fn = 0.3248 there is a nominal Froude number whose unstable "
    "manifold of a saddle tends to a different saddle'; midpoint 0.32475"
)


@dataclass(frozen=True, eq=False)
class Calibration:
    """A coefficient solved so that the critical Fn of one course equals a target.

    Attributes
    ----------
    key : str
        Dotted vessel key.
    target_Fn : float
        The target critical Fn.
    chi_c : float
        Course of the target (rad).
    target_source : str
        Where the target comes from.
    value_before, value : float
        The coefficient before and after (its own unit).
    unit : str
    Fn_before : float
        Critical Fn with ``value_before``.
    Fn_check : float
        Critical Fn of the calibrated vessel from a fresh ``critical_fn_bvp`` solve.
    iterations : int
        Bordered Newton iterations (all rounds).
    rounds : int
        Bordered solves (1 unless the fresh check missed ``target_tol``).
    vessel : VesselData
        The calibrated vessel (file values plus the calibrated entry).
    connection : CriticalFn
        The fresh connection of the calibrated vessel.
    success : bool
        ``|Fn_check - target_Fn| <= target_tol``.
    message : str
    elapsed : float
    """

    key: str
    target_Fn: float
    chi_c: float
    target_source: str
    value_before: float
    value: float
    unit: str
    Fn_before: float
    Fn_check: float
    iterations: int
    rounds: int
    vessel: VesselData = field(repr=False)
    connection: CriticalFn = field(repr=False)
    success: bool = False
    message: str = ""
    elapsed: float = 0.0

    def write(self, path: str | Path) -> Path:
        """Write the calibrated vessel file (TOML); return its path."""
        head = (
            f"Calibrated vessel: {self.key} solved so that the critical Fn at chi_c = "
            f"{math.degrees(self.chi_c):g} deg is {self.target_Fn:.8g}\n"
            f"(target: {self.target_source}). A CALIBRATION, not a prediction.\n"
            f"Written by ship_models.analysis.calibration.calibrate."
        )
        return dump_vessel(self.vessel, path, header=head)

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "coefficient": self.key,
            "target_Fn": self.target_Fn,
            "chi_c_deg": math.degrees(self.chi_c),
            "target_source": self.target_source,
            "value_before": self.value_before,
            "value": self.value,
            "unit": self.unit,
            "Fn_before": self.Fn_before,
            "Fn_check": self.Fn_check,
            "iterations": self.iterations,
            "rounds": self.rounds,
            "success": self.success,
            "message": self.message,
            "elapsed_s": self.elapsed,
        }


def coefficient_key(name: str, resolved: VesselData) -> str:
    """The dotted key of a coefficient given by its key or by its last part when unique.

    ``"wave_surge_scale"`` -> ``"hydrodynamics.wave_surge_scale"``. Names that are not
    a coefficient's last part are returned unchanged (:func:`calibrate` then says so).

    Raises
    ------
    ValueError
        Naming the candidates, when the short name is the last part of several keys.
    """
    if name in resolved.coefficients or name in FACTORS or name in SYSTEM_PARAMS:
        return name
    matches = sorted(k for k in resolved.coefficients if k.rsplit(".", 1)[-1] == name)
    if len(matches) > 1:
        raise ValueError(
            f"`coefficient` {name!r} is ambiguous in vessel {resolved.name!r}: "
            f"give one of {', '.join(matches)}"
        )
    return matches[0] if matches else name


def _check_key(key: str, resolved: VesselData) -> None:
    if key in FACTORS:
        raise ValueError(f"`coefficient` {key!r} is a sensitivity factor, not a vessel "
                         "coefficient; calibrate e.g. hydrodynamics.wave_surge_scale")  # fmt: skip
    if key in SYSTEM_PARAMS:
        raise ValueError(f"`coefficient` {key!r} is a wave/autopilot parameter, not a ship "
                         "coefficient; it cannot be calibrated")  # fmt: skip
    if key not in resolved.coefficients:
        import difflib

        near = difflib.get_close_matches(key, list(resolved.coefficients), n=3)
        hint = f" (did you mean {', '.join(near)}?)" if near else ""
        raise ValueError(f"`coefficient`: no coefficient {key!r} in vessel {resolved.name!r}{hint}")


def _bordered_solve(
    conn: CriticalFn,
    raw: VesselData,
    resolved: VesselData,
    key: str,
    theta0: float,
    target: float,
    template: VesselModel,
    tol: float,
    max_iter: int,
    rel_step: float,
) -> tuple[float, int, float]:
    """Newton on G(z with Fn = target; theta) = 0 for (z, theta); returns (theta, iters, |G|)."""
    prob = conn.orbit.problem
    z = np.array(conn.orbit.z, dtype=float)
    i = _fn_index(prob)

    def g_theta(p_theta: Any, zz: FloatArray, theta: float, g0: FloatArray) -> FloatArray:
        h = rel_step * abs(theta) if theta != 0 else rel_step
        p_h = prob.replace(system=model_at(raw, {key: theta + h}, resolved=resolved,
                                           model=template))  # fmt: skip
        return (np.asarray(p_h.residual(zz)) - g0) / h

    # predictor: theta0 + dtheta, z + dz/dtheta dtheta (one solve with G_z)
    theta = float(theta0)
    p0 = prob.replace(system=model_at(raw, {key: theta}, resolved=resolved, model=template))
    g0 = np.asarray(p0.residual(z), dtype=float)
    J = sp.csc_matrix(p0.jacobian(z))
    gt = g_theta(p0, z, theta, g0)
    lu = spla.splu(J)
    dz = -lu.solve(gt)
    dfn = float(dz[i])
    if dfn == 0 or not math.isfinite(dfn):
        raise ValueError(f"the critical Fn does not depend on {key!r} (dFn/dtheta = {dfn})")
    dth = (target - float(z[i])) / dfn
    z = z + dz * dth
    theta += dth
    z[i] = target
    rn = math.inf
    it = 0
    for it in range(1, max_iter + 1):
        p_t = prob.replace(system=model_at(raw, {key: theta}, resolved=resolved, model=template))
        zz = z.copy()
        zz[i] = target
        g = np.asarray(p_t.residual(zz), dtype=float)
        rn = float(np.max(np.abs(g)))
        log.info("calibration %s: iteration %d, theta = %.12g, |G| = %.3e", key, it, theta, rn)
        if rn <= tol:
            break
        Jz = sp.lil_matrix(p_t.jacobian(zz))
        Jz[:, i] = g_theta(p_t, zz, theta, g).reshape(-1, 1)
        step = spla.spsolve(sp.csc_matrix(Jz), -g)
        dtheta = float(step[i])
        step[i] = 0.0
        z = zz + step
        theta += dtheta
    else:
        raise ValueError(f"the bordered calibration solve for {key!r} did not converge in "
                         f"{max_iter} iterations (|G| = {rn:.2e})")  # fmt: skip
    return theta, it, rn


def calibrate(
    coefficient: str,
    target_Fn: float,
    chi_c: float = math.radians(10.0),
    *,
    vessel: VesselData | str | Path = "purse_seiner",
    target_source: str = PAPER_TARGET_SOURCE,
    connection: CriticalFn | None = None,
    tol: float = 1e-10,
    target_tol: float = 1e-7,
    max_iter: int = 15,
    max_rounds: int = 3,
    rel_step: float = 1e-6,
    **bvp_options: Any,
) -> Calibration:
    r"""Solve one coefficient so that the critical Fn at ``chi_c`` equals ``target_Fn``.

    Parameters
    ----------
    coefficient : str
        Dotted key of a vessel coefficient (given, assumed or estimated), e.g.
        ``"hydrodynamics.wave_surge_scale"``.
    target_Fn : float
        Target critical Fn.
    chi_c : float
        Course of the target (rad).
    vessel : VesselData, str or Path
        The vessel as in its file.
    target_source : str
        Provenance of the target (written into the calibrated entry's source).
    connection : CriticalFn, optional
        A converged connection of ``vessel`` at ``chi_c`` to start from.
    tol : float
        Max-norm of the bordered residual.
    target_tol : float
        Allowed ``|Fn_check - target_Fn|`` of the fresh check solve.
    max_iter, max_rounds : int
        Newton iterations per bordered solve; bordered solves.
    rel_step : float
        Forward-difference step of ``G_theta``, relative to ``theta``.
    **bvp_options
        Passed to ``critical_fn_bvp``.

    Returns
    -------
    Calibration
        ``success`` False (with the reason in ``message``) if the check misses
        ``target_tol`` after ``max_rounds``.

    Raises
    ------
    ValueError
        For a bad key or target, or when the bordered solve fails.
    """
    t0 = time.perf_counter()
    if not (isinstance(target_Fn, (int, float)) and math.isfinite(target_Fn) and target_Fn > 0):
        raise ValueError(f"`target_Fn` must be a positive number, got {target_Fn!r}")
    if not target_source.strip():
        raise ValueError("`target_source` must say where the target comes from")
    raw = vessel if isinstance(vessel, VesselData) else load_vessel(vessel)
    given = connection.orbit.problem.system if connection is not None else None
    base = build_vessel_model(raw, waves=given.data.wave_builder if given is not None else None)
    resolved = base.vessel
    coefficient = coefficient_key(coefficient, resolved)
    _check_key(coefficient, resolved)
    c0 = resolved.coefficients[coefficient]
    if connection is None:
        connection = critical_fn_bvp(chi_c, model=vessel_model(base), **bvp_options)
    if not connection.success:
        raise ValueError(f"the starting connection did not converge: {connection.message}")
    template: VesselModel = connection.orbit.problem.system  # rebuilt with its wave forces
    conn = connection
    theta = c0.value
    iters = 0
    check = conn
    cal_vessel = raw
    for rnd in range(1, max_rounds + 1):
        with uncompiled():  # one-off rebuilt models (see continuation.casadi_compile)
            theta, it, _ = _bordered_solve(conn, raw, resolved, coefficient, theta, target_Fn,
                                           template, tol, max_iter, rel_step)  # fmt: skip
        iters += it
        cal_vessel = _calibrated_vessel(raw, c0, coefficient, theta, target_Fn,
                                        conn.chi_c, target_source)  # fmt: skip
        model = template.rebuild(cal_vessel)
        check = critical_fn_bvp(conn.chi_c, model=model, params=conn.orbit.params.replace(
            Fn=target_Fn), guess=conn, **bvp_options)  # fmt: skip
        if not check.success:
            raise ValueError(f"the calibrated vessel's connection did not converge: "
                             f"{check.message}")  # fmt: skip
        miss = abs(check.Fn - target_Fn)
        log.info("calibration round %d: %s = %.12g, fresh Fn = %.10f (miss %.2e)",
                 rnd, coefficient, theta, check.Fn, miss)  # fmt: skip
        if miss <= target_tol:
            break
        conn = check
    miss = abs(check.Fn - target_Fn)
    ok = miss <= target_tol
    msg = (f"{coefficient}: {c0.value:.8g} -> {theta:.8g} {c0.unit}; fresh solve Fn = "
           f"{check.Fn:.9f} (target {target_Fn}, miss {miss:.1e})")  # fmt: skip
    return Calibration(coefficient, float(target_Fn), conn.chi_c, target_source, c0.value,
                       float(theta), c0.unit, connection.Fn, float(check.Fn), iters, rnd,
                       cal_vessel, check, ok, msg, time.perf_counter() - t0)  # fmt: skip


def _calibrated_vessel(
    raw: VesselData,
    before: Coefficient,
    key: str,
    theta: float,
    target: float,
    chi_c: float,
    target_source: str,
) -> VesselData:
    src = (
        f"calibrated: solved so that the critical Fn at chi_c = {math.degrees(chi_c):g} deg "
        f"equals {target:.8g} (target: {target_source}); replaces {before.value:.8g} "
        f"({before.status}: {before.source})"
    )
    entry = Coefficient(float(theta), before.unit, src, "calibrated")
    v = raw.with_overrides({key: entry})
    unc = {k: u for k, u in v.uncertainties.items() if k != key}
    meta = dict(v.meta)
    meta["calibration"] = (
        f"{key} calibrated to critical Fn = {target:.8g} at chi_c = {math.degrees(chi_c):g} "
        "deg; results of this file are calibrated, not predicted"
    )
    return dataclasses.replace(v, meta=meta, uncertainties=unc, path="")


@dataclass(frozen=True, eq=False)
class CalibratedCurves:
    """Critical Fn against the course for the predicted and the calibrated vessel.

    Attributes
    ----------
    chi_c : ndarray, shape (K,)
        Courses (rad).
    predicted, calibrated : CriticalCurve
    calibration : Calibration
    """

    chi_c: FloatArray
    predicted: CriticalCurve
    calibrated: CriticalCurve
    calibration: Calibration

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "chi_c_deg": np.degrees(self.chi_c).tolist(),
            "Fn_predicted": [None if not np.isfinite(f) else float(f) for f in self.predicted.Fn],
            "Fn_calibrated": [
                None if not np.isfinite(f) else float(f) for f in self.calibrated.Fn
            ],  # fmt: skip
            "converged_predicted": [bool(c) for c in self.predicted.converged],
            "converged_calibrated": [bool(c) for c in self.calibrated.converged],
            "status_predicted": self.predicted.status.name,
            "status_calibrated": self.calibrated.status.name,
            "calibration": self.calibration.to_json(),
        }


def calibrated_curves(
    cal: Calibration,
    chi_c_values: Sequence[float] | FloatArray,
    *,
    vessel: VesselData | str | Path = "purse_seiner",
    **curve_options: Any,
) -> CalibratedCurves:
    """The critical curve of the calibrated vessel beside the predicted one.

    Both by :func:`~ship_models.analysis.critical_curve.critical_curve` (its statuses and
    per-course convergence are kept). For the default ship calibrated on
    ``wave_surge_scale`` the calibrated curve rises steeply beyond about 25 deg and
    fresh one-course solves fail there, so points past 25 deg need checking.
    """
    raw = vessel if isinstance(vessel, VesselData) else load_vessel(vessel)
    template: VesselModel = cal.connection.orbit.problem.system
    chis = np.asarray(chi_c_values, dtype=float)
    pred = critical_curve(chis, model=template.rebuild(raw), **curve_options)
    calc = critical_curve(chis, model=template.rebuild(cal.vessel), **curve_options)
    return CalibratedCurves(chis, pred, calc, cal)


__all__ = ["PAPER_TARGET_SOURCE", "CalibratedCurves", "Calibration", "calibrate",
           "calibrated_curves"]  # fmt: skip
