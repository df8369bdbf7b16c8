r"""Sensitivity of the critical Froude number to every coefficient of the vessel.

The critical ``Fn*`` of one course is an unknown of the collocation system of the
saddle-to-shifted-saddle connection (:func:`ship_models.analysis.critical_bvp.critical_fn_bvp`):
:math:`G(z; \theta) = 0` with ``z`` the discretised orbit, the saddle, the Riccati
unknowns and ``Fn``, and :math:`\theta` any coefficient the model is built from. By
the implicit-function theorem, with :math:`G_z` the (square, non-singular at a
transversal connection) Jacobian and :math:`e_{Fn}` the unit vector of ``Fn`` in ``z``,

.. math::

    \frac{dz}{d\theta} = -G_z^{-1} G_\theta, \qquad
    \frac{dFn^*}{d\theta} = -\lambda^T G_\theta, \qquad G_z^T \lambda = e_{Fn},

so one sparse LU factorisation of :math:`G_z` and one adjoint solve give the
derivative for every coefficient at once (Cao, Li, Petzold & Serban 2003, "Adjoint
sensitivity analysis for differential-algebraic equations: the adjoint DAE system and
its numerical solution", SIAM J. Sci. Comput. 24:1076-1089, for the discrete adjoint
idea). This is the derivative of the *discrete* ``Fn*`` on the fixed mesh, which is
within the discretisation error (about 1e-7) of the continuous one.

:math:`G_\theta` is taken by central differences of the residual at the converged
``z``, with the model *rebuilt* from the vessel file at :math:`\theta \pm h`
(:func:`ship_models.estimation.build_vessel_model`), so a coefficient of the file
(given or assumed) carries the estimates that depend on it along (a total
derivative: changing ``B`` changes ``m_y``, the Inoue derivatives, the resistance...),
while an *estimated* coefficient is overridden alone (its own partial effect).
Parameters of the dynamical system (``waves.H_over_lambda``, ``waves.lambda_over_L``,
``autopilot.K_R``, ``autopilot.T_D``) are differentiated exactly by CasADi.

Intermediate quantities of the force model, which are not numbers of the file, are
reached through factors (all 1 at the base point; their elasticity is that of the
quantity):

=====================  =========================================================
``factor.R_surf``      calm-water resistance ``R(u)`` in the surge equation, the
                       propeller revolution ``n(Fn)`` held (resistance near the wave
                       celerity, where the connection runs)
``factor.T_surf``      propeller thrust ``T(u; n)`` in the surge equation, ``n`` held
``factor.R_nominal``   ``R(u_0)`` in the calm-water balance that sets ``n(Fn)``
``factor.Y_w``         amplitude of the wave sway force (Froude-Krylov + lift)
``factor.N_w``         amplitude of the wave yaw moment
``factor.K_w``         amplitude of the wave roll moment
=====================  =========================================================

and the wave surge-force amplitude is the file's own ``hydrodynamics.wave_surge_scale``
(status ``assumed``, 1 by default). ``R_surf`` and ``R_nominal`` add up to a uniform
scaling of ``R``. A factor scales its quantity along the whole orbit (the surge speed
varies along it); the ``quantity`` reported with it is its value at the wave
celerity ``u = c`` (for the default ship ``T(c; n)`` is negative: the propeller, set
for ``u_0 < c``, brakes at the celerity) or, for ``R_nominal``, at ``u_0``.

Public names
------------
:func:`critical_fn_sensitivity` — ``dFn*/dtheta`` and elasticities for all (or the
named) coefficients; :class:`Sensitivity`, :class:`SensitivityEntry`.
:func:`model_at` — the model rebuilt with some coefficients / factors changed.
:func:`resolve_at` — re-solve the connection for such a model (for checks).
:func:`uncertainty_band` — linear propagation of the vessel file's uncertainties,
with an optional sampled confirmation; :class:`UncertaintyBand`.
:func:`tornado_figure` — the sorted elasticities as a PNG.

Functions of :mod:`ship_models.analysis.critical_bvp` used: ``critical_fn_bvp``
(the connection) and the ``CriticalFn`` result type.
"""

from __future__ import annotations

import contextlib
import dataclasses
import inspect
import logging
import math
import pickle
import time
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from continuation.newton import newton
from continuation.ops import NUMPY_OPS, Ops
from continuation.settings import NewtonSettings
from continuation.typing import FloatArray

