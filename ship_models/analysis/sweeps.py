r"""Ship sweeps on the generic sweep layer (:mod:`continuation.sweep`): Figs. 16/22/23, surface.

Every study here is many independent solves; each solve is one task ``run_task(key)``
with a JSON key that names everything it depends on (vessel, wave, controls,
tolerances), so tasks run on local processes, a Dask ``LocalCluster`` or a remote
scheduler, are checkpointed as they finish, and an interrupted sweep resumes
(:func:`continuation.sweep.run_sweep`). The context of every task is the content of
the vessel file (:func:`vessel_context`): editing it invalidates the checkpoints.

Tasks (``key["task"]``):

- ``"boundary"`` -- critical nominal Froude number of one sudden-change experiment by
  bisection of its outcome (:func:`~ship_models.analysis.sudden_change.sudden_change_boundary`)
  for one initial position :math:`(\xi_G/\lambda)_0` and new course ``chi_c``
  (Umeda 1999, Figs. 16, 22 boundaries; Fig. 23 squares).
- ``"outcome"`` -- the outcome of one sudden change at one ``(Fn, xi_0)`` (the maps
  of Figs. 16, 22; :func:`~ship_models.analysis.sudden_change.sudden_change`).
- ``"line"`` -- the critical Fn of the heteroclinic connection over wave steepness
  :math:`H/\lambda` at one wavelength :math:`\lambda/L` and course (:func:`critical_line`):
  one row of the critical surface :math:`Fn^*(H/\lambda, \lambda/L)`.
- ``"surge-line"`` -- the same for the uncoupled surge model (``chi_c = 0``,
  :func:`surge_threshold`): the surge-only threshold beside the surface.

Sweeps (the calling side): :func:`boundary_sweep`, :func:`courses_sweep`,
:func:`surface_sweep`.

Notes
-----
The connection is the capture threshold only where the fate of the upslope branch
switches at it. For the purse seiner at ``chi_c = 10 deg``, ``lambda/L = 1.5`` this was
checked by bisection by simulation at ``H/lambda = 0.08, 0.1`` (agreement to 1e-7),
but at ``H/lambda = 0.06`` the connection (Fn = 0.358836, converged under mesh halving
and longer T; the simulated branch passes within 1e-3 of the shifted saddle there)
does not change the fate -- periodic on both sides -- and the fate switches at
Fn = 0.36030 instead, with the branch nowhere near the shifted saddle: another global
bifurcation takes over in gentler waves. :func:`surface_sweep` therefore re-checks a
sample of points by bisection (``check``) and reports ``agrees`` for each.

Ship functions called (for re-pointing after the reorganisation of
``ship_models.analysis``): ``sudden_change.periodic_orbit``,
``sudden_change.follow_orbit``, ``sudden_change.sudden_change``,
``sudden_change.sudden_change_boundary``, ``fixed_points.fixed_points``,
``critical_bvp.critical_fn_bvp``, ``critical_curve.critical_curve``,
``critical_bisection.upslope_bisection``,
``SurgeModel.fixed_points`` / ``surge_force``, ``registry.get_model`` /
``get_vessel_data``; engine: ``continuation.bvp.continue_connection``,
``continuation.newton.newton``, ``continuation.dynamics.simulate``.
"""

from __future__ import annotations

import hashlib
import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.optimize as so

from continuation.dynamics import SimEvent, simulate
from continuation.errors import ContinuationError
from continuation.newton import newton
from continuation.params import Params
from continuation.settings import ContinuationSettings, NewtonSettings
from continuation.status import Status
from continuation.sweep import SweepResult, file_digest, run_sweep
from continuation.typing import FloatArray

log = logging.getLogger(__name__)

#: Sudden-change Fn offsets from the heteroclinic Fn: the first bisection bracket, and a
#: wider one tried when the first does not bracket the switch (as the Fig. 16-23 study).
BRACKET_OFFSETS = ((-0.004, 0.003), (-0.03, 0.01))
#: Fn offsets of the outcome map from the heteroclinic Fn (the Fig. 16 study's grid).
MAP_OFFSETS = (-0.004, -0.0015, -0.0005, 0.0005, 0.003)

