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
   means the orbit attracts. :meth:`PeriodicOrbit.state_at` gives the state on the
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

import logging
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from continuation.errors import ContinuationError
from continuation.params import Params
from continuation.simulate import PoincareSection, SimEvent, Trajectory, simulate
from continuation.status import Status
from continuation.typing import FloatArray

from .eigen import paper_scales
from .events import capsize_angle as capsize_angle_of
from .fixed_points import fixed_points
from .manifold import ShipFate, classify_ship_fate

log = logging.getLogger(__name__)

CAPSIZE, PERIODIC, SURF_RIDING = "capsize", "periodic", "surf-riding"
SADDLE, UNDECIDED = "saddle", "undecided"
#: Outcomes of a sudden-change run (Umeda 1999, Figs. 16, 22: cross = capsize, circle =
#: periodic motion).
OUTCOMES = (CAPSIZE, PERIODIC, SURF_RIDING, SADDLE, UNDECIDED)
#: Outcomes counted as "captured by the wave" (the upper side of a boundary).
CAPTURED = (CAPSIZE, SURF_RIDING, SADDLE)


# ------------------------------------------------------------------------ helpers
def _params(model: Any, params: Any, name: str) -> Params:
    if params is None:
        raise ValueError(f"`{name}` must be given (Params, mapping or array)")
    try:
        return Params(model.param_names, model.check_params(params, name))
    except ValueError as exc:
        raise ValueError(f"`{name}`: {exc}") from None


def _positive(value: Any, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"`{name}` must be a positive number, got {value!r}")
    v = float(value)
    if not (math.isfinite(v) and v > 0):
        raise ValueError(f"`{name}` must be a positive number, got {value!r}")
    return v


def _position(value: Any, name: str = "xi_0") -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"`{name}` must be a finite number (xi_G/lambda), got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"`{name}` must be a finite number (xi_G/lambda), got {value!r}")
    return v


def _capsize_sim_event(model: Any, angle: float | None) -> SimEvent:
    phi_cap = capsize_angle_of(model, angle)
    i_phi = model.state_index("phi")
    return SimEvent(
        CAPSIZE,
        lambda t, x: np.abs(np.asarray(x)[..., i_phi]) - phi_cap,
        terminal=True,
        direction=1,
        vectorized=True,
    )


def default_guess(model: Any, params: Params, xi: float = 0.0) -> FloatArray:
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
@dataclass(frozen=True, eq=False)
class PeriodicOrbit:
    r"""A periodic orbit of the ship, sectioned at :math:`\xi_G/\lambda = c \pmod 1`.

    Attributes
    ----------
    model : Umeda4DOF
    params : Params
        The controls (and wave) it belongs to.
    x_section : ndarray, shape (8,)
        The state on the section (``xi_G = section``).
    section : float
    period : float
        Return time to the section (s).
    drift : int
        Wavelengths travelled per period (``-1``: overtaken by one wave per period).
    multipliers : ndarray, shape (7,), complex
        Eigenvalues of the return map's Jacobian (nontrivial Floquet multipliers).
    closure : float
        Nondimensional max-norm of ``P(x) - x`` at the solution.
    trajectory : Trajectory
        One period from ``x_section``.
    status : Status
    message : str
    n_transient : int
        Returns simulated before the Newton refinement.
    elapsed : float
        Wall time (s).
    """

    model: Any
    params: Params
    x_section: FloatArray
    section: float
    period: float
    drift: int
    multipliers: np.ndarray
    closure: float
    trajectory: Trajectory
    status: Status
    message: str = ""
    n_transient: int = 0
    elapsed: float = 0.0

    @property
    def success(self) -> bool:
        """Converged."""
        return self.status is Status.SUCCESS

    @property
    def attracting(self) -> bool:
        """All nontrivial Floquet multipliers inside the unit circle."""
        return bool(np.all(np.abs(self.multipliers) < 1.0))

    def state_at(self, xi_0: float) -> FloatArray:
        r"""The state on the orbit where :math:`\xi_G/\lambda \equiv \xi_0 \pmod 1`.

        The first such point after the section in the direction of the drift, located
        by a Poincare section on the re-integrated orbit (so to the integrator's
        accuracy, not an interpolation). ``xi_G`` of the result is ``xi_0`` itself.

        Parameters
        ----------
        xi_0 : float
            Initial longitudinal position :math:`(\xi_G/\lambda)_0`.

        Returns
        -------
        ndarray, shape (8,)
        """
        xi_0 = _position(xi_0)
        if not self.success:
            raise ContinuationError(f"the periodic orbit did not converge: {self.message}")
        i = self.model.state_index("xi_G")
        x = self.x_section.copy()
        if math.isclose(math.remainder(xi_0 - self.section, 1.0), 0.0, abs_tol=1e-13):
            x[i] = xi_0
            return x
        direction = 1 if self.drift > 0 else -1
        sec = PoincareSection("xi_G", xi_0, direction=direction, name="xi_0", terminal=True)
        tr = simulate(
            self.model,
            x,
            self.params,
            (0.0, 1.5 * self.period),
            events=[sec],
            dt=min(0.05, self.period / 100),
            rtol=1e-11,
            atol=1e-13,
        )
        hits = tr.events["xi_0"]
        if len(hits) == 0:  # pragma: no cover - a drifting orbit crosses every level
            raise ContinuationError(f"the orbit does not pass xi_G/lambda = {xi_0} (mod 1)")
        out = np.array(hits.x[0], dtype=float)
        out[i] = xi_0
        return out

    def states(self, xi_0: Sequence[float]) -> FloatArray:
        """:meth:`state_at` for several positions, shape ``(len(xi_0), 8)``."""
        return np.array([self.state_at(v) for v in xi_0])

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "params": {k: float(self.params[k]) for k in self.params.names},
            "section": self.section,
            "x_section": [float(v) for v in self.x_section],
            "period_s": self.period,
            "drift": self.drift,
            "multipliers_abs": [float(v) for v in np.abs(self.multipliers)],
            "closure": self.closure,
            "attracting": self.attracting,
            "status": self.status.name,
            "message": self.message,
            "n_transient": self.n_transient,
            "elapsed_s": self.elapsed,
        }