from .. import estimation as _estimation
from ..estimation import VesselModelData, build_vessel_model
from ..forces import ShipForces
from ..hydro.propeller import revolutions
from ..hydro.waves import WaveStrips
from ..umeda_4dof import Umeda4DOF
from ..vessel import SCHEMA, Coefficient, VesselData, VesselFileError, load_vessel
from .critical_bvp import critical_fn_bvp
from .critical_result import CriticalFn

log = logging.getLogger(__name__)

#: Factors on intermediate quantities of the force model (name -> description).
FACTORS: dict[str, str] = {
    "factor.R_surf": "resistance R(u) in the surge equation (n(Fn) held)",
    "factor.T_surf": "thrust T(u; n) in the surge equation (n held)",
    "factor.R_nominal": "R(u0) in the calm-water balance that sets n(Fn)",
    "factor.Y_w": "amplitude of the wave sway force Y_w",
    "factor.N_w": "amplitude of the wave yaw moment N_w",
    "factor.K_w": "amplitude of the wave roll moment K_w",
}

#: Vessel keys that are parameters of the dynamical system (exact CasADi derivative).
SYSTEM_PARAMS: dict[str, str] = {
    "waves.H_over_lambda": "H_over_lambda",
    "waves.lambda_over_L": "lambda_over_L",
    "autopilot.K_R": "K_R",
    "autopilot.T_D": "T_D",
}

#: Coefficients that set the numerical discretisation of the estimation, not the ship.
#: Their derivatives are reported (kind ``"numerical"``) but measure the local response
#: of a least-squares fit, not a convergence error: e.g. halving
#: ``resistance.knot_spacing_Fn`` moves Fn* by -5.5e-5 (R-fit error 0.56 % -> 0.24 %),
#: not by the +3.8e-3 its derivative would extrapolate.
NUMERICAL_KEYS = frozenset(
    {
        "resistance.Fn_max_fit",
        "resistance.knot_spacing_Fn",
        "propulsion.J_max_fit",
        "stability.heel_step",
    }
)

_KT = ("propulsion.K_T0", "propulsion.K_T1", "propulsion.K_T2")


# ----------------------------------------------------------------------------- factors
@dataclass(frozen=True)
class _FactoredWaves(WaveStrips):
    """Wave strips with factors on the lateral force amplitudes."""

    f_Y: float = 1.0
    f_N: float = 1.0
    f_K: float = 1.0

    def forces(self, *args: Any, **kwargs: Any) -> tuple[Any, Any, Any, Any]:
        X, Y, N, K = super().forces(*args, **kwargs)
        return X, self.f_Y * Y, self.f_N * N, self.f_K * K


@dataclass(frozen=True)
class _FactoredForces(ShipForces):
    """Ship forces with factors on R and T in the surge equation and on R(u0) in n(Fn)."""

    f_R_surf: float = 1.0
    f_T_surf: float = 1.0
    f_R_nominal: float = 1.0

    def resistance_force(self, u: Any, ops: Ops = NUMPY_OPS) -> Any:
        return self.f_R_surf * super().resistance_force(u, ops)

    def thrust_force(self, u: Any, n: Any) -> Any:
        return self.f_T_surf * super().thrust_force(u, n)

    def revolutions(self, Fn: Any, ops: Ops = NUMPY_OPS) -> Any:
        u0 = self.nominal_speed(Fn)
        return revolutions(
            u0,
            self.f_R_nominal * self.resistance.evaluate(u0, ops),
            rho=self.rho,
            D_p=self.D_p,
            w_P=self.w_P,
            t_P=self.t_P,
            k=self.kt,
            ops=ops,
        )


def _with_factors(data: VesselModelData, factors: Mapping[str, float]) -> VesselModelData:
    unknown = sorted(set(factors) - set(FACTORS))
    if unknown:
        raise ValueError(f"`factors`: unknown factor(s) {unknown}; known are {list(FACTORS)}")
    if all(float(v) == 1.0 for v in factors.values()):
        return data
    F = data.forces
    w = F.waves
    waves = _FactoredWaves(
        **{f.name: getattr(w, f.name) for f in dataclasses.fields(WaveStrips)},
        f_Y=float(factors.get("factor.Y_w", 1.0)),
        f_N=float(factors.get("factor.N_w", 1.0)),
        f_K=float(factors.get("factor.K_w", 1.0)),
    )
    kw = {f.name: getattr(F, f.name) for f in dataclasses.fields(ShipForces)}
    kw["waves"] = waves
    forces = _FactoredForces(
        **kw,
        f_R_surf=float(factors.get("factor.R_surf", 1.0)),
        f_T_surf=float(factors.get("factor.T_surf", 1.0)),
        f_R_nominal=float(factors.get("factor.R_nominal", 1.0)),
    )
    return dataclasses.replace(data, forces=forces)