_MODELS: dict[str, Any] = {}
_ORBITS: dict[str, Any] = {}


# ----------------------------------------------------------------------- vessel, model
def vessel_context(vessel: str) -> str:
    """Content hash of the vessel file behind a name or path (the tasks' context).

    Raises
    ------
    ValueError
        For an unknown vessel.
    """
    from ship_models import get_vessel_data

    data = get_vessel_data(vessel)
    path = getattr(data.vessel, "path", None)
    if path:
        return file_digest(path)
    return hashlib.sha256(repr(data.vessel).encode()).hexdigest()  # pragma: no cover


def _model(vessel: str) -> Any:
    """The 4-DOF model of a vessel, built once per process."""
    if vessel not in _MODELS:
        from ship_models import get_model

        _MODELS[vessel] = get_model(vessel)
    return _MODELS[vessel]


def _surge(vessel: str) -> Any:
    key = f"surge:{vessel}"
    if key not in _MODELS:
        from ship_models.surge import SurgeModel

        _MODELS[key] = SurgeModel(_model(vessel).data)
    return _MODELS[key]


def _params(m: Any, key: dict[str, Any], **changes: float) -> Params:
    base = m.default_params()
    wave = {k: float(key[k]) for k in ("H_over_lambda", "lambda_over_L") if k in key}
    return base.replace(**wave, **changes)


def _orbit(key: dict[str, Any]) -> Any:
    """The old periodic orbit of a sudden change, computed once per process.

    ``key["Fn_from"], key["chi_c_from_deg"]``; with ``key["follow_steps"] > 0`` it is
    followed from the (0.1, 0 deg) orbit in that many steps
    (:func:`~ship_models.analysis.sudden_change.follow_orbit`), as for Fig. 22.
    """
    from .sudden_change import follow_orbit, periodic_orbit

    m = _model(key["vessel"])
    p_from = _params(m, key, Fn=float(key["Fn_from"]), chi_c=math.radians(key["chi_c_from_deg"]))
    steps = int(key.get("follow_steps", 0))
    tag = repr((key["vessel"], tuple(p_from.values), steps))
    if tag not in _ORBITS:
        if steps > 0:
            first = periodic_orbit(m, p_from.replace(Fn=0.1, chi_c=0.0), throw=True)
            orb = follow_orbit(first, p_from, steps=steps)
            if not orb.success:
                raise ContinuationError(f"no periodic orbit at the old controls: {orb.message}")
        else:
            orb = periodic_orbit(m, p_from, throw=True)
        _ORBITS[tag] = orb
    return _ORBITS[tag]


def _finite(v: float) -> float | None:
    return float(v) if math.isfinite(v) else None


# ----------------------------------------------------------------------- tasks
def _boundary(key: dict[str, Any]) -> dict[str, Any]:
    from .sudden_change import sudden_change_boundary

    m = _model(key["vessel"])
    orb = _orbit(key)
    chi = math.radians(float(key["chi_c_deg"]))
    b = None
    for lo, hi in key["Fn_brackets"]:
        b = sudden_change_boundary(
            m, None, chi, float(key["xi_0"]), (float(lo), float(hi)), float(key["tol"]),
            orbit=orb, t_max=float(key.get("t_max", 600.0)),
        )  # fmt: skip
        if b.status is not Status.NO_BRACKET:
            break
    assert b is not None
    if b.status is Status.INTERRUPTED:
        raise KeyboardInterrupt
    ok = b.success
    return {
        "Fn": b.Fn if ok else None,
        "Fn_lower": b.bracket[0],
        "Fn_upper": b.bracket[1],
        "outcome_lower": b.outcomes[0],
        "outcome_upper": b.outcomes[1],
        "n_runs": b.n_runs,
        "status": b.status.name,
        "message": b.message,
    }