class _ReturnMap:
    """The first-return map to ``xi_G = c (mod 1)`` in the drift direction."""

    def __init__(self, model: Any, params: Params, section: float, direction: int, tmax: float):
        self.model, self.params, self.section = model, params, section
        self.direction, self.tmax = direction, tmax
        self.i = model.state_index("xi_G")
        self.others = [k for k in range(len(model.state_names)) if k != self.i]

    def full(self, y: FloatArray) -> FloatArray:
        x = np.empty(len(self.others) + 1)
        x[self.i] = self.section
        x[self.others] = y
        return x

    def __call__(self, y: FloatArray) -> tuple[FloatArray, float, Trajectory]:
        sec = PoincareSection(
            "xi_G", self.section, direction=self.direction, name="ret", terminal=True
        )
        tr = simulate(
            self.model,
            self.full(y),
            self.params,
            (0.0, self.tmax),
            events=[sec],
            dt=0.05,
            rtol=1e-11,
            atol=1e-13,
        )
        if tr.status is Status.INTERRUPTED:
            raise KeyboardInterrupt
        if tr.terminal_event != "ret":
            raise ContinuationError(f"no return to the section within {self.tmax:g} s")
        return np.asarray(tr.x[-1, self.others], dtype=float), float(tr.t[-1]), tr