# ----------------------------------------------------------------------------- rebuilding
#: Hydrostatic computations of the estimation that dominate a rebuild (the GZ curve and
#: the IS-Code topside fit: about 1.3 s of 1.5 s); most coefficients leave their inputs
#: (hull, GM, heel step) unchanged, so a rebuild at theta +- h reuses them.
_HYDROSTATIC_CALLS = ("gz_curve", "marginal_topside_height")


@contextlib.contextmanager
def reuse_hydrostatics() -> Iterator[dict[str, int]]:
    """Memoise the estimation's hydrostatic calls on their exact arguments.

    Inside the context, :func:`ship_models.estimation.build_vessel_model` calls
    ``gz_curve`` and ``marginal_topside_height`` through a cache keyed by the pickled
    arguments (the hull form with all its arrays, ``GM`` and the keywords), so a call
    with bit-identical inputs returns the earlier result and any changed input (a
    hull dimension, GM, the heel step) recomputes; likewise ``fit_resistance``, keyed
    by the resistance's values on the fit's own sample grid (what the fit depends on).
    Yields ``{"hits": .., "misses": ..}``.
    """
    stats = {"hits": 0, "misses": 0}
    saved = {name: getattr(_estimation, name) for name in _HYDROSTATIC_CALLS}

    def cached(name: str, fn: Callable[..., Any]) -> Callable[..., Any]:
        store: dict[bytes, Any] = {}

        def call(*args: Any, **kwargs: Any) -> Any:
            key = pickle.dumps((args, sorted(kwargs.items())), protocol=4)
            if key in store:
                stats["hits"] += 1
                return store[key]
            stats["misses"] += 1
            out = store[key] = fn(*args, **kwargs)
            return out

        call.__name__ = name
        return call

    fit = _estimation.fit_resistance
    n_default = inspect.signature(fit).parameters["n_samples"].default
    fits: dict[bytes, Any] = {}

    def cached_fit(fun: Callable[[FloatArray], FloatArray], u_max: float,
                   knot_spacing: float, **kwargs: Any) -> Any:  # fmt: skip
        # the fit depends on ``fun`` only through its values on its sample grid
        u = np.linspace(0.0, u_max, int(kwargs.get("n_samples", n_default)))
        R = np.asarray(fun(u), dtype=float)
        key = pickle.dumps((R, float(u_max), float(knot_spacing), sorted(kwargs.items())))
        if key in fits:
            stats["hits"] += 1
            return fits[key]
        stats["misses"] += 1
        out = fits[key] = fit(fun, u_max, knot_spacing, **kwargs)
        return out

    try:
        for name, fn in saved.items():
            setattr(_estimation, name, cached(name, fn))
        _estimation.fit_resistance = cached_fit
        yield stats
    finally:
        for name, fn in saved.items():
            setattr(_estimation, name, fn)
        _estimation.fit_resistance = fit


def _model_options(model: Any) -> dict[str, Any]:
    return {
        "saturation": bool(getattr(model, "saturation", True)),
        "saturation_order": int(getattr(model, "saturation_order", 16)),
        "wave_lift": bool(getattr(model, "wave_lift", True)),
    }


def _overridden(raw: VesselData, resolved: VesselData, changes: Mapping[str, float]) -> VesselData:
    """``raw`` with the coefficients ``changes`` (values in each entry's own unit)."""
    out: dict[str, Coefficient] = {}
    for key, val in changes.items():
        base = resolved.coefficients.get(key) or raw.coefficients.get(key)
        if base is None:
            raise ValueError(f"`{key}`: no such coefficient in vessel {raw.name!r}")
        out[key] = Coefficient(float(val), base.unit, base.source, base.status)
        if key in _KT:  # the K_T polynomial is given as a whole or not at all
            for k in _KT:
                if k not in out and k not in raw.coefficients:
                    out[k] = resolved.coefficients[k]
    return raw.with_overrides(out)