def _outcome(key: dict[str, Any]) -> dict[str, Any]:
    from .sudden_change import sudden_change

    m = _model(key["vessel"])
    orb = _orbit(key)
    pt = orb.params.replace(Fn=float(key["Fn"]), chi_c=math.radians(float(key["chi_c_deg"])))
    r = sudden_change(m, None, pt, float(key["xi_0"]), orbit=orb, t_max=float(key["t_max"]))
    if r.fate.status is Status.INTERRUPTED:
        raise KeyboardInterrupt
    return {"outcome": r.outcome, "t_decided_s": _finite(r.t)}


def _line(key: dict[str, Any]) -> dict[str, Any]:
    m = _model(key["vessel"])
    line = critical_line(
        m,
        math.radians(float(key["chi_c_deg"])),
        float(key["lambda_over_L"]),
        key["H_over_lambda"],
        tol=float(key.get("tol", 1e-9)),
    )
    return line.to_json()


def _surge_line(key: dict[str, Any]) -> dict[str, Any]:
    s = _surge(key["vessel"])
    out = []
    for h in key["H_over_lambda"]:
        try:
            t = surge_threshold(s, float(h), float(key["lambda_over_L"]), tol=float(key["tol"]))
        except (ContinuationError, ValueError) as exc:
            t = SurgeThreshold(math.nan, (math.nan, math.nan), Status.UNDECIDED, str(exc))
        out.append(t)
    return {
        "H_over_lambda": [float(h) for h in key["H_over_lambda"]],
        "Fn": [_finite(t.Fn) for t in out],
        "status": [t.status.name for t in out],
        "reason": [t.message for t in out],
    }


def _bisect(key: dict[str, Any]) -> dict[str, Any]:
    from .critical_bisection import upslope_bisection as critical_fn_bisection

    m = _model(key["vessel"])
    b = critical_fn_bisection(
        math.radians(float(key["chi_c_deg"])), model=m, params=_params(m, key),
        bracket=(float(key["Fn_bracket"][0]), float(key["Fn_bracket"][1])),
        tol=float(key["tol"]), t_max=float(key.get("t_max", 600.0)),
    )  # fmt: skip
    if b.status is Status.INTERRUPTED:
        raise KeyboardInterrupt
    return {
        "Fn": b.Fn if b.success else None,
        "Fn_lower": b.bracket[0],
        "Fn_upper": b.bracket[1],
        "n_runs": b.n_evaluations,
        "status": b.status.name,
        "message": b.message,
    }


_TASKS = {
    "boundary": _boundary,
    "outcome": _outcome,
    "line": _line,
    "surge-line": _surge_line,
    "bisect": _bisect,
}


def run_task(key: dict[str, Any]) -> dict[str, Any]:
    """Run one ship task (``key["task"]``: boundary, outcome, line, surge-line, bisect).

    The function handed to :func:`continuation.sweep.run_sweep`: module level, JSON in,
    JSON out (``None`` for values that do not exist), no timings (so the table does
    not depend on the machine's load).

    Raises
    ------
    ValueError
        For an unknown task.
    """
    fn = _TASKS.get(key.get("task"))
    if fn is None:
        raise ValueError(f"`task` must be one of {', '.join(_TASKS)}, got {key.get('task')!r}")
    return fn(key)


# ----------------------------------------------------------------------- surge threshold
@dataclass(frozen=True)
class SurgeThreshold:
    """Critical Fn of the uncoupled surge model (``chi_c = 0``) at one wave.

    Attributes
    ----------
    Fn : float
        Where the upslope unstable manifold of the crest saddle lands on the crest
        saddle one wavelength back (nan if there is none).
    Fn_range : (float, float)
        Nominal Froude numbers with surf-riding fixed points (nan if none).
    status : Status
        ``SUCCESS``, or ``NO_BRACKET`` (no surf-riding, or the branch's fate does not
        change in ``Fn_range``).
    message : str
    n_runs : int
        Simulations of the manifold.
    """

    Fn: float
    Fn_range: tuple[float, float]
    status: Status
    message: str
    n_runs: int = 0

    @property
    def success(self) -> bool:
        """Converged to the tolerance."""
        return self.status is Status.SUCCESS