def periodic_orbit(
    model: Any,
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
) -> PeriodicOrbit:
    r"""The attracting periodic orbit of the ship at ``params``, by simulation + Newton.

    1. Simulate from ``x_guess`` (default :func:`default_guess`) with the capsize event
       and the section :math:`\xi_G/\lambda = c \pmod 1` until two consecutive returns
       :math:`y_k, y_{k-1}` (the 7 states other than ``xi_G``, nondimensional
       max-norm, :func:`~ship_models.analysis.eigen.paper_scales`) differ by less
       than ``return_tol``.
    2. Newton's method on :math:`G(y) = P(y) - y = 0` with the Jacobian
       :math:`DP - I` by forward differences (7 one-period runs), until the scaled
       step and residual are below ``tol``.

    Parameters
    ----------
    model : Umeda4DOF
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
        Raise :class:`~continuation.errors.ConvergenceError` (a ContinuationError) on
        failure instead of returning the status.

    Returns
    -------
    PeriodicOrbit

    Raises
    ------
    ValueError
        For bad ``params``, ``x_guess``, tolerances or counts.
    """
    t_start = time.perf_counter()
    par = _params(model, params, "params")
    section = _position(section, "section")
    return_tol = _positive(return_tol, "return_tol")
    tol = _positive(tol, "tol")
    for name, v in (("max_returns", max_returns), ("max_newton", max_newton)):
        if isinstance(v, bool) or not isinstance(v, int) or v < 1:
            raise ValueError(f"`{name}` must be a positive integer, got {v!r}")
    x0 = (
        default_guess(model, par, section)
        if x_guess is None
        else model.check_state(x_guess, "x_guess")
    )
    scales, _ = paper_scales(model, par, default_guess(model, par))
    i_xi = model.state_index("xi_G")
    others = [k for k in range(len(model.state_names)) if k != i_xi]
    s7 = np.asarray(scales, dtype=float)[others]
    cap = _capsize_sim_event(model, capsize_angle)

    def fail(status: Status, msg: str, traj: Trajectory) -> PeriodicOrbit:
        if throw and status is not Status.INTERRUPTED:
            raise ContinuationError(f"periodic_orbit: {msg}")
        return PeriodicOrbit(
            model, par, np.array(traj.x[-1], dtype=float), section, math.nan, 0,
            np.full(len(others), np.nan + 0j), math.nan, traj, status, msg, 0,
            time.perf_counter() - t_start,
        )  # fmt: skip

    # ---- 1. transient: returns in both directions, in chunks
    sec = PoincareSection("xi_G", section, name="sec")
    x, t_now, hits_t, hits_x = x0, 0.0, [], []
    y_prev: FloatArray | None = None
    chunk = 200.0
    converged = False
    last: Trajectory | None = None
    while len(hits_t) < max_returns:
        tr = simulate(
            model, x, par, (t_now, t_now + chunk), events=[cap, sec], dt=0.1, rtol=1e-9, atol=1e-11
        )
        last = tr
        if tr.terminal_event == CAPSIZE:
            return fail(Status.EVENT, f"capsized at t = {tr.t[-1]:.1f} s from the guess", tr)
        if not tr.status.ok:
            return fail(tr.status, tr.message, tr)
        h = tr.events["sec"]
        for tk, xk in zip(h.t, h.x, strict=True):
            yk = np.asarray(xk[others])
            hits_t.append(float(tk))
            hits_x.append(np.asarray(xk, dtype=float))
            if y_prev is not None and np.max(np.abs(yk - y_prev) / s7) < return_tol:
                converged = True
                break
            y_prev = yk
        if converged:
            break
        x, t_now = tr.x[-1], float(tr.t[-1])
    assert last is not None
    if not converged:
        return fail(Status.MAX_ITER, f"returns did not settle in {len(hits_t)} returns", last)
    n_transient = len(hits_t)
    xa, xb = hits_x[-2], hits_x[-1]
    drift = int(round(xb[i_xi] - xa[i_xi]))
    if drift == 0:
        return fail(
            Status.UNDECIDED,
            "the motion does not drift through the waves",
            last,
        )
    period_est = hits_t[-1] - hits_t[-2]
    pmap = _ReturnMap(model, par, section, 1 if drift > 0 else -1, 3.0 * period_est * abs(drift))

    # ---- 2. Newton on P(y) - y
    y = np.asarray(xb[others], dtype=float)
    status, msg = Status.NEWTON_FAILED, f"Newton did not converge in {max_newton} iterations"
    J = np.eye(len(others))
    res = math.inf
    try:
        for it in range(max_newton):
            py, _, _ = pmap(y)
            g = py - y
            res = float(np.max(np.abs(g) / s7))
            J = np.empty((len(others), len(others)))
            for k in range(len(others)):
                h = 1e-6 * s7[k]
                yk = y.copy()
                yk[k] += h
                J[:, k] = (pmap(yk)[0] - py) / h
            step = np.linalg.solve(J - np.eye(len(others)), -g)
            y = y + step
            if np.max(np.abs(step) / s7) < tol and res < 1e3 * tol:
                status, msg = Status.SUCCESS, f"converged in {it + 1} Newton iterations"
                break
            if res < tol:
                status, msg = Status.SUCCESS, f"converged in {it + 1} Newton iterations"
                break
    except ContinuationError as exc:
        status, msg = Status.NEWTON_FAILED, str(exc)
    except np.linalg.LinAlgError:
        status, msg = Status.SINGULAR, "singular return-map Jacobian (a multiplier equal to 1)"
    except KeyboardInterrupt:
        return fail(Status.INTERRUPTED, "interrupted during the Newton refinement", last)
    try:
        py, period, tr = pmap(y)
    except ContinuationError as exc:
        return fail(Status.NEWTON_FAILED, f"Newton diverged: {exc}", last)
    except KeyboardInterrupt:
        return fail(Status.INTERRUPTED, "interrupted during the Newton refinement", last)
    closure = float(np.max(np.abs(py - y) / s7))
    mult = np.linalg.eigvals(J)
    orbit = PeriodicOrbit(
        model, par, pmap.full(y), section, period, drift, mult, closure, tr, status, msg,
        n_transient, time.perf_counter() - t_start,
    )  # fmt: skip
    if throw and status not in (Status.SUCCESS, Status.INTERRUPTED):
        raise ContinuationError(f"periodic_orbit: {msg}")
    log.debug("periodic orbit: %s, period %.6g s, closure %.2e", msg, period, closure)
    return orbit