def model_at(
    vessel: VesselData,
    changes: Mapping[str, float] | None = None,
    factors: Mapping[str, float] | None = None,
    *,
    resolved: VesselData | None = None,
    options: Mapping[str, Any] | None = None,
) -> Umeda4DOF:
    """The 4-DOF model rebuilt with some coefficients and factors changed.

    Parameters
    ----------
    vessel : VesselData
        The vessel as in its file (estimates are recomputed from it).
    changes : mapping, optional
        ``{dotted key: value}`` in the unit of the key's entry; an estimated key is
        fixed at the value, a file key replaced (and the estimates that depend on it
        follow).
    factors : mapping, optional
        ``{name: value}`` of :data:`FACTORS`.
    resolved : VesselData, optional
        ``vessel`` with its estimates (gives units and values of estimated keys).
    options : mapping, optional
        ``saturation``, ``saturation_order``, ``wave_lift`` of :class:`Umeda4DOF`.
    """
    if resolved is None:
        resolved = build_vessel_model(vessel).vessel
    v = _overridden(vessel, resolved, dict(changes or {}))
    data = _with_factors(build_vessel_model(v), dict(factors or {}))
    return Umeda4DOF(data, **dict(options or {}))


# ----------------------------------------------------------------------------- results
@dataclass(frozen=True)
class SensitivityEntry:
    """Derivative of the critical Fn with respect to one coefficient.

    Attributes
    ----------
    key : str
        Dotted vessel key, or a name of :data:`FACTORS`.
    value : float
        The coefficient at the base point (its own unit; 1 for factors).
    unit, status, source : str
        As in the vessel file (``"factor"`` status for factors).
    dFn_dtheta : float
        ``dFn*/dtheta`` per unit of ``unit``.
    elasticity : float or None
        ``theta / Fn* dFn*/dtheta`` (None when ``theta = 0``).
    step : float
        Finite-difference step of ``G_theta`` (0 for exact parameter derivatives).
    method : str
        ``"central"``, ``"forward"`` (a bound next to theta) or ``"exact"``.
    kind : str
        ``"file"`` (given/assumed/measured in the file), ``"estimated"``,
        ``"system-parameter"``, ``"numerical"`` or ``"factor"``.
    quantity : float or None
        For factors: the quantity they scale at the base point (N), else None.
    sigma : float or None
        Standard uncertainty from the vessel file (its unit), if any.
    """

    key: str
    value: float
    unit: str
    status: str
    source: str
    dFn_dtheta: float
    elasticity: float | None
    step: float
    method: str
    kind: str
    quantity: float | None = None
    sigma: float | None = None

    @property
    def contribution(self) -> float | None:
        """``|dFn*/dtheta| sigma``: this coefficient's standard uncertainty of Fn*."""
        return None if self.sigma is None else abs(self.dFn_dtheta) * self.sigma

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dictionary."""
        d = dataclasses.asdict(self)
        d["contribution"] = self.contribution
        return d


@dataclass(frozen=True, eq=False)
class Sensitivity:
    """Sensitivities of the critical Fn of one course.

    Attributes
    ----------
    chi_c : float
        Course (rad).
    Fn : float
        Critical Fn at the base point.
    entries : tuple of SensitivityEntry
        Sorted by decreasing ``|elasticity|`` (zero-valued coefficients last, by
        ``|dFn/dtheta|``).
    connection : CriticalFn
        The converged connection that was differentiated.
    elapsed : float
        Wall time (s).
    """

    chi_c: float
    Fn: float
    entries: tuple[SensitivityEntry, ...]
    connection: CriticalFn = field(repr=False)
    elapsed: float = 0.0

    def entry(self, key: str) -> SensitivityEntry:
        """The entry of ``key``."""
        for e in self.entries:
            if e.key == key:
                return e
        raise KeyError(f"no sensitivity for {key!r}")

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary: the course, Fn and every entry (sorted)."""
        return {
            "chi_c_deg": math.degrees(self.chi_c),
            "Fn": self.Fn,
            "residual_norm": self.connection.residual_norm,
            "n_intervals": self.connection.orbit.mesh.n_intervals,
            "entries": [e.to_json() for e in self.entries],
            "elapsed_s": self.elapsed,
        }


def _sort_key(e: SensitivityEntry) -> tuple[int, float]:
    if e.elasticity is None:
        return (1, -abs(e.dFn_dtheta))
    return (0, -abs(e.elasticity))