def surf_riding_range(
    surge: Any, H_over_lambda: float, lambda_over_L: float
) -> tuple[float, float]:
    r"""Nominal Froude numbers at which surf-riding fixed points exist (surge model).

    Fixed points have ``u = c`` and :math:`T(c; n(Fn)) - R(c) + X_w(\xi) = 0`; they exist
    while :math:`-\max X_w \le T - R \le -\min X_w` (:math:`T - R` increases with Fn).

    Returns
    -------
    (float, float)
        ``(Fn_a, Fn_b)``, ``(nan, nan)`` if none in ``0.01 <= Fn <= 2`` (``Fn_a = 0.01``
        when they exist already there).
    """
    F = surge.forces
    p = surge.params(Fn=0.3, H_over_lambda=H_over_lambda, lambda_over_L=lambda_over_L)
    c = surge.celerity(p)
    grid = np.linspace(0.0, 1.0, 801)

    def net(Fn: float) -> float:
        return float(F.thrust_force(c, F.revolutions(Fn)) - F.resistance_force(c))

    xw = surge.surge_force(grid, c, p) - net(0.3)
    hi, lo = float(np.max(xw)), float(np.min(xw))
    fns = np.linspace(0.01, 2.0, 200)
    vals = np.array([net(f) for f in fns])
    out = []
    for target in (-hi, -lo):
        g = vals - target
        k = np.nonzero(np.sign(g[:-1]) != np.sign(g[1:]))[0]
        if k.size:
            i = int(k[0])
            out.append(so.brentq(lambda f, t=target: net(f) - t, fns[i], fns[i + 1], xtol=1e-12))
        elif g[0] > 0:  # already past this edge at the smallest Fn scanned
            out.append(float(fns[0]))
        else:
            out.append(math.nan)
    if not (math.isfinite(out[0]) and math.isfinite(out[1])):
        return (math.nan, math.nan)
    return (out[0], out[1])


def _surge_miss(surge: Any, pv: FloatArray, t_max: float) -> float:
    """Signed miss of the upslope branch at the next crest saddle (surge model).

    From the crest saddle ``x_s + eps v_u`` (``xi_G`` decreasing): if the branch reaches
    ``xi_s - 1`` (the shifted saddle's position) it returns ``(u - c)/c < 0`` there
    (passes the crest: periodic); if ``u`` climbs back to ``c`` first (turns back down
    the slope: surf-riding), ``xi_turn - (xi_s - 1) > 0``. Both tend to 0 at the
    connection, so the function is continuous and changes sign at the critical Fn.
    """
    fps = [fp for fp in surge.fixed_points(pv) if fp.kind == "saddle"]
    if not fps:
        raise ContinuationError("no crest saddle")
    xs = fps[0].x
    c = surge.celerity(pv)
    w, V = np.linalg.eig(surge.jacobian(xs, pv))
    k = int(np.argmax(w.real))
    v = np.real(V[:, k])
    v = v / np.linalg.norm(v / np.array([1.0, c]))
    if v[0] > 0:
        v = -v
    x0 = xs + 1e-7 * v
    xi_end = float(xs[0]) - 1.0
    passed = SimEvent("passed", lambda t, x: x[..., 0] - xi_end, True, -1, vectorized=True)
    back = SimEvent("back", lambda t, x: x[..., 1] - c, True, 1, vectorized=True)
    tr = simulate(
        surge, x0, pv, (0.0, t_max), events=[passed, back], rtol=1e-11, atol=1e-12, dt=1.0
    )
    if tr.status is Status.INTERRUPTED:
        raise KeyboardInterrupt
    xe = np.asarray(tr.x[-1], dtype=float)
    if tr.terminal_event == "passed":
        return (float(xe[1]) - c) / c
    if tr.terminal_event == "back":
        return float(xe[0]) - xi_end
    # lingering at the shifted saddle: as close to the connection as it gets
    return (float(xe[1]) - c) / c if xe[0] <= xi_end else float(xe[0]) - xi_end