def follow_orbit(
    orbit: PeriodicOrbit,
    params: Any,
    *,
    steps: int = 3,
    progress: Callable[[str], None] | None = None,
    **options: Any,
) -> PeriodicOrbit:
    """Follow a periodic orbit to new parameters in ``steps`` equal parameter steps.

    Each step starts :func:`periodic_orbit` from the previous orbit's section state
    (natural-parameter continuation of the attractor, the controls changed slowly).
    Use it when the attractor is not reached from the calm-water guess (e.g. the
    purse seiner at Fn = 0.3, chi_c = 45 deg capsizes from it).

    Parameters
    ----------
    orbit : PeriodicOrbit
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
    PeriodicOrbit
        At ``params``; a failed status if some step failed (that step's orbit).
    """
    if not isinstance(orbit, PeriodicOrbit) or not orbit.success:
        raise ValueError("`orbit` must be a converged PeriodicOrbit")
    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
        raise ValueError(f"`steps` must be a positive integer, got {steps!r}")
    model = orbit.model
    target = _params(model, params, "params")
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
    outcome : str
        One of :data:`OUTCOMES`: ``capsize``, ``periodic`` (periodic attractor or
        bounded recurrent surging), ``surf-riding`` (stable equilibrium),
        ``undecided``.
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

    outcome: str
    xi_0: float
    params_to: Params
    x0: FloatArray
    t: float
    fate: ShipFate
    trajectory: Trajectory

    @property
    def capsized(self) -> bool:
        """The ship capsized."""
        return self.outcome == CAPSIZE

    @property
    def captured(self) -> bool:
        """Capsize, surf-riding or convergence onto a saddle (:data:`CAPTURED`)."""
        return self.outcome in CAPTURED

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


def _outcome(fate: ShipFate) -> str:
    if fate.kind == "capsize":
        return CAPSIZE
    if fate.kind in ("periodic", "recurrent"):
        return PERIODIC
    if fate.kind == "equilibrium":
        return SURF_RIDING
    if fate.kind == "saddle":
        return SADDLE
    return UNDECIDED


def _orbit_for(model: Any, params_from: Any, orbit: PeriodicOrbit | None) -> PeriodicOrbit:
    if orbit is not None:
        if not isinstance(orbit, PeriodicOrbit):
            raise ValueError(f"`orbit` must be a PeriodicOrbit, got {type(orbit).__name__}")
        if not orbit.success:
            raise ValueError(f"`orbit` did not converge: {orbit.message}")
        return orbit
    pf = _params(model, params_from, "params_from")
    return periodic_orbit(model, pf, throw=True)