# ----------------------------------------------------------------------------- core
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
                 options: Mapping[str, Any]) -> None:  # fmt: skip
        self.prob = conn.orbit.problem
        self.z = np.asarray(conn.orbit.z, dtype=float)
        self.vessel = vessel
        self.resolved = resolved
        self.options = dict(options)

    def problem_for(self, model: Umeda4DOF) -> Any:
        return self.prob.replace(system=model)

    def at(self, changes: Mapping[str, float], factors: Mapping[str, float]) -> FloatArray:
        m = model_at(self.vessel, changes, factors, resolved=self.resolved, options=self.options)
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
    from ..vessel import _si_factor  # noqa: PLC0415 (the unit table is private)

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


def _factor_quantity(key: str, model: Any, conn: CriticalFn) -> float:
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
    vals = [F.waves.forces(s, c, chi, Hl, lL)[idx] for s in xi]
    return float(np.max(np.abs(vals)))


def wave_surge_amplitude(model: Any, chi_c: float, lambda_over_L: float | None = None,
                         H_over_lambda: float | None = None) -> float:  # fmt: skip
    """Amplitude of the wave surge force ``max |X_w|`` over one wavelength (N)."""
    F = model.forces
    p = model.default_params()
    lL = float(p["lambda_over_L"]) if lambda_over_L is None else float(lambda_over_L)
    Hl = float(p["H_over_lambda"]) if H_over_lambda is None else float(H_over_lambda)
    c = float(F.celerity(lL))
    xi = np.linspace(0.0, 1.0, 256, endpoint=False)
    X = [F.waves.forces(s, c, chi_c, Hl, lL, lift=False)[0] for s in xi]
    return float(np.max(np.abs(X)))


def critical_fn_sensitivity(
    chi_c: float = math.radians(10.0),
    *,
    vessel: VesselData | str | Path = "purse_seiner",
    keys: Iterable[str] | None = None,
    connection: CriticalFn | None = None,
    model: Umeda4DOF | None = None,
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
    model : Umeda4DOF, optional
        The model of ``vessel`` (built if omitted); its options (saturation, lift)
        are kept for the rebuilt models.
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
                 connection: CriticalFn | None, model: Umeda4DOF | None, rel_step: float,
                 abs_step: float, progress: Callable[[str], None] | None,
                 bvp_options: Mapping[str, Any], stats: Mapping[str, int],
                 t0: float) -> Sensitivity:  # fmt: skip
    """Body of :func:`critical_fn_sensitivity` (inside :func:`reuse_hydrostatics`)."""
    base = build_vessel_model(raw)
    resolved = base.vessel
    m = model if model is not None else Umeda4DOF(base)
    opts = _model_options(m)
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
    res = _Residuals(conn, raw, resolved, opts)
    entries = [_entry(k, res, lam, m, conn, raw, resolved, rel_step, abs_step, progress)
               for k in key_list]  # fmt: skip
    log.info("sensitivity: %d coefficients, hydrostatics reused %d / %d calls",
             len(key_list), stats["hits"], stats["hits"] + stats["misses"])  # fmt: skip
    entries.sort(key=_sort_key)
    return Sensitivity(conn.chi_c, conn.Fn, tuple(entries), conn, time.perf_counter() - t0)