def surge_threshold(
    surge: Any,
    H_over_lambda: float,
    lambda_over_L: float,
    *,
    tol: float = 1e-8,
    n_scan: int = 9,
    t_max: float = 3000.0,
) -> SurgeThreshold:
    r"""Critical Fn of the surge model: root of the signed miss of its upslope branch.

    The 2-D counterpart of the heteroclinic connection (an independent method: shooting
    + Brent instead of collocation): :func:`surf_riding_range` bounds Fn; the signed
    miss (:func:`_surge_miss`) is evaluated at ``n_scan`` interior points and the first
    sign change refined by :func:`scipy.optimize.brentq` to ``tol`` in Fn.

    Returns
    -------
    SurgeThreshold
        ``NO_BRACKET`` with the reason where there is no surf-riding at this wave or the
        branch's fate does not change.
    """
    if not (math.isfinite(H_over_lambda) and H_over_lambda > 0):
        raise ValueError(f"`H_over_lambda` must be positive, got {H_over_lambda!r}")
    if not (math.isfinite(lambda_over_L) and lambda_over_L > 0):
        raise ValueError(f"`lambda_over_L` must be positive, got {lambda_over_L!r}")
    fa, fb = surf_riding_range(surge, H_over_lambda, lambda_over_L)
    if not math.isfinite(fa):
        return SurgeThreshold(
            math.nan, (fa, fb), Status.NO_BRACKET,
            f"no surf-riding fixed points at H/lambda = {H_over_lambda:g}, "
            f"lambda/L = {lambda_over_L:g}",
        )  # fmt: skip
    n = 0

    def g(Fn: float) -> float:
        nonlocal n
        n += 1
        pv = surge.params(Fn=Fn, H_over_lambda=H_over_lambda, lambda_over_L=lambda_over_L)
        return _surge_miss(surge, np.asarray(pv.values, dtype=float), t_max)

    w = fb - fa
    # dense near the birth of the fixed points, where the connection ends
    fns = fa + w * np.concatenate([[1e-4, 1e-3, 1e-2], np.linspace(0.02, 0.98, n_scan)])
    vals = []
    for f in fns:
        try:
            vals.append(g(float(f)))
        except ContinuationError as exc:  # e.g. fixed points too close to be resolved
            log.info("surge threshold: no miss at Fn = %.6f: %s", f, exc)
            vals.append(math.nan)
    ok = [i for i, v in enumerate(vals) if math.isfinite(v)]
    for i, k in zip(ok[:-1], ok[1:], strict=True):
        if vals[i] < 0 <= vals[k]:
            try:
                fn = so.brentq(g, fns[i], fns[k], xtol=tol, rtol=4 * np.finfo(float).eps)
            except ContinuationError as exc:
                return SurgeThreshold(
                    math.nan, (fa, fb), Status.UNDECIDED,
                    f"Brent's method failed in [{fns[i]:.6f}, {fns[k]:.6f}]: {exc}", n,
                )  # fmt: skip
            return SurgeThreshold(fn, (fa, fb), Status.SUCCESS, f"brentq, {n} simulations", n)
    if not ok:
        return SurgeThreshold(
            math.nan, (fa, fb), Status.UNDECIDED, "no crest saddle resolved at any scanned Fn", n
        )
    if all(vals[i] >= 0 for i in ok):
        msg = (
            f"no connection: the upslope branch turns back to surf-riding already at "
            f"Fn = {fns[ok[0]]:.6f}, just above the birth of the surf-riding points "
            f"(Fn = {fa:.6f}; the threshold there is that saddle-node)"
        )
    elif all(vals[i] < 0 for i in ok):
        msg = (
            f"no connection: the upslope branch passes the next crest at every Fn with "
            f"surf-riding points ({fa:.5f} < Fn < {fb:.5f})"
        )
    else:
        msg = "the miss changes sign only from captured to periodic: no threshold found"
    return SurgeThreshold(math.nan, (fa, fb), Status.NO_BRACKET, msg, n)


# ----------------------------------------------------------------------- critical line
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
    model: Any,
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
    model : Umeda4DOF
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

    from .critical_bvp import critical_fn_bvp

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


# ----------------------------------------------------------------------- sweeps
_RUN_OPTIONS = ("store", "backend", "workers", "scheduler", "progress", "retry_failed")


