r"""The "sudden change" numerical experiments of Umeda (1999), Figs. 16-23.

Umeda (1999), section "Unstable manifolds and numerical experiments": the initial
state is "a steady periodic orbit for a set of control variables, and the control
variables are then suddenly changed to specified values; transient behavior is
observed" (the *sudden change concept*, Umeda, Workshop on Numerical and Physical
Simulation of Ship Capsize in Heavy Seas, Strathclyde 1995). Eight initial states are
so reduced to the two old controls and one initial longitudinal position
:math:`(\xi_G/\lambda)_0` on the old periodic orbit.

Steps, each a public function:

1. :func:`periodic_orbit` -- the attracting periodic orbit for the old controls
   ``params_from``: simulate from a guess until returns to the Poincare section
   :math:`\xi_G/\lambda = c \pmod 1` settle, then refine the fixed point
   :math:`x^* = P(x^*)` of the return map :math:`P` by Newton's method with a
   finite-difference Jacobian of :math:`P` (the 7 states other than ``xi_G``). Its
   eigenvalues are the nontrivial Floquet multipliers; all inside the unit circle
   means the orbit attracts. :meth:`ShootingOrbit.state_at` gives the state on the
   orbit at any :math:`(\xi_G/\lambda)_0` (its first crossing after the section).
2. :func:`sudden_change` -- start at that state with the new controls ``params_to``
   and classify the transient (:func:`~ship_models.analysis.manifold.classify_ship_fate`):
   ``capsize`` (roll beyond the angle of vanishing stability), ``periodic`` (a periodic
   attractor, or bounded recurrent surging), ``surf-riding`` (a stable fixed point),
   ``saddle`` (converged onto an unstable fixed point, i.e. started on its stable
   manifold: this happens in the invariant surge plane at ``chi_c = 0``, where the
   ship surf-rides at the trough point that is unstable only in yaw), or
   ``undecided``.
3. :func:`sudden_change_boundary` -- the critical nominal Froude number by bisection
   on "periodic" (below) against "captured by the wave" (capsize, surf-riding or
   saddle; above) for one new course and initial position (Fig. 23 squares). For
   ``chi_c > 0`` the upper side is capsize; at ``chi_c = 0`` it is surf-riding.
4. :func:`sudden_change_map` -- the outcome on a grid of initial positions and Fn
   (Figs. 16 and 22).
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from continuation.arguments import finite_number
from continuation.dynamics import Fate, FateKind, SimEvent, Trajectory, bisect_fate
from continuation.dynamics.shooting import ShootingOrbit, ShootingSettings
from continuation.dynamics.shooting import shoot_orbit as engine_periodic_orbit
from continuation.errors import ContinuationError
from continuation.params import Params
from continuation.status import Status
from continuation.typing import FloatArray

from ..contracts import VesselModel
from .eigen import paper_scales
from .events import capsize_angle as capsize_angle_of
from .fixed_points import FixedPointsInFn, fixed_points
from .manifold import ShipFate, classify_ship_fate
from .outcomes import CAPTURED_BY_WAVE, SUDDEN_CHANGE_OUTCOMES, ShipOutcome
from .params import course, ship_params

log = logging.getLogger(__name__)


# ------------------------------------------------------------------------ helpers
def _given(model: VesselModel, params: Any, name: str) -> Params:
    if params is None:
        raise ValueError(f"`{name}` must be given (Params, mapping or array)")
    return ship_params(model, params, name)


def _positive(value: Any, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"`{name}` must be a positive number, got {value!r}")
    v = float(value)
    if not (math.isfinite(v) and v > 0):
        raise ValueError(f"`{name}` must be a positive number, got {value!r}")
    return v


def _position(value: Any, name: str = "xi_0") -> float:
    return finite_number(name, value, meaning="xi_G/lambda")


def _capsize_sim_event(model: VesselModel, angle: float | None) -> SimEvent:
    phi_cap = capsize_angle_of(model, angle)
    i_phi = model.state_index("phi")
    return SimEvent(
        ShipOutcome.CAPSIZE,
        lambda t, x: np.abs(np.asarray(x)[..., i_phi]) - phi_cap,
        terminal=True,
        direction=1,
        vectorized=True,
    )


def default_guess(model: VesselModel, params: Params, xi: float = 0.0) -> FloatArray:
    """A calm-water start: ``u`` the nominal speed of ``Fn``, heading ``chi_c``, rest 0.

    Returns
    -------
    ndarray, shape (8,)
    """
    x = np.zeros(len(model.state_names))
    x[model.state_index("xi_G")] = xi
    x[model.state_index("u")] = float(model.forces.nominal_speed(params["Fn"]))
    x[model.state_index("chi")] = float(params["chi_c"])
    return x


# ----------------------------------------------------------------- periodic orbit
def periodic_orbit(
    model: VesselModel,
    params: Any,
    *,
    x_guess: Any = None,
    section: float = 0.0,
    return_tol: float = 1e-4,
    tol: float = 1e-9,
    max_returns: int = 400,
    max_newton: int = 8,
    capsize_angle: float | None = None,
    throw: bool = False,
) -> ShootingOrbit:
    r"""The attracting periodic orbit of the ship at ``params``, by simulation + Newton.

    The ship's use of the engine's return-map solver
    (:func:`continuation.dynamics.shooting.shoot_orbit`): section
    :math:`\xi_G/\lambda = c \pmod 1` (a rotation orbit: the ship is overtaken by whole
    waves, ``shift = -1`` per period), the nondimensional max-norm of
    :func:`~ship_models.analysis.eigen.paper_scales`, and the capsize event.

    1. Simulate from ``x_guess`` (default :func:`default_guess`) with the capsize event
       and the section until two consecutive returns :math:`y_k, y_{k-1}` (the 7
       states other than ``xi_G``) differ by less than ``return_tol``.
    2. Newton's method on :math:`G(y) = P(y) - y = 0` with the Jacobian
       :math:`DP - I` from the variational equations (one run of the 8 + 64 states per
       iteration; :mod:`continuation.dynamics.shooting`), until the scaled step and
       residual are below ``tol``. The Floquet multipliers are the eigenvalues of
       :math:`DP` at the converged orbit.

    Parameters
    ----------
    model : VesselModel
    params : Params, mapping or array
        The controls of the orbit (e.g. Fn = 0.1, chi_c = 0).
    x_guess : array_like, shape (8,), optional
        Start of the transient simulation.
    section : float
        Section level ``c`` of ``xi_G/lambda`` (mod 1).
    return_tol : float
        Returns this close end the transient simulation.
    tol : float
        Newton tolerance (nondimensional).
    max_returns : int
        Returns simulated at most before giving up (``Status.MAX_ITER``).
    max_newton : int
    capsize_angle : float, optional
        Roll angle (rad) of capsize; default the vanishing angle of GZ. A capsize
        during the transient gives ``Status.EVENT``.
    throw : bool
        Raise :class:`~continuation.errors.ContinuationError` on failure instead of
        returning the status.

    Returns
    -------
    ShootingOrbit
        The engine's type (``system`` is the model, ``shift`` the waves per period,
        ``state_at(xi_0)`` the state at :math:`(\xi_G/\lambda)_0`).

    Raises
    ------
    ValueError
        For bad ``params``, ``x_guess``, tolerances or counts.
    """
    par = ship_params(model, params)
    section = _position(section, "section")
    settings = ShootingSettings(
        return_tol=_positive(return_tol, "return_tol"),
        tol=_positive(tol, "tol"),
        max_returns=max_returns,
        max_newton=max_newton,
    )
    x0 = (
        default_guess(model, par, section)
        if x_guess is None
        else model.check_state(x_guess, "x_guess")
    )
    scales, _ = paper_scales(model, par, default_guess(model, par))
    orbit = engine_periodic_orbit(
        model,
        par,
        x0,
        state="xi_G",
        section=section,
        scale=scales,
        events=[_capsize_sim_event(model, capsize_angle)],
        settings=settings,
    )
    if orbit.status is Status.EVENT:
        msg = f"capsized at t = {orbit.trajectory.t[-1]:.1f} s from the guess"
        orbit = dataclasses.replace(orbit, message=msg)
    if throw and orbit.status not in (Status.SUCCESS, Status.INTERRUPTED):
        raise ContinuationError(f"periodic_orbit: {orbit.message}")
    return orbit


def follow_orbit(
    orbit: ShootingOrbit,
    params: Any,
    *,
    steps: int = 3,
    progress: Callable[[str], None] | None = None,
    **options: Any,
) -> ShootingOrbit:
    """Follow a periodic orbit to new parameters in ``steps`` equal parameter steps.

    Each step starts :func:`periodic_orbit` from the previous orbit's section state
    (natural-parameter continuation of the attractor, the controls changed slowly).
    Use it when the attractor is not reached from the calm-water guess (e.g. the
    purse seiner at Fn = 0.3, chi_c = 45 deg capsizes from it).

    Parameters
    ----------
    orbit : ShootingOrbit
        A converged orbit.
    params : Params, mapping or array
        Target parameters.
    steps : int
        Number of equal steps of the parameter vector.
    progress : callable, optional
        ``progress(message)`` after each step.
    **options
        Passed to :func:`periodic_orbit` (``section`` is the orbit's).

    Returns
    -------
    ShootingOrbit
        At ``params``; a failed status if some step failed (that step's orbit).
    """
    if not isinstance(orbit, ShootingOrbit) or not orbit.success:
        raise ValueError("`orbit` must be a converged ShootingOrbit")
    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
        raise ValueError(f"`steps` must be a positive integer, got {steps!r}")
    model = orbit.system
    target = ship_params(model, params)
    a = np.asarray(orbit.params.values, dtype=float)
    b = np.asarray(target.values, dtype=float)
    options.setdefault("section", orbit.section)
    cur = orbit
    for k in range(1, steps + 1):
        p = target.with_vector(a + (b - a) * k / steps)
        cur = periodic_orbit(model, p, x_guess=cur.x_section, **options)
        if progress is not None:
            progress(f"orbit step {k}/{steps}: {cur.message}")
        if not cur.success:
            break
    return cur


# ----------------------------------------------------------------- sudden change
@dataclass(frozen=True, eq=False)
class SuddenChange:
    r"""The outcome of one sudden-change run.

    Attributes
    ----------
    outcome : ShipOutcome
        One of :data:`~ship_models.analysis.outcomes.SUDDEN_CHANGE_OUTCOMES`:
        ``capsize``, ``periodic`` (periodic attractor or bounded recurrent surging),
        ``surf-riding`` (stable equilibrium), ``saddle``, ``undecided``.
    xi_0 : float
        Initial longitudinal position :math:`(\xi_G/\lambda)_0`.
    params_to : Params
        The new controls.
    x0 : ndarray, shape (8,)
        Initial state (on the old periodic orbit).
    t : float
        Time (s) at which the outcome was decided (capsize time for ``capsize``).
    fate : ShipFate
        The detailed classification.
    trajectory : Trajectory
    """

    outcome: ShipOutcome
    xi_0: float
    params_to: Params
    x0: FloatArray
    t: float
    fate: ShipFate
    trajectory: Trajectory

    @property
    def capsized(self) -> bool:
        """The ship capsized."""
        return self.outcome == ShipOutcome.CAPSIZE

    @property
    def captured(self) -> bool:
        """Capsize, surf-riding or convergence onto a saddle (``CAPTURED_BY_WAVE``)."""
        return self.outcome in CAPTURED_BY_WAVE

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary (no trajectory)."""
        return {
            "outcome": self.outcome,
            "xi_0": self.xi_0,
            "Fn": float(self.params_to["Fn"]),
            "chi_c_deg": math.degrees(float(self.params_to["chi_c"])),
            "t": self.t,
            "fate": self.fate.to_json(),
        }


def _outcome(fate: ShipFate) -> ShipOutcome:
    if fate.kind == ShipOutcome.CAPSIZE:
        return ShipOutcome.CAPSIZE
    if fate.kind in (ShipOutcome.PERIODIC, ShipOutcome.RECURRENT):
        return ShipOutcome.PERIODIC
    if fate.kind == ShipOutcome.EQUILIBRIUM:
        return ShipOutcome.SURF_RIDING
    if fate.kind == ShipOutcome.SADDLE:
        return ShipOutcome.SADDLE
    return ShipOutcome.UNDECIDED


def _orbit_for(model: VesselModel, params_from: Any, orbit: ShootingOrbit | None) -> ShootingOrbit:
    if orbit is not None:
        if not isinstance(orbit, ShootingOrbit):
            raise ValueError(f"`orbit` must be a ShootingOrbit, got {type(orbit).__name__}")
        if not orbit.success:
            raise ValueError(f"`orbit` did not converge: {orbit.message}")
        return orbit
    pf = _given(model, params_from, "params_from")
    return periodic_orbit(model, pf, throw=True)


def sudden_change(
    model: VesselModel,
    params_from: Any,
    params_to: Any,
    xi_0: float,
    *,
    orbit: ShootingOrbit | None = None,
    t_max: float = 600.0,
    capsize_angle: float | None = None,
    progress: Callable[[float], None] | None = None,
    **classify: Any,
) -> SuddenChange:
    r"""Start on the periodic orbit of ``params_from`` at ``xi_0``; switch to ``params_to``.

    Parameters
    ----------
    model : VesselModel
    params_from : Params, mapping or array
        The old controls (ignored when ``orbit`` is given), e.g. Fn = 0.1, chi_c = 0.
    params_to : Params, mapping or array
        The new controls, e.g. Fn = 0.31, chi_c = 10 deg.
    xi_0 : float
        Initial longitudinal position :math:`(\xi_G/\lambda)_0` on the old orbit.
    orbit : ShootingOrbit, optional
        The old orbit, if already computed (:func:`periodic_orbit`).
    t_max : float
        Time limit (s); ``undecided`` after it.
    capsize_angle : float, optional
        Roll angle of capsize (rad); default vanishing stability of GZ.
    progress : callable, optional
        ``progress(t)`` after each integration segment.
    **classify
        Further options of :func:`~ship_models.analysis.manifold.classify_ship_fate`
        (``segment``, ``dt``, ``return_tol``, ``points``, ...). ``points`` defaults to
        :func:`~ship_models.analysis.fixed_points.fixed_points` at ``params_to``
        (needed to recognise convergence onto a saddle).

    Returns
    -------
    SuddenChange

    Raises
    ------
    ValueError
        For bad parameters, ``xi_0``, ``t_max`` or ``orbit``.
    """
    pt = _given(model, params_to, "params_to")
    xi_0 = _position(xi_0)
    t_max = _positive(t_max, "t_max")
    orb = _orbit_for(model, params_from, orbit)
    x0 = orb.state_at(xi_0)
    points = classify.pop("points", None)
    if points is None:
        points = fixed_points(model, pt)
    traj, fate = classify_ship_fate(
        model,
        pt,
        x0,
        points=points,
        capsize_angle=capsize_angle,
        t_max=t_max,
        progress=progress,
        **classify,
    )
    return SuddenChange(_outcome(fate), xi_0, pt, x0, float(fate.t), fate, traj)


# ----------------------------------------------------------------- boundary
@dataclass(frozen=True)
class SuddenChangeBoundary:
    """Critical nominal Froude number of one sudden-change experiment.

    Attributes
    ----------
    Fn : float
        Midpoint of the final bracket.
    bracket : (float, float)
        ``(lower, upper)``: periodic at the lower end, captured (capsize,
        surf-riding, saddle) at the upper.
    outcomes : (str, str)
        Outcomes at the two ends.
    chi_c : float
        New course (rad).
    xi_0 : float
    n_runs : int
    status : Status
    message : str
    elapsed : float
    end_runs : tuple of (float, str, float)
        ``(Fn, outcome, t)`` of the first run at each end of the bracket (before any
        retry of an undecided run): the same run as an outcome map's cell at that ``Fn``
        and position (:func:`sudden_change_map`), so a map can take it from here.
    """

    Fn: float
    bracket: tuple[float, float]
    outcomes: tuple[str, str]
    chi_c: float
    xi_0: float
    n_runs: int
    status: Status
    message: str = ""
    elapsed: float = 0.0
    end_runs: tuple[tuple[float, str, float], ...] = ()

    @property
    def success(self) -> bool:
        """Converged to the tolerance."""
        return self.status is Status.SUCCESS

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "Fn": self.Fn,
            "bracket": list(self.bracket),
            "outcomes": list(self.outcomes),
            "chi_c_deg": math.degrees(self.chi_c),
            "xi_0": self.xi_0,
            "n_runs": self.n_runs,
            "status": self.status.name,
            "message": self.message,
            "elapsed_s": self.elapsed,
        }


def _fn_bracket(value: Any) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ValueError(f"`fn_bracket` must be a pair of numbers, got {value!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo < hi):
        raise ValueError(f"`fn_bracket` must satisfy 0 < lower < upper, got {value!r}")
    return lo, hi


def sudden_change_boundary(
    model: VesselModel,
    params_from: Any,
    chi_c_to: float,
    xi_0: float,
    fn_bracket: tuple[float, float],
    tol: float = 1e-4,
    *,
    orbit: ShootingOrbit | None = None,
    t_max: float = 600.0,
    throw: bool = False,
    progress: Callable[[str], None] | None = None,
    **options: Any,
) -> SuddenChangeBoundary:
    r"""Critical Fn of the sudden change to course ``chi_c_to`` by bisection on the outcome.

    The outcome at the lower end of ``fn_bracket`` must be ``periodic`` and at the
    upper end captured (``CAPTURED_BY_WAVE``: ``capsize`` for ``chi_c > 0``,
    ``surf-riding``/``saddle`` in the surge plane at ``chi_c = 0``); otherwise the
    result carries ``Status.NO_BRACKET`` (``ContinuationError`` with ``throw=True``).
    Each step halves the bracket, keeping ends with different outcomes, until it is
    shorter than ``tol``. A run still ``undecided`` at ``t_max`` is repeated once with
    ``2 t_max``; if still undecided the result carries ``Status.UNDECIDED``.
    (Bisection assumes one switch in the bracket: check the outcome map,
    :func:`sudden_change_map`, where that is in doubt.)

    Parameters
    ----------
    model : VesselModel
    params_from : Params, mapping or array
        The old controls (ignored with ``orbit``); the new ones are these with
        ``chi_c = chi_c_to`` and the bisected ``Fn``.
    chi_c_to : float
        New autopilot course (rad).
    xi_0 : float
        Initial longitudinal position.
    fn_bracket : (float, float)
        ``(lower, upper)`` nominal Froude numbers.
    tol : float
        Final bracket width in Fn.
    orbit : ShootingOrbit, optional
        The old periodic orbit (computed from ``params_from`` if not given).
    t_max : float
        Time limit of each run (s).
    throw : bool
    progress : callable, optional
        ``progress(message)`` after each run.
    **options
        Passed to :func:`sudden_change`. Without ``points``, the fixed points at each
        ``Fn`` are traced in full at the bracket's ends and tracked by Newton between
        anchors at most 0.01 apart (:class:`~ship_models.analysis.fixed_points.FixedPointsInFn`).

    Returns
    -------
    SuddenChangeBoundary
        On ``KeyboardInterrupt`` the bracket so far with ``Status.INTERRUPTED``.

    Raises
    ------
    ValueError
        For a bad ``fn_bracket``, ``tol``, ``chi_c_to``, ``xi_0`` or parameters.
    """
    t_start = time.perf_counter()
    lo, hi = _fn_bracket(fn_bracket)
    tol = _positive(tol, "tol")
    chi = course(chi_c_to, "chi_c_to")
    xi_0 = _position(xi_0)
    orb = _orbit_for(model, params_from, orbit)
    base = orb.params.replace(chi_c=chi)
    n_runs = 0
    # every fixed point at each Fn: traced at the bracket's ends, tracked by Newton between
    points_at = FixedPointsInFn(model, base)

    ends: list[ShipOutcome] = []
    end_runs: list[tuple[float, str, float]] = []

    def run(fn: float) -> Any:
        nonlocal n_runs
        pt = base.replace(Fn=fn)
        options.setdefault("points", None)
        opts = {**options, "points": points_at(fn)} if options["points"] is None else options
        r = sudden_change(model, None, pt, xi_0, orbit=orb, t_max=t_max, **opts)
        n_runs += 1
        if len(ends) < 2 and r.fate.status is not Status.INTERRUPTED:
            end_runs.append((float(fn), str(r.outcome), float(r.t)))
        if r.outcome == ShipOutcome.UNDECIDED and r.fate.status is not Status.INTERRUPTED:
            # close to the boundary the transient lingers near the crest saddle and the
            # attractor below it has several returns: one more try with twice the time
            r = sudden_change(model, None, pt, xi_0, orbit=orb, t_max=2 * t_max, **opts)
            n_runs += 1
        if r.fate.status is Status.INTERRUPTED:
            raise KeyboardInterrupt
        if progress is not None:
            progress(f"Fn = {fn:.7f}: {r.outcome}")
        if len(ends) < 2:
            ends.append(r.outcome)
            if len(ends) == 2 and (
                ends[0] != ShipOutcome.PERIODIC or ends[1] not in CAPTURED_BY_WAVE
            ):
                raise _WrongEnds
        if r.outcome == ShipOutcome.UNDECIDED:
            return Fate(FateKind.UNDECIDED, "undecided", t=r.t)
        return r.outcome

    def done(status: Status, msg: str, bracket: tuple[float, float], out: Any) -> Any:
        if throw and status not in (Status.SUCCESS, Status.INTERRUPTED):
            raise ContinuationError(f"sudden_change_boundary: {msg}")
        return SuddenChangeBoundary(
            0.5 * (bracket[0] + bracket[1]), bracket, out, chi, xi_0, n_runs, status, msg,
            time.perf_counter() - t_start, tuple(end_runs),
        )  # fmt: skip

    try:
        res = bisect_fate(run, lo, hi, tol=tol, max_evaluations=10**6)
    except _WrongEnds:
        captured = ", ".join(o for o in SUDDEN_CHANGE_OUTCOMES if o in CAPTURED_BY_WAVE)
        return done(
            Status.NO_BRACKET,
            f"bracket ends must be 'periodic' below and captured ({captured}) above; got "
            f"{str(ends[0])!r} at Fn = {lo:g} and {str(ends[1])!r} at Fn = {hi:g}",
            (lo, hi),
            (ends[0], ends[1]),
        )
    bracket = (float(res.bracket[0]), float(res.bracket[1]))
    out = tuple(
        ShipOutcome.UNDECIDED if f is None or isinstance(f, Fate) else f
        for f in (res.fate_lo, res.fate_hi)
    )
    if res.status is Status.UNDECIDED:
        mid = res.history[-1][0]
        return done(Status.UNDECIDED, f"undecided outcome at Fn = {mid:.8f}", bracket, out)
    if res.status is Status.INTERRUPTED:
        return done(Status.INTERRUPTED, "interrupted", bracket, out)
    if res.status is not Status.SUCCESS:
        return done(res.status, res.message, bracket, out)
    width = bracket[1] - bracket[0]
    return done(Status.SUCCESS, f"bracket width {width:.2e} after {n_runs} runs", bracket, out)


class _WrongEnds(Exception):
    """The ends of the bracket are not periodic (lower) and captured (upper)."""


# ----------------------------------------------------------------- map
@dataclass(frozen=True, eq=False)
class SuddenChangeMap:
    """Outcomes on a grid of initial positions and Froude numbers (Figs. 16, 22).

    Attributes
    ----------
    xi_0 : ndarray, shape (n_xi,)
    Fn : ndarray, shape (n_fn,)
    outcomes : ndarray of str, shape (n_fn, n_xi)
        ``""`` where not computed (interrupted).
    times : ndarray, shape (n_fn, n_xi)
        Time of the decision (s), e.g. the capsize time.
    chi_c : float
        New course (rad).
    status : Status
    elapsed : float
    """

    xi_0: FloatArray
    Fn: FloatArray
    outcomes: np.ndarray
    times: FloatArray
    chi_c: float
    status: Status
    elapsed: float = 0.0

    def boundary(self) -> FloatArray:
        """Per initial position: lowest capsizing Fn of the grid (nan if none), shape (n_xi,)."""
        out = np.full(self.xi_0.size, np.nan)
        for j in range(self.xi_0.size):
            k = np.nonzero(self.outcomes[:, j] == ShipOutcome.CAPSIZE)[0]
            if k.size:
                out[j] = self.Fn[k[0]]
        return out


def sudden_change_map(
    model: VesselModel,
    params_from: Any,
    chi_c_to: float,
    xi_0: Sequence[float],
    fn_values: Sequence[float],
    *,
    orbit: ShootingOrbit | None = None,
    t_max: float = 600.0,
    progress: Callable[[str], None] | None = None,
    **options: Any,
) -> SuddenChangeMap:
    """Outcome of the sudden change for every ``(Fn, xi_0)`` of a grid.

    Parameters
    ----------
    model, params_from, chi_c_to, orbit, t_max
        As in :func:`sudden_change_boundary`.
    xi_0 : sequence of float
        Initial positions.
    fn_values : sequence of float
        New nominal Froude numbers.
    progress : callable, optional
        ``progress(message)`` after each run.
    **options
        Passed to :func:`sudden_change`.

    Returns
    -------
    SuddenChangeMap
        On ``KeyboardInterrupt`` the runs finished so far, ``Status.INTERRUPTED``.
    """
    t_start = time.perf_counter()
    xs = np.array([_position(v) for v in np.atleast_1d(np.asarray(xi_0, dtype=object))])
    try:
        fns = np.asarray(fn_values, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ValueError(f"`fn_values` must be numbers, got {fn_values!r}") from None
    if xs.size == 0:
        raise ValueError("`xi_0` must not be empty")
    if fns.size == 0 or not np.all(np.isfinite(fns)) or np.any(fns <= 0):
        raise ValueError(f"`fn_values` must be positive finite numbers, got {fn_values!r}")
    chi = float(chi_c_to)
    orb = _orbit_for(model, params_from, orbit)
    base = orb.params.replace(chi_c=chi)
    outcomes = np.full((fns.size, xs.size), "", dtype=object)
    times = np.full((fns.size, xs.size), np.nan)
    status = Status.SUCCESS
    try:
        for i, fn in enumerate(fns):
            pt = base.replace(Fn=float(fn))
            opts = dict(options)
            if opts.get("points") is None:
                opts["points"] = fixed_points(model, pt)
            for j, xi in enumerate(xs):
                r = sudden_change(model, None, pt, float(xi), orbit=orb, t_max=t_max, **opts)
                if r.fate.status is Status.INTERRUPTED:
                    raise KeyboardInterrupt
                outcomes[i, j], times[i, j] = r.outcome, r.t
                if progress is not None:
                    progress(f"Fn = {fn:.5f}, xi_0 = {xi:.3f}: {r.outcome}")
    except KeyboardInterrupt:
        status = Status.INTERRUPTED
    return SuddenChangeMap(xs, fns, outcomes, times, chi, status, time.perf_counter() - t_start)


__all__ = [
    "ShootingOrbit",
    "SuddenChange",
    "SuddenChangeBoundary",
    "SuddenChangeMap",
    "default_guess",
    "follow_orbit",
    "periodic_orbit",
    "sudden_change",
    "sudden_change_boundary",
    "sudden_change_map",
]