def _entry(k: str, res: _Residuals, lam: FloatArray, m: Umeda4DOF, conn: CriticalFn,
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


# ----------------------------------------------------------------------------- re-solves
def resolve_at(
    conn: CriticalFn,
    model: Umeda4DOF,
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


# ----------------------------------------------------------------------------- band
@dataclass(frozen=True, eq=False)
class UncertaintyBand:
    """Standard uncertainty of the critical Fn from the vessel file's uncertainties.

    Attributes
    ----------
    Fn : float
        Critical Fn at the nominal coefficients.
    sigma_linear : float
        ``sqrt(sum_i (dFn*/dtheta_i sigma_i)^2)`` (independent coefficients).
    contributions : tuple of (str, float)
        ``(key, |dFn*/dtheta| sigma)`` sorted by decreasing size.
    samples : ndarray, shape (S,)
        Re-solved critical Fn of the sampled coefficient sets (empty if not sampled).
    sample_linear : ndarray, shape (S,)
        The linear prediction ``Fn + sum_i dFn/dtheta_i (theta_i - theta_i0)`` for each.
    failed : int
        Samples whose connection did not converge (not in ``samples``).
    coverage : float
        Multiple of sigma for the reported band (1.96: about 95 % for a normal law).
    """

    Fn: float
    sigma_linear: float
    contributions: tuple[tuple[str, float], ...]
    samples: FloatArray = field(default_factory=lambda: np.zeros(0))
    sample_linear: FloatArray = field(default_factory=lambda: np.zeros(0))
    failed: int = 0
    coverage: float = 1.96

    @property
    def band(self) -> tuple[float, float]:
        """``Fn -+ coverage sigma_linear``."""
        return (self.Fn - self.coverage * self.sigma_linear,
                self.Fn + self.coverage * self.sigma_linear)  # fmt: skip

    @property
    def sigma_sampled(self) -> float:
        """Sample standard deviation of the re-solved Fn (nan without samples)."""
        return float(np.std(self.samples, ddof=1)) if self.samples.size > 1 else math.nan

    def contains(self, value: float) -> bool:
        """Whether ``value`` lies inside :attr:`band`."""
        lo, hi = self.band
        return lo <= value <= hi

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "Fn": self.Fn,
            "sigma_linear": self.sigma_linear,
            "coverage": self.coverage,
            "band": list(self.band),
            "contributions": [{"key": k, "sigma_Fn": v} for k, v in self.contributions],
            "n_samples": int(self.samples.size),
            "failed_samples": self.failed,
            "sigma_sampled": None if self.samples.size < 2 else self.sigma_sampled,
            "samples": self.samples.tolist(),
            "sample_linear": self.sample_linear.tolist(),
        }


def uncertainty_band(
    sens: Sensitivity,
    vessel: VesselData | str | Path = "purse_seiner",
    *,
    n_samples: int = 0,
    seed: int = 0,
    scale: float = 1.0,
    coverage: float = 1.96,
) -> UncertaintyBand:
    r"""Linear propagation of the file's standard uncertainties, optionally sampled.

    ``sigma_Fn^2 = sum_i (dFn*/dtheta_i sigma_i)^2`` over the coefficients that carry
    an uncertainty (assumed independent). With ``n_samples > 0``, that many coefficient
    sets are drawn (independent normal laws with standard deviations ``scale sigma_i``,
    redrawn where a value would leave the schema's range) and the connection is
    re-solved for each from the nominal one (full ``critical_fn_bvp``): the sampled
    spread confirms (or not) the linear one; ``scale < 1`` probes the linear regime.

    Parameters
    ----------
    sens : Sensitivity
        From :func:`critical_fn_sensitivity` for this vessel (must include the keys
        that carry uncertainties).
    vessel : VesselData, str or Path
    n_samples : int
    seed : int
    scale : float
        Factor on every sigma for the samples (the linear band is for ``scale = 1``).
    coverage : float
        Band half-width in multiples of sigma.
    """
    raw = vessel if isinstance(vessel, VesselData) else load_vessel(vessel)
    resolved = build_vessel_model(raw).vessel
    by_key = {e.key: e for e in sens.entries}
    contrib = []
    used: list[SensitivityEntry] = []
    for k in resolved.uncertainties:
        if k not in resolved.coefficients:
            continue
        if k not in by_key:
            raise ValueError(f"`sens` has no entry for {k!r}, which carries an uncertainty")
        e = by_key[k]
        s = resolved.sigma(k) or 0.0
        contrib.append((k, abs(e.dFn_dtheta) * s))
        used.append(dataclasses.replace(e, sigma=s))
    contrib.sort(key=lambda kv: -kv[1])
    sigma = math.sqrt(sum(v * v for _, v in contrib))
    samples: list[float] = []
    linear: list[float] = []
    failed = 0
    if n_samples > 0:
        rng = np.random.default_rng(seed)
        m0 = sens.connection.orbit.problem.system
        opts = _model_options(m0)
        sys_p = {}
        for _ in range(int(n_samples)):
            changes: dict[str, float] = {}
            dlin = 0.0
            for e in used:
                th = _draw(rng, e, scale)
                changes[e.key] = th
                dlin += e.dFn_dtheta * (th - e.value)
            sys_p = {SYSTEM_PARAMS[k]: changes.pop(k) for k in list(changes) if k in SYSTEM_PARAMS}
            try:
                m = model_at(raw, changes, resolved=resolved, options=opts)
                fn = resolve_at(sens.connection, m, same_discretisation=False, params=sys_p)
            except (ValueError, ArithmeticError) as exc:
                log.warning("sample failed: %s", exc)
                failed += 1
                continue
            samples.append(fn)
            linear.append(sens.Fn + dlin)
    return UncertaintyBand(sens.Fn, sigma, tuple(contrib), np.array(samples),
                           np.array(linear), failed, coverage)  # fmt: skip


def _draw(rng: np.random.Generator, e: SensitivityEntry, scale: float) -> float:
    sec, name = e.key.split(".", 1)
    spec = SCHEMA[sec][name]
    from ..vessel import _si_factor  # noqa: PLC0415

    f = _si_factor(e.key, e.unit)
    for _ in range(100):
        th = e.value + scale * (e.sigma or 0.0) * rng.standard_normal()
        v = th * f
        low_ok = v > spec.low if spec.low_open else v >= spec.low
        if low_ok and v <= spec.high:
            return float(th)
    return float(e.value)


# ----------------------------------------------------------------------------- figure
def tornado_figure(
    sens: Sensitivity,
    path: str | Path,
    *,
    top: int = 25,
    band: UncertaintyBand | None = None,
) -> Path:
    """Horizontal bars of the ``top`` largest elasticities (PNG), coloured by status.

    With ``band``, a second panel shows each coefficient's contribution to the
    standard uncertainty of Fn*.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    # numerical settings (fit ranges, knot spacing) are not properties of the ship:
    # their derivatives measure fit noise, not physics, and are left out of the figure
    rows = [e for e in sens.entries if e.elasticity is not None and e.kind != "numerical"]
    rows = rows[:top][::-1]
    colours = {"given": "#1f77b4", "assumed": "#ff7f0e", "estimated": "#2ca02c",
               "measured": "#9467bd", "calibrated": "#8c564b", "factor": "#7f7f7f"}  # fmt: skip
    ncol = 2 if band is not None else 1
    fig, axes = plt.subplots(1, ncol, figsize=(7.5 * ncol, 0.32 * len(rows) + 1.6), squeeze=False)
    ax = axes[0, 0]
    ax.barh(range(len(rows)), [e.elasticity for e in rows],
            color=[colours.get(e.status, "k") for e in rows])  # fmt: skip
    ax.set_yticks(range(len(rows)), [e.key for e in rows], fontsize=7)
    ax.axvline(0.0, color="k", lw=0.6)
    ax.set_xlabel(r"elasticity $(\theta/Fn^*)\,dFn^*/d\theta$")
    ax.set_title(f"critical Fn = {sens.Fn:.5f} at chi_c = {math.degrees(sens.chi_c):g} deg",
                 fontsize=9)  # fmt: skip
    handles = [plt.Rectangle((0, 0), 1, 1, color=c) for c in colours.values()]
    ax.legend(handles, list(colours), fontsize=7, loc="lower right")
    if band is not None:
        ax2 = axes[0, 1]
        cont = list(band.contributions[:top])[::-1]
        ax2.barh(range(len(cont)), [v for _, v in cont], color="#d62728")
        ax2.set_yticks(range(len(cont)), [k for k, _ in cont], fontsize=7)
        ax2.set_xlabel(r"$|dFn^*/d\theta|\,\sigma_\theta$")
        lo, hi = band.band
        ax2.set_title(f"sigma(Fn*) = {band.sigma_linear:.4f}; band [{lo:.4f}, {hi:.4f}]",
                      fontsize=9)  # fmt: skip
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path


def dominant(band: UncertaintyBand, n: int = 3) -> list[str]:
    """Keys of the ``n`` largest contributions to the band's width."""
    return [k for k, _ in band.contributions[:n]]


def linear_prediction(sens: Sensitivity, changes: Mapping[str, float]) -> float:
    """``Fn* + sum dFn*/dtheta (theta - theta_0)`` for ``{key: new value}``."""
    out = sens.Fn
    for k, v in changes.items():
        e = sens.entry(k)
        out += e.dFn_dtheta * (float(v) - e.value)
    return out


__all__: Sequence[str] = [
    "FACTORS",
    "NUMERICAL_KEYS",
    "SYSTEM_PARAMS",
    "Sensitivity",
    "SensitivityEntry",
    "UncertaintyBand",
    "critical_fn_sensitivity",
    "default_keys",
    "dominant",
    "linear_prediction",
    "model_at",
    "resolve_at",
    "tornado_figure",
    "uncertainty_band",
    "wave_surge_amplitude",
]