def _vessel_ref(vessel: Any) -> str:
    """A vessel name as given; a vessel file as its absolute path (workers elsewhere)."""
    from pathlib import Path

    if not isinstance(vessel, str) or not vessel:
        raise ValueError(f"`vessel` must be a vessel name or a .toml path, got {vessel!r}")
    p = Path(vessel)
    return str(p.resolve()) if p.suffix == ".toml" or p.is_file() else vessel


def _run(keys: list[dict[str, Any]], vessel: str, desc: str, run: dict[str, Any]) -> SweepResult:
    bad = set(run) - set(_RUN_OPTIONS)
    if bad:
        raise ValueError(f"unknown sweep option(s): {', '.join(sorted(bad))}")
    return run_sweep(run_task, keys, context=vessel_context(vessel), desc=desc, **run)


def _wave(m: Any, H_over_lambda: float | None, lambda_over_L: float | None) -> dict[str, float]:
    p = m.default_params()
    return {
        "H_over_lambda": float(p["H_over_lambda"] if H_over_lambda is None else H_over_lambda),
        "lambda_over_L": float(p["lambda_over_L"] if lambda_over_L is None else lambda_over_L),
    }


@dataclass(frozen=True, eq=False)
class BoundarySweep:
    """Critical sudden-change Fn per initial position (and the outcome map), Figs. 16/22.

    Attributes
    ----------
    chi_c_deg : float
        New course.
    xi_0 : ndarray, shape (n,)
    Fn : ndarray, shape (n,)
        Critical Fn per position (nan where the bisection did not succeed).
    heteroclinic_Fn : float
        Critical Fn of the connection at ``chi_c`` (collocation).
    boundaries : SweepResult
    outcomes : SweepResult or None
        The outcome map (``Fn x xi_0``).
    bvp : CapsizeBoundary or None
        With ``method="bvp"``: the boundary as a landing BVP at the bisected positions
        (:func:`~ship_models.analysis.capsize_boundary.capsizing_boundary_bvp`), beside
        the bisection brackets.
    """

    chi_c_deg: float
    xi_0: FloatArray
    Fn: FloatArray
    heteroclinic_Fn: float
    boundaries: SweepResult
    outcomes: SweepResult | None
    bvp: Any = None

    @property
    def complete(self) -> bool:
        """Every task finished (none interrupted)."""
        parts = [self.boundaries] + ([self.outcomes] if self.outcomes is not None else [])
        return all(p.status is Status.SUCCESS for p in parts)


def _sudden_keys(
    vessel: str, initial: tuple[float, float], wave: dict[str, float], follow_steps: int
) -> dict[str, Any]:
    return {
        "vessel": vessel,
        "Fn_from": float(initial[0]),
        "chi_c_from_deg": float(initial[1]),
        "follow_steps": int(follow_steps),
        **wave,
    }


