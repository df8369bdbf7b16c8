"""``dFn*/dtheta`` by one adjoint solve of the converged connection's collocation system.

See :mod:`ship_models.analysis.sensitivity` for the method.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from continuation.casadi_compile import uncompiled
from continuation.newton import newton
from continuation.settings import NewtonSettings
from continuation.typing import FloatArray

from ...contracts import SeaState, VesselModel
from ...estimation import build_vessel_model
from ...registry import vessel_model
from ...vessel import SCHEMA, VesselData, VesselFileError, load_vessel
from ..critical_bvp import critical_fn_bvp
from ..critical_result import CriticalFn
from .factors import FACTORS, NUMERICAL_KEYS, SYSTEM_PARAMS
from .rebuild import model_at, reuse_hydrostatics
from .result import Sensitivity, SensitivityEntry, _sort_key

log = logging.getLogger(__name__)


def _kind(key: str, raw: VesselData) -> str:
    if key in FACTORS:
        return "factor"
    if key in SYSTEM_PARAMS:
        return "system-parameter"
    if key in NUMERICAL_KEYS:
        return "numerical"
    return "file" if key in raw.coefficients else "estimated"


def default_keys(resolved: VesselData) -> list[str]:
    """Every continuous coefficient of the resolved vessel plus the factors.

    Integer discretisation counts (``hull.n_stations`` ...) are left out.
    """
    out = []
    for key in resolved.coefficients:
        sec, name = key.split(".", 1)
        if SCHEMA[sec][name].integer:
            continue
        out.append(key)
    return out + list(FACTORS)


def _fn_index(prob: Any) -> int:
    sl = prob.layout.slices()["params"]
    names = list(prob.free)
    return int(sl.start + names.index("Fn"))


class _Residuals:
    """Residual of the converged connection's discretisation for rebuilt models."""

    def __init__(self, conn: CriticalFn, vessel: VesselData, resolved: VesselData,
                 model: VesselModel) -> None:  # fmt: skip
        self.prob = conn.orbit.problem
        self.z = np.asarray(conn.orbit.z, dtype=float)
        self.vessel = vessel
        self.resolved = resolved
        self.model = model  # rebuilt for each change (class, options, wave forces kept)

    def problem_for(self, model: VesselModel) -> Any:
        return self.prob.replace(system=model)

    def at(self, changes: Mapping[str, float], factors: Mapping[str, float]) -> FloatArray:
        m = model_at(self.vessel, changes, factors, resolved=self.resolved, model=self.model)
        with uncompiled():  # a one-off model: nothing of it is in the compile cache
            return np.asarray(self.problem_for(m).residual(self.z), dtype=float)

    def exact_param(self, name: str) -> FloatArray:
        pv = self.prob.params
        return np.asarray(self.prob.with_vary(name).dp(self.z, float(pv[name])), dtype=float)


def _lower_bound_hit(key: str, value: float, h: float, unit: str) -> bool:
    if key in FACTORS:
        return value - h <= 0
    sec, name = key.split(".", 1)
    spec = SCHEMA[sec][name]
    if not math.isfinite(spec.low):
        return False
    from ...vessel import _si_factor  # noqa: PLC0415 (the unit table is private)

    v_si = (value - h) * _si_factor(key, unit)
    return v_si <= spec.low if spec.low_open else v_si < spec.low


def _g_theta(
    res: _Residuals, key: str, value: float, unit: str, rel_step: float, abs_step: float
) -> tuple[FloatArray, float, str]:
    """``dG/dtheta`` at the converged z: exact, central or one-sided (3-point)."""
    if key in SYSTEM_PARAMS:
        return res.exact_param(SYSTEM_PARAMS[key]), 0.0, "exact"
    h = rel_step * abs(value) if value != 0 else abs_step

    def G(theta: float) -> FloatArray:
        if key in FACTORS:
            return res.at({}, {key: theta})
        return res.at({key: theta}, {})

    if not _lower_bound_hit(key, value, h, unit):
        try:
            gp, gm = G(value + h), G(value - h)
            return (gp - gm) / (2 * h), h, "central"
        except VesselFileError:
            pass
    g0 = np.asarray(res.prob.residual(res.z), dtype=float)
    g1, g2 = G(value + h), G(value + 2 * h)
    return (-3 * g0 + 4 * g1 - g2) / (2 * h), h, "forward"