def sudden_change(
    model: Any,
    params_from: Any,
    params_to: Any,
    xi_0: float,
    *,
    orbit: PeriodicOrbit | None = None,
    t_max: float = 600.0,
    capsize_angle: float | None = None,
    progress: Callable[[float], None] | None = None,
    **classify: Any,
) -> SuddenChange:
    r"""Start on the periodic orbit of ``params_from`` at ``xi_0``; switch to ``params_to``.

    Parameters
    ----------
    model : Umeda4DOF
    params_from : Params, mapping or array
        The old controls (ignored when ``orbit`` is given), e.g. Fn = 0.1, chi_c = 0.
    params_to : Params, mapping or array
        The new controls, e.g. Fn = 0.31, chi_c = 10 deg.
    xi_0 : float
        Initial longitudinal position :math:`(\xi_G/\lambda)_0` on the old orbit.
    orbit : PeriodicOrbit, optional
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
    pt = _params(model, params_to, "params_to")
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
    model: Any,
    params_from: Any,
    chi_c_to: float,
    xi_0: float,
    fn_bracket: tuple[float, float],
    tol: float = 1e-4,
    *,
    orbit: PeriodicOrbit | None = None,
    t_max: float = 600.0,
    throw: bool = False,
    progress: Callable[[str], None] | None = None,
    **options: Any,
) -> SuddenChangeBoundary:
    r"""Critical Fn of the sudden change to course ``chi_c_to`` by bisection on the outcome.

    The outcome at the lower end of ``fn_bracket`` must be ``periodic`` and at the
    upper end captured (:data:`CAPTURED`: ``capsize`` for ``chi_c > 0``,
    ``surf-riding``/``saddle`` in the surge plane at ``chi_c = 0``); otherwise the
    result carries ``Status.NO_BRACKET`` (``ContinuationError`` with ``throw=True``).
    Each step halves the bracket, keeping ends with different outcomes, until it is
    shorter than ``tol``. A run still ``undecided`` at ``t_max`` is repeated once with
    ``2 t_max``; if still undecided the result carries ``Status.UNDECIDED``.
    (Bisection assumes one switch in the bracket: check the outcome map,
    :func:`sudden_change_map`, where that is in doubt.)

    Parameters
    ----------
    model : Umeda4DOF
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
    orbit : PeriodicOrbit, optional
        The old periodic orbit (computed from ``params_from`` if not given).
    t_max : float
        Time limit of each run (s).
    throw : bool
    progress : callable, optional
        ``progress(message)`` after each run.
    **options
        Passed to :func:`sudden_change`.

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
    try:
        chi = float(chi_c_to)
    except (TypeError, ValueError):
        raise ValueError(f"`chi_c_to` must be a number (rad), got {chi_c_to!r}") from None
    if not (math.isfinite(chi) and abs(chi) < math.pi / 2):
        raise ValueError(f"`chi_c_to` must be a course in (-pi/2, pi/2) rad, got {chi_c_to!r}")
    xi_0 = _position(xi_0)
    orb = _orbit_for(model, params_from, orbit)
    base = orb.params.replace(chi_c=chi)
    n_runs = 0

    def run(fn: float) -> str:
        nonlocal n_runs
        pt = base.replace(Fn=fn)
        options.setdefault("points", None)
        opts = (
            {**options, "points": fixed_points(model, pt)} if options["points"] is None else options
        )
        r = sudden_change(model, None, pt, xi_0, orbit=orb, t_max=t_max, **opts)
        n_runs += 1
        if r.outcome == UNDECIDED and r.fate.status is not Status.INTERRUPTED:
            # close to the boundary the transient lingers near the crest saddle and the
            # attractor below it has several returns: one more try with twice the time
            r = sudden_change(model, None, pt, xi_0, orbit=orb, t_max=2 * t_max, **opts)
            n_runs += 1
        if r.fate.status is Status.INTERRUPTED:
            raise KeyboardInterrupt
        if progress is not None:
            progress(f"Fn = {fn:.7f}: {r.outcome}")
        return r.outcome

    def done(status: Status, msg: str, out: tuple[str, str]) -> SuddenChangeBoundary:
        if throw and status not in (Status.SUCCESS, Status.INTERRUPTED):
            raise ContinuationError(f"sudden_change_boundary: {msg}")
        return SuddenChangeBoundary(
            0.5 * (lo + hi), (lo, hi), out, chi, xi_0, n_runs, status, msg,
            time.perf_counter() - t_start,
        )  # fmt: skip

    o_lo = o_hi = UNDECIDED
    try:
        o_lo, o_hi = run(lo), run(hi)
        if o_lo != PERIODIC or o_hi not in CAPTURED:
            return done(
                Status.NO_BRACKET,
                f"bracket ends must be 'periodic' below and captured ({', '.join(CAPTURED)}) "
                f"above; got {o_lo!r} at Fn = {lo:g} and {o_hi!r} at Fn = {hi:g}",
                (o_lo, o_hi),
            )
        while hi - lo > tol:
            mid = 0.5 * (lo + hi)
            o = run(mid)
            if o == UNDECIDED:
                return done(Status.UNDECIDED, f"undecided outcome at Fn = {mid:.8f}", (o_lo, o_hi))
            if o in CAPTURED:
                hi, o_hi = mid, o
            else:
                lo, o_lo = mid, o
    except KeyboardInterrupt:
        return done(Status.INTERRUPTED, "interrupted", (o_lo, o_hi))
    return done(Status.SUCCESS, f"bracket width {hi - lo:.2e} after {n_runs} runs", (o_lo, o_hi))


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
            k = np.nonzero(self.outcomes[:, j] == CAPSIZE)[0]
            if k.size:
                out[j] = self.Fn[k[0]]
        return out


def sudden_change_map(
    model: Any,
    params_from: Any,
    chi_c_to: float,
    xi_0: Sequence[float],
    fn_values: Sequence[float],
    *,
    orbit: PeriodicOrbit | None = None,
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
    "CAPSIZE",
    "CAPTURED",
    "OUTCOMES",
    "PERIODIC",
    "SADDLE",
    "SURF_RIDING",
    "UNDECIDED",
    "PeriodicOrbit",
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