def boundary_sweep(
    vessel: str = "purse_seiner",
    chi_c_deg: float = 10.0,
    *,
    initial: tuple[float, float] = (0.1, 0.0),
    positions: int | Sequence[float] = 21,
    tol: float = 2e-4,
    Fn_bracket: tuple[float, float] | None = None,
    map_offsets: Sequence[float] | None = MAP_OFFSETS,
    follow_steps: int = 0,
    t_max: float = 600.0,
    H_over_lambda: float | None = None,
    lambda_over_L: float | None = None,
    method: str = "bisection",
    **run: Any,
) -> BoundarySweep:
    r"""Figs. 16/22: critical Fn of the sudden change per initial position, by bisection.

    The old controls ``initial = (Fn, chi_c_deg)`` give the periodic orbit; the new
    course is ``chi_c_deg``; one bisection task per initial position
    :math:`(\xi_G/\lambda)_0` (``positions`` equally spaced in ``[0, 1)`` or the values
    given), in ``Fn_bracket`` (default the heteroclinic Fn + :data:`BRACKET_OFFSETS`),
    and one outcome task per ``(heteroclinic Fn + offset, xi_0)`` of the map.

    Parameters
    ----------
    vessel : str
        Name or path of the vessel file.
    method : {"bisection", "bvp"}
        ``"bvp"``: also solve the boundary as a landing BVP at every bisected position
        (in this process, after the sweep; its bracket is the reference).
    run
        ``store``, ``backend``, ``workers``, ``scheduler``, ``progress``,
        ``retry_failed`` of :func:`continuation.sweep.run_sweep`.

    Returns
    -------
    BoundarySweep
    """
    if method not in ("bisection", "bvp"):
        raise ValueError(f"`method` must be 'bisection' or 'bvp', got {method!r}")
    vessel = _vessel_ref(vessel)
    from .critical_bvp import critical_fn_bvp

    if isinstance(positions, int) and not isinstance(positions, bool):
        if positions < 1:
            raise ValueError(f"`positions` must be a positive integer, got {positions!r}")
        xs = np.arange(positions) / positions
    else:
        xs = np.asarray(positions, dtype=float).reshape(-1)
        if xs.size == 0 or not np.all(np.isfinite(xs)):
            raise ValueError(f"`positions` must be finite numbers, got {positions!r}")
    m = _model(vessel)
    wave = _wave(m, H_over_lambda, lambda_over_L)
    chi = math.radians(float(chi_c_deg))
    het = critical_fn_bvp(chi, model=m, params=m.default_params().replace(**wave))
    fh = het.Fn if het.success else math.nan
    if Fn_bracket is not None:
        brackets = [[float(Fn_bracket[0]), float(Fn_bracket[1])]]
    elif het.success:
        brackets = [[fh + a, fh + b] for a, b in BRACKET_OFFSETS]
    else:
        raise ValueError(
            f"`Fn_bracket` must be given: no heteroclinic connection at {chi_c_deg:g} deg "
            f"({het.message})"
        )
    common = _sudden_keys(vessel, initial, wave, follow_steps)
    keys = [
        {"task": "boundary", "xi_0": float(x), "chi_c_deg": float(chi_c_deg),
         "Fn_brackets": brackets, "tol": float(tol), "t_max": float(t_max), **common}
        for x in xs
    ]  # fmt: skip
    b = _run(keys, vessel, "boundary", run)
    outcomes = None
    if (
        map_offsets is not None
        and len(map_offsets)
        and het.success
        and b.status is not Status.INTERRUPTED  # an interrupted study stops here
    ):
        mk = [
            {"task": "outcome", "Fn": fh + float(d), "xi_0": float(x),
             "chi_c_deg": float(chi_c_deg), "t_max": float(t_max), **common}
            for d in map_offsets for x in xs
        ]  # fmt: skip
        outcomes = _run(mk, vessel, "outcome map", run)
    by_xi = {r.key["xi_0"]: r for r in b.records}
    Fn = np.array(
        [
            by_xi[float(x)].value["Fn"]
            if float(x) in by_xi and by_xi[float(x)].done and by_xi[float(x)].value["Fn"]
            else math.nan
            for x in xs
        ],
        dtype=float,
    )
    bvp = None
    if method == "bvp" and b.status is not Status.INTERRUPTED:
        bvp = _bvp_of_sweep(m, chi, b, {"vessel": vessel, **common})
    return BoundarySweep(float(chi_c_deg), xs, Fn, fh, b, outcomes, bvp)


def _bvp_of_sweep(m: Any, chi: float, b: SweepResult, key: dict[str, Any]) -> Any:
    """The landing BVP at the positions the bisection tasks bracketed."""
    from .capsize_boundary import capsizing_boundary_bvp
    from .sudden_change import SuddenChangeBoundary

    bis = []
    for r in b.records:
        v = r.value if r.done else None
        if v and v.get("status") == "SUCCESS":
            lo, hi = float(v["Fn_lower"]), float(v["Fn_upper"])
            bis.append(SuddenChangeBoundary(
                0.5 * (lo + hi), (lo, hi), (v["outcome_lower"], v["outcome_upper"]), chi,
                float(r.key["xi_0"]), int(v["n_runs"]), Status.SUCCESS, v["message"],
            ))  # fmt: skip
    if not bis:
        return None
    xs = [x.xi_0 for x in sorted(bis, key=lambda x: x.xi_0)]
    return capsizing_boundary_bvp(m, None, chi, xs, orbit=_orbit(key), bisections=bis)