def _factor_quantity(key: str, model: VesselModel, conn: CriticalFn) -> float:
    """The quantity a factor scales, at the base point (N or N m)."""
    F = model.forces
    pv = conn.orbit.params
    lL, Hl, chi = float(pv["lambda_over_L"]), float(pv["H_over_lambda"]), conn.chi_c
    c = float(F.celerity(lL))
    n = float(F.revolutions(conn.Fn))
    if key == "factor.R_surf":
        return float(F.resistance_force(c))
    if key == "factor.T_surf":
        return float(F.thrust_force(c, n))
    if key == "factor.R_nominal":
        return float(F.resistance_force(F.nominal_speed(conn.Fn)))
    idx = {"factor.Y_w": 1, "factor.N_w": 2, "factor.K_w": 3}[key]
    xi = np.linspace(0.0, 1.0, 64, endpoint=False)
    vals = [F.waves.forces(s, c, chi, SeaState(Hl, lL))[idx] for s in xi]
    return float(np.max(np.abs(vals)))


def wave_surge_amplitude(model: VesselModel, chi_c: float, lambda_over_L: float | None = None,
                         H_over_lambda: float | None = None) -> float:  # fmt: skip
    """Amplitude of the wave surge force ``max |X_w|`` over one wavelength (N)."""
    F = model.forces
    p = model.default_params()
    lL = float(p["lambda_over_L"]) if lambda_over_L is None else float(lambda_over_L)
    Hl = float(p["H_over_lambda"]) if H_over_lambda is None else float(H_over_lambda)
    c = float(F.celerity(lL))
    xi = np.linspace(0.0, 1.0, 256, endpoint=False)
    X = [F.waves.forces(s, c, chi_c, SeaState(Hl, lL), lift=False)[0] for s in xi]
    return float(np.max(np.abs(X)))


def critical_fn_sensitivity(
    chi_c: float = math.radians(10.0),
    *,
    vessel: VesselData | str | Path = "purse_seiner",
    keys: Iterable[str] | None = None,
    connection: CriticalFn | None = None,
    model: VesselModel | None = None,
    rel_step: float = 1e-4,
    abs_step: float = 1e-5,
    progress: Callable[[str], None] | None = None,
    **bvp_options: Any,
) -> Sensitivity:
    r"""``dFn*/dtheta`` of the critical connection for every (or the named) coefficient.

    One sparse LU of ``G_z`` and one adjoint solve ``G_z^T lambda = e_Fn``; then
    ``dFn*/dtheta = -lambda^T G_theta`` per coefficient, ``G_theta`` by central
    differences of the residual with the model rebuilt at ``theta +- h`` (``h =
    rel_step |theta|``, or ``abs_step`` at ``theta = 0``; a one-sided 3-point formula
    next to a bound of the schema), exact for the system parameters.

    Parameters
    ----------
    chi_c : float
        Course (rad).
    vessel : VesselData, str or Path
        The vessel (file values; estimates are recomputed).
    keys : iterable of str, optional
        Dotted keys and factor names; default :func:`default_keys`.
    connection : CriticalFn, optional
        A converged connection of this vessel at ``chi_c`` (else solved with
        :func:`~ship_models.analysis.critical_bvp.critical_fn_bvp`).
    model : VesselModel, optional
        The model of ``vessel`` (the 4-DOF model if omitted); the rebuilt models are
        its :meth:`~ship_models.contracts.VesselModel.rebuild` (class, options and
        wave-force model kept).
    rel_step, abs_step : float
        Finite-difference steps.
    progress : callable, optional
        Called with each key before it is evaluated.
    **bvp_options
        Passed to ``critical_fn_bvp``.

    Returns
    -------
    Sensitivity

    Raises
    ------
    ValueError
        For an unknown key, non-positive steps, or a connection that did not converge.
    """
    t0 = time.perf_counter()
    if not (math.isfinite(rel_step) and rel_step > 0 and math.isfinite(abs_step) and abs_step > 0):
        raise ValueError(f"`rel_step` and `abs_step` must be positive, got {rel_step}, {abs_step}")
    raw = vessel if isinstance(vessel, VesselData) else load_vessel(vessel)
    with reuse_hydrostatics() as stats:  # the base build seeds the cache of the rebuilds
        return _sensitivity(chi_c, raw, keys, connection, model, rel_step, abs_step,
                            progress, bvp_options, stats, t0)  # fmt: skip