@dataclass(frozen=True, eq=False)
class CoursesSweep:
    """Fig. 23 squares: critical sudden-change Fn per course, beside the connection.

    Attributes
    ----------
    chi_c_deg : ndarray, shape (n,)
    Fn : ndarray, shape (n,)
        Sudden-change boundary (nan where not found).
    heteroclinic_Fn : ndarray, shape (n,)
        Critical Fn of the connection (:func:`~ship_models.analysis.critical_curve.critical_curve`).
    xi_0 : float
    boundaries : SweepResult
    """

    chi_c_deg: FloatArray
    Fn: FloatArray
    heteroclinic_Fn: FloatArray
    xi_0: float
    boundaries: SweepResult


def courses_sweep(
    vessel: str = "purse_seiner",
    chi_c_deg: Sequence[float] = (0.0, 10.0, 20.0, 30.0),
    *,
    initial: tuple[float, float] = (0.1, 0.0),
    xi_0: float = 0.5,
    tol: float = 2e-4,
    t_max: float = 600.0,
    H_over_lambda: float | None = None,
    lambda_over_L: float | None = None,
    **run: Any,
) -> CoursesSweep:
    """Fig. 23 squares: one sudden-change bisection task per course ``chi_c_deg``.

    Brackets: the connection's critical Fn at each course (one continuation in
    ``chi_c``, in this process) plus :data:`BRACKET_OFFSETS`.

    Returns
    -------
    CoursesSweep
    """
    vessel = _vessel_ref(vessel)
    from .critical_curve import critical_curve

    degs = np.asarray(chi_c_deg, dtype=float).reshape(-1)
    if degs.size == 0 or not np.all(np.isfinite(degs)) or np.any(np.abs(degs) >= 90):
        raise ValueError(f"`chi_c_deg` must be courses in (-90, 90) deg, got {chi_c_deg!r}")
    m = _model(vessel)
    wave = _wave(m, H_over_lambda, lambda_over_L)
    curve = critical_curve(np.radians(degs), model=m, params=m.default_params().replace(**wave))
    common = _sudden_keys(vessel, initial, wave, 0)
    keys = []
    for d, fh in zip(degs, curve.Fn, strict=True):
        if not math.isfinite(fh):
            log.warning("no heteroclinic Fn at %g deg: that course is skipped", d)
            continue
        keys.append(
            {"task": "boundary", "chi_c_deg": float(d), "xi_0": float(xi_0),
             "Fn_brackets": [[fh + a, fh + b] for a, b in BRACKET_OFFSETS], "tol": float(tol),
             "t_max": float(t_max), **common}
        )  # fmt: skip
    b = _run(keys, vessel, "courses", run)
    by = {r.key["chi_c_deg"]: r for r in b.records if r.done}
    Fn = np.array(
        [by[float(d)].value["Fn"] if float(d) in by and by[float(d)].value["Fn"] else np.nan
         for d in degs],
        dtype=float,
    )  # fmt: skip
    return CoursesSweep(degs, Fn, np.asarray(curve.Fn, dtype=float), float(xi_0), b)


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
    res = _run(keys, vessel, "surface", run)
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
        check_res = _run(ck, vessel, "surface checks", run)
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
    return SurfaceSweep(
        float(chi_c_deg), hs, ls, Fn, Fs, tuple(reasons), res, tuple(checks), check_res
    )


__all__ = [
    "BRACKET_OFFSETS",
    "MAP_OFFSETS",
    "BoundarySweep",
    "CoursesSweep",
    "CriticalLine",
    "SurfaceSweep",
    "SurgeThreshold",
    "boundary_sweep",
    "courses_sweep",
    "critical_line",
    "run_task",
    "surf_riding_range",
    "surface_sweep",
    "surge_threshold",
    "vessel_context",
]