def _sensitivity(chi_c: float, raw: VesselData, keys: Iterable[str] | None,
                 connection: CriticalFn | None, model: VesselModel | None, rel_step: float,
                 abs_step: float, progress: Callable[[str], None] | None,
                 bvp_options: Mapping[str, Any], stats: Mapping[str, int],
                 t0: float) -> Sensitivity:  # fmt: skip
    """Body of :func:`critical_fn_sensitivity` (inside :func:`reuse_hydrostatics`)."""
    base = build_vessel_model(raw, waves=model.data.wave_builder if model is not None else None)
    resolved = base.vessel
    m = model if model is not None else vessel_model(base)
    conn = connection or critical_fn_bvp(chi_c, model=m, **bvp_options)
    if not conn.success:
        raise ValueError(f"the connection at chi_c = {math.degrees(chi_c):g} deg did not "
                         f"converge: {conn.message}")  # fmt: skip
    key_list = list(keys) if keys is not None else default_keys(resolved)
    for k in key_list:
        if k not in FACTORS and k not in resolved.coefficients:
            raise ValueError(f"`keys`: no coefficient {k!r} in vessel {raw.name!r} "
                             f"(nor a factor {list(FACTORS)})")  # fmt: skip
    prob, z = conn.orbit.problem, np.asarray(conn.orbit.z, dtype=float)
    J = sp.csc_matrix(prob.jacobian(z))
    lu = spla.splu(J)
    e = np.zeros(J.shape[0])
    e[_fn_index(prob)] = 1.0
    lam = lu.solve(e, trans="T")
    res = _Residuals(conn, raw, resolved, m)
    entries = [_entry(k, res, lam, m, conn, raw, resolved, rel_step, abs_step, progress)
               for k in key_list]  # fmt: skip
    log.info("sensitivity: %d coefficients, hydrostatics reused %d / %d calls",
             len(key_list), stats["hits"], stats["hits"] + stats["misses"])  # fmt: skip
    entries.sort(key=_sort_key)
    return Sensitivity(conn.chi_c, conn.Fn, tuple(entries), conn, time.perf_counter() - t0)


def _entry(k: str, res: _Residuals, lam: FloatArray, m: VesselModel, conn: CriticalFn,
           raw: VesselData, resolved: VesselData, rel_step: float, abs_step: float,
           progress: Callable[[str], None] | None) -> SensitivityEntry:  # fmt: skip
    """The sensitivity entry of one key (see :func:`critical_fn_sensitivity`)."""
    if progress is not None:
        progress(k)
    if k in FACTORS:
        value, unit, status, source = 1.0, "-", "factor", FACTORS[k]
    else:
        c = resolved.coefficients[k]
        value, unit, status, source = c.value, c.unit, c.status, c.source
    g, h, method = _g_theta(res, k, value, unit, rel_step, abs_step)
    d = -float(lam @ g)
    el = value / conn.Fn * d if value != 0 else None
    sig = resolved.sigma(k) if k not in FACTORS and k in resolved.uncertainties else None
    q = _factor_quantity(k, m, conn) if k in FACTORS else None
    return SensitivityEntry(k, value, unit, status, source, d, el, h, method,
                            _kind(k, raw), q, sig)  # fmt: skip


def resolve_at(
    conn: CriticalFn,
    model: VesselModel,
    *,
    same_discretisation: bool = True,
    params: Mapping[str, float] | None = None,
    tol: float = 1e-11,
) -> float:
    """Critical Fn of a changed model, re-solved from ``conn``.

    ``same_discretisation=True``: Newton on the same collocation system (mesh, phase
    reference, projection bases) with the new model — the discrete ``Fn*`` that the
    implicit derivative differentiates. ``False``: a full
    :func:`~ship_models.analysis.critical_bvp.critical_fn_bvp` solve from ``conn``.
    ``params`` changes system parameters (``K_R`` ...).

    Raises
    ------
    ValueError
        If the re-solve does not converge.
    """
    prob = conn.orbit.problem
    if same_discretisation:
        new = prob.replace(system=model)
        if params:
            new = new.replace(params=new.params.replace(**params))
        r = newton(new.residual, new.jacobian, np.asarray(conn.orbit.z, dtype=float),
                   NewtonSettings(tol=tol, step_tol=1e-12, max_iter=30, damping=True))  # fmt: skip
        if not r.converged:
            raise ValueError(f"re-solve did not converge: {r.message}")
        return float(r.z[_fn_index(prob)])
    p = conn.orbit.params
    if params:
        p = p.replace(**params)
    out = critical_fn_bvp(conn.chi_c, model=model, params=p, guess=conn, tol=tol)
    if not out.success:
        raise ValueError(f"re-solve did not converge: {out.message}")
    return float(out.Fn)
