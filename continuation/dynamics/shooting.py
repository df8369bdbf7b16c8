r"""Periodic orbits by the first-return map of a Poincare section: simulation + Newton.

A periodic orbit of :math:`\dot x = f(x; p)` crosses the section
:math:`\Sigma = \{x_i = c\}` (``c`` modulo the period :math:`P_i` of state ``i`` when
that state is an angle-like, periodic coordinate) at a fixed point of the first-return
map :math:`P: \Sigma \to \Sigma`. :func:`shoot_orbit` finds it in two steps
(e.g. Parker & Chua 1989, *Practical Numerical Algorithms for Chaotic Systems*,
Ch. 6, shooting on the Poincare map):

1. Transient: simulate from a guess until two consecutive returns :math:`y_k, y_{k-1}`
   (the ``n - 1`` states other than ``x_i``, scaled max-norm) differ by less than
   ``return_tol``: the orbit attracts, or the run ends with a status.
2. Newton on :math:`G(y) = P(y) - y = 0` with the Jacobian :math:`DP - I`. The
   eigenvalues of :math:`DP` at the solution are the nontrivial Floquet multipliers:
   all inside the unit circle means the orbit attracts.

The Jacobian of the return map (``ShootingSettings.jacobian``):

``"variational"`` (default for a system with a CasADi trace)
    From the state transition matrix :math:`\Phi(T) = \partial x(T)/\partial x_0`
    over the return time :math:`T`, integrated by CVODES with the variational
    equations :math:`\dot\Phi = (\partial f/\partial x)\,\Phi`, :math:`\Phi(0) = I`
    (exact ``df/dx`` of the trace; :func:`~continuation.dynamics.integrators.state_transition`).
    The return time depends on the start, :math:`g(x(T(x_0), x_0)) = 0` with
    :math:`g = x_i - c`, so :math:`\partial T/\partial x_0 = -e_i^T\Phi / f_i(x_T)` and

    .. math::

        DP_{\text{full}} = \Bigl(I - \frac{f(x_T)\, e_i^T}{f_i(x_T)}\Bigr)\,\Phi(T)

    (differentiating the return condition, as in Parker & Chua 1989, Ch. 6; row ``i``
    vanishes: the return stays on the section), of which :math:`DP` is the block of
    the ``n - 1`` section coordinates.
    One run with the variational equations per Newton iteration (and one at the
    solution). Error: that of the integration of :math:`\Phi` (CVODES controls
    the local error of every component of :math:`\Phi` with ``map_rtol``,
    ``map_atol``; the global error is a modest multiple, growing with the
    orbit's expansion), plus :math:`|f(x_T)|\,|\Phi|\,\delta x_i / |f_i|^2`-terms
    of the section miss :math:`\delta x_i` of the located return, at the event
    location's accuracy. A simple multiplier :math:`\mu` then errs by about
    :math:`\kappa(\mu)\,\|\delta DP\|` (:math:`\kappa` its eigenvalue condition
    number): for a well-conditioned orbit, to integration accuracy (about 1e-8
    with the default tolerances; see ``tests/test_shooting_monodromy.py``).
``"fd"`` (the only one for a NumPy-only system)
    Forward differences of :math:`P` with steps ``fd_step`` times the scales
    (``n - 1`` extra one-period runs per iteration): error
    :math:`O(\text{fd\_step}\,|D^2P|)` plus the noise of the runs over ``fd_step``
    (about 1e-5 to 1e-3 in the multipliers of the ship's orbits with the
    defaults).

Rotation orbits: when state ``i`` is periodic (``period[i] > 0``) the orbit may
advance by whole periods between returns (``shift = (x_i(T) - x_i(0)) / P_i``, an
integer, e.g. a ship overtaken by one wave per period: ``shift = -1``); the return map
then counts crossings in the direction of the shift. An oscillation that does not
rotate (``shift = 0``) needs the crossing ``direction`` of the section.

The engine knows nothing of the model: the system, its parameters, the section, the
scales of the norm and any terminal events (e.g. a capsize) are the caller's.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from continuation.errors import ContinuationError
from continuation.status import Status
from continuation.typing import FloatArray

from ..arguments import finite_number
from ._common import check_scale, param_vector
from .events import PoincareSection
from .integrators import _IntegrationFailure, state_transition
from .simulate import simulate
from .trajectory import Trajectory

log = logging.getLogger(__name__)

#: Choices of ``ShootingSettings.jacobian``.
JACOBIANS = ("auto", "variational", "fd")


@dataclass(frozen=True)
class ShootingSettings:
    """Settings of :func:`shoot_orbit`.

    Attributes
    ----------
    return_tol : float
        Consecutive returns this close (scaled max-norm) end the transient.
    tol : float
        Newton tolerance (scaled max-norm of the step and of ``P(y) - y``).
    max_returns : int
        Returns simulated at most in the transient (else ``Status.MAX_ITER``).
    max_newton : int
        Newton iterations at most.
    chunk : float
        Length of one transient integration (time units).
    transient_dt, transient_rtol, transient_atol : float
        Sampling and integrator tolerances of the transient.
    map_dt, map_rtol, map_atol : float
        Sampling and integrator tolerances of one return-map evaluation.
    fd_step : float
        Forward-difference step of ``DP``, relative to the state's scale (used by
        ``jacobian="fd"``).
    jacobian : {"auto", "variational", "fd"}
        How ``DP`` is computed (module notes): ``"variational"`` from the state
        transition matrix (needs a CasADi trace), ``"fd"`` by forward differences,
        ``"auto"`` (default) the first when the system has a CasADi trace, else the
        second.

    Raises
    ------
    ValueError
        On construction, naming the bad field.
    """

    return_tol: float = 1e-4
    tol: float = 1e-9
    max_returns: int = 400
    max_newton: int = 8
    chunk: float = 200.0
    transient_dt: float = 0.1
    transient_rtol: float = 1e-9
    transient_atol: float = 1e-11
    map_dt: float = 0.05
    map_rtol: float = 1e-11
    map_atol: float = 1e-13
    fd_step: float = 1e-6
    jacobian: str = "auto"

    def __post_init__(self) -> None:
        if self.jacobian not in JACOBIANS:
            raise ValueError(f"`jacobian` must be one of {JACOBIANS}, got {self.jacobian!r}")
        for name in ("max_returns", "max_newton"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise ValueError(f"`{name}` must be a positive integer, got {v!r}")
        for name in (
            "return_tol", "tol", "chunk", "transient_dt", "transient_rtol", "transient_atol",
            "map_dt", "map_rtol", "map_atol", "fd_step",
        ):  # fmt: skip
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise ValueError(f"`{name}` must be a positive number, got {v!r}")
            if not (math.isfinite(v) and v > 0):
                raise ValueError(f"`{name}` must be a positive number, got {v!r}")


@dataclass(frozen=True, eq=False)
class ShootingOrbit:
    r"""A periodic orbit sectioned at :math:`x_i = c \pmod{P_i}`.

    Attributes
    ----------
    system : System
    params : Params or ndarray
        The parameters it belongs to (as given).
    state : int
        Index ``i`` of the sectioning state.
    x_section : ndarray, shape (n,)
        The state on the section (``x_i = section``).
    section : float
        The level ``c``.
    period : float
        Return time to the section.
    shift : int
        Periods of state ``i`` advanced per return (0 for an oscillation).
    direction : int
        Crossing direction of the return map (``+1``/``-1``).
    multipliers : ndarray, shape (n - 1,), complex
        Eigenvalues of the return map's Jacobian (nontrivial Floquet multipliers), by
        the method ``jacobian`` (its accuracy: module notes).
    closure : float
        Scaled max-norm of ``P(y) - y`` at the solution.
    trajectory : Trajectory
        One period from ``x_section`` (the last run on failure).
    status : Status
    message : str
    n_transient : int
        Returns simulated before the Newton refinement.
    elapsed : float
        Wall time (s).
    jacobian : str
        How the return map's Jacobian was computed: ``"variational"`` or ``"fd"``
        (``""`` when Newton was not reached).
    """

    system: Any
    params: Any
    state: int
    x_section: FloatArray
    section: float
    period: float
    shift: int
    direction: int
    multipliers: np.ndarray
    closure: float
    trajectory: Trajectory
    status: Status
    message: str = ""
    n_transient: int = 0
    elapsed: float = 0.0
    jacobian: str = ""
    #: States found by :meth:`state_at`, by level (each found once per orbit).
    _levels: dict[float, FloatArray] = field(
        default_factory=dict, init=False, repr=False, compare=False
    )

    @property
    def success(self) -> bool:
        """Converged."""
        return self.status is Status.SUCCESS

    @property
    def attracting(self) -> bool:
        """All nontrivial Floquet multipliers inside the unit circle."""
        return bool(np.all(np.abs(self.multipliers) < 1.0))

    def state_at(self, level: float) -> FloatArray:
        r"""The state on the orbit where :math:`x_i \equiv` ``level`` (mod :math:`P_i`).

        The first such point after the section in the crossing direction, located by
        a Poincare section on the re-integrated orbit (to the integrator's accuracy,
        not an interpolation). ``x_i`` of the result is ``level`` itself.

        Parameters
        ----------
        level : float

        Returns
        -------
        ndarray, shape (n,)

        Raises
        ------
        ValueError
            For a non-finite ``level``.
        ContinuationError
            If the orbit did not converge, or does not cross ``level``.
        """
        level = finite_number("level", level)
        if not self.success:
            raise ContinuationError(f"the periodic orbit did not converge: {self.message}")
        known = self._levels.get(level)
        if known is not None:  # the same deterministic integration as the first time
            return known.copy()
        i = self.state
        x = self.x_section.copy()
        per = _periods(self.system)[i]
        if per > 0 and math.isclose(math.remainder(level - self.section, per), 0.0, abs_tol=1e-13):
            x[i] = level
            return x
        sec = PoincareSection(i, level, direction=self.direction, name="level", terminal=True)
        tr = simulate(
            self.system,
            x,
            self.params,
            (0.0, 1.5 * self.period),
            events=[sec],
            dt=min(0.05, self.period / 100),
            rtol=1e-11,
            atol=1e-13,
        )
        hits = tr.events["level"]
        if len(hits) == 0:
            raise ContinuationError(f"the orbit does not cross x[{i}] = {level}")
        out = np.array(hits.x[0], dtype=float)
        out[i] = level
        self._levels[level] = out.copy()
        return out

    def states(self, levels: Sequence[float]) -> FloatArray:
        """:meth:`state_at` for several levels, shape ``(len(levels), n)``."""
        return np.array([self.state_at(v) for v in levels])

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary (no trajectory)."""
        p = self.params
        params = (
            {k: float(p[k]) for k in p.names}
            if hasattr(p, "names")
            else [float(v) for v in np.asarray(p, dtype=float)]
        )
        return {
            "params": params,
            "state": self.state,
            "section": self.section,
            "x_section": [float(v) for v in self.x_section],
            "period": self.period,
            "shift": self.shift,
            "direction": self.direction,
            "multipliers_abs": [float(v) for v in np.abs(self.multipliers)],
            "closure": self.closure,
            "attracting": self.attracting,
            "status": self.status.name,
            "message": self.message,
            "n_transient": self.n_transient,
            "elapsed_s": self.elapsed,
            "jacobian": self.jacobian,
        }


def _periods(system: Any) -> FloatArray:
    n = len(system.state_names)
    per = getattr(system, "period", None)
    return np.zeros(n) if per is None else np.asarray(per, dtype=float).reshape(n)


class ReturnMap:
    """The first-return map to ``x_i = c`` (mod ``P_i``) in one crossing direction.

    ``y`` is the state without component ``i`` (shape ``(n - 1,)``);
    ``map(y) -> (P(y), return time, trajectory)``.
    """

    def __init__(
        self,
        system: Any,
        params: Any,
        state: int,
        section: float,
        direction: int,
        t_max: float,
        settings: ShootingSettings,
    ) -> None:
        self.system, self.params, self.state, self.section = system, params, state, section
        self.direction, self.t_max, self.settings = direction, t_max, settings
        self.others = [k for k in range(len(system.state_names)) if k != state]

    def full(self, y: FloatArray) -> FloatArray:
        """The state on the section with the other components ``y``, shape (n,)."""
        x = np.empty(len(self.others) + 1)
        x[self.state] = self.section
        x[self.others] = y
        return x

    def __call__(self, y: FloatArray) -> tuple[FloatArray, float, Trajectory]:
        """The return ``P(y)`` on the section, its time and the trajectory to it."""
        sec = PoincareSection(
            self.state, self.section, direction=self.direction, name="ret", terminal=True
        )
        s = self.settings
        tr = simulate(
            self.system,
            self.full(y),
            self.params,
            (0.0, self.t_max),
            events=[sec],
            dt=s.map_dt,
            rtol=s.map_rtol,
            atol=s.map_atol,
        )
        if tr.status is Status.INTERRUPTED:
            raise KeyboardInterrupt
        if tr.terminal_event != "ret":
            raise ContinuationError(f"no return to the section within {self.t_max:g}")
        return np.asarray(tr.x[-1, self.others], dtype=float), float(tr.t[-1]), tr

    def jacobian(self, y: FloatArray, T: float) -> FloatArray:
        r"""``DP`` at ``y`` with return time ``T``, from the variational equations.

        :math:`DP_{\text{full}} = (I - f(x_T) e_i^T / f_i(x_T))\,\Phi(T)` restricted
        to the section coordinates (module notes).

        Parameters
        ----------
        y : ndarray, shape (n - 1,)
        T : float
            The return time of ``y`` (from :meth:`__call__`).

        Returns
        -------
        ndarray, shape (n - 1, n - 1)

        Raises
        ------
        ContinuationError
            If the integration fails or the orbit meets the section tangentially
            (``f_i(x_T) = 0``).
        """
        s = self.settings
        p = param_vector(self.system, self.params)
        try:
            xT, phi = state_transition(
                self.system, p, self.full(y), T, rtol=s.map_rtol, atol=s.map_atol
            )
        except _IntegrationFailure as exc:
            raise ContinuationError(f"the variational equations failed: {exc}") from None
        fT = np.asarray(self.system.f(xT, p), dtype=float).reshape(-1)
        fi = float(fT[self.state])
        if not (math.isfinite(fi) and abs(fi) > 0.0):
            raise ContinuationError("the orbit meets the section tangentially")
        dp = phi - np.outer(fT / fi, phi[self.state])
        return np.asarray(dp[np.ix_(self.others, self.others)], dtype=float)

    def jacobian_fd(self, y: FloatArray, py: FloatArray, scale: FloatArray) -> FloatArray:
        """``DP`` at ``y`` (``py = P(y)``) by forward differences, shape ``(n - 1, n - 1)``.

        Steps ``fd_step * scale`` (one extra return per column).
        """
        m = len(self.others)
        J = np.empty((m, m))
        for k in range(m):
            h = self.settings.fd_step * scale[k]
            yk = y.copy()
            yk[k] += h
            J[:, k] = (self(yk)[0] - py) / h
        return J


def shoot_orbit(
    system: Any,
    params: Any,
    x_guess: Any,
    *,
    state: str | int,
    section: float = 0.0,
    direction: int | None = None,
    scale: Any = None,
    events: Sequence[Any] = (),
    settings: ShootingSettings | None = None,
    throw: bool = False,
) -> ShootingOrbit:
    r"""The attracting periodic orbit through the section ``x_state = section``.

    See the module docstring for the method.

    Parameters
    ----------
    system : System
        With ``state_names`` and, for rotation orbits, ``period`` (shape (n,), 0 for
        non-periodic states).
    params : Params, mapping or array_like, shape (m,)
    x_guess : array_like, shape (n,)
        Start of the transient simulation.
    state : str or int
        The sectioning state ``i``.
    section : float
        The level ``c``.
    direction : {None, 1, -1}
        Crossing direction of the return map. None (only for a periodic ``state``): a
        rotation orbit, the direction of its shift (the transient counts crossings both
        ways); an orbit that does not rotate then fails with ``Status.UNDECIDED``.
    scale : array_like, shape (n,), optional
        Scales of the max-norm (default ones).
    events : sequence of SimEvent
        Terminal events of the transient (e.g. a capsize): one that fires gives
        ``Status.EVENT``, its name in the message.
    settings : ShootingSettings, optional
    throw : bool
        Raise :class:`~continuation.errors.ContinuationError` on failure instead of
        returning the status.

    Returns
    -------
    ShootingOrbit

    Raises
    ------
    ValueError
        For a bad ``state``, ``section``, ``direction`` (None for a non-periodic
        ``state``), ``scale`` or ``x_guess``.
    """
    t_start = time.perf_counter()
    cfg = settings or ShootingSettings()
    names = tuple(system.state_names)
    n = len(names)
    if isinstance(state, str):
        if state not in names:
            raise ValueError(f"`state` must be one of {names}, got {state!r}")
        i = names.index(state)
    elif isinstance(state, (int, np.integer)) and not isinstance(state, bool) and 0 <= state < n:
        i = int(state)
    else:
        raise ValueError(f"`state` must be a state name or index, got {state!r}")
    section = finite_number("section", section)
    if direction not in (None, 1, -1):
        raise ValueError(f"`direction` must be None, 1 or -1, got {direction!r}")
    x0 = system.check_state(x_guess, "x_guess")
    if cfg.jacobian == "variational" and not getattr(system, "has_casadi", False):
        raise ValueError(
            "`settings.jacobian` is 'variational' but the system has no CasADi trace "
            "(use 'fd' or 'auto')"
        )
    sc = check_scale(n, scale)
    others = [k for k in range(n) if k != i]
    s_o = sc[others]
    per_i = float(_periods(system)[i])
    if direction is None and per_i <= 0:
        raise ValueError(
            f"`direction` must be given: state {names[i]!r} is not periodic, so the orbit "
            "cannot be a rotation (give 1 or -1 for an oscillation)"
        )
    terminal = {e.name for e in events if getattr(e, "terminal", False)}

    def fail(status: Status, msg: str, traj: Trajectory) -> ShootingOrbit:
        if throw and status is not Status.INTERRUPTED:
            raise ContinuationError(f"shoot_orbit: {msg}")
        return ShootingOrbit(
            system, params, i, np.array(traj.x[-1], dtype=float), section, math.nan, 0,
            direction or 0, np.full(len(others), np.nan + 0j), math.nan, traj, status, msg,
            0, time.perf_counter() - t_start,
        )  # fmt: skip

    # ---- 1. transient, in chunks
    sec = PoincareSection(i, section, direction=direction or 0, name="sec")
    x, t_now = x0, 0.0
    hits_t: list[float] = []
    hits_x: list[FloatArray] = []
    y_prev: FloatArray | None = None
    converged = False
    last: Trajectory | None = None
    while len(hits_t) < cfg.max_returns:
        tr = simulate(
            system,
            x,
            params,
            (t_now, t_now + cfg.chunk),
            events=[*events, sec],
            dt=cfg.transient_dt,
            rtol=cfg.transient_rtol,
            atol=cfg.transient_atol,
        )
        last = tr
        if tr.terminal_event is not None and tr.terminal_event in terminal:
            return fail(
                Status.EVENT,
                f"terminal event {tr.terminal_event!r} at t = {tr.t[-1]:.1f} from the guess",
                tr,
            )
        if not tr.status.ok:
            return fail(tr.status, tr.message, tr)
        h = tr.events["sec"]
        for tk, xk in zip(h.t, h.x, strict=True):
            yk = np.asarray(xk[others])
            hits_t.append(float(tk))
            hits_x.append(np.asarray(xk, dtype=float))
            if y_prev is not None and np.max(np.abs(yk - y_prev) / s_o) < cfg.return_tol:
                converged = True
                break
            y_prev = yk
        if converged:
            break
        x, t_now = tr.x[-1], float(tr.t[-1])
    if last is None:  # pragma: no cover - max_returns >= 1 runs the loop once
        raise ContinuationError("shoot_orbit: no transient simulated")
    if not converged:
        return fail(Status.MAX_ITER, f"returns did not settle in {len(hits_t)} returns", last)
    n_transient = len(hits_t)
    xa, xb = hits_x[-2], hits_x[-1]
    shift = int(round((xb[i] - xa[i]) / per_i)) if per_i > 0 else 0
    if direction is None and shift == 0:
        return fail(
            Status.UNDECIDED,
            f"the motion does not rotate through state {names[i]!r} (give `direction` "
            "for an oscillation)",
            last,
        )
    d = direction if direction is not None else (1 if shift > 0 else -1)
    period_est = hits_t[-1] - hits_t[-2]
    pmap = ReturnMap(system, params, i, section, d, 3.0 * period_est * max(abs(shift), 1), cfg)

    # ---- 2. Newton on P(y) - y
    variational = cfg.jacobian == "variational" or (
        cfg.jacobian == "auto" and bool(getattr(system, "has_casadi", False))
    )
    how = "variational" if variational else "fd"
    y = np.asarray(xb[others], dtype=float)
    status, msg = Status.NEWTON_FAILED, f"Newton did not converge in {cfg.max_newton} iterations"
    J = np.eye(len(others))
    res = math.inf
    try:
        for it in range(cfg.max_newton):
            py, t_ret, _ = pmap(y)
            g = py - y
            res = float(np.max(np.abs(g) / s_o))
            J = pmap.jacobian(y, t_ret) if variational else pmap.jacobian_fd(y, py, s_o)
            step = np.linalg.solve(J - np.eye(len(others)), -g)
            y = y + step
            if np.max(np.abs(step) / s_o) < cfg.tol and res < 1e3 * cfg.tol:
                status, msg = Status.SUCCESS, f"converged in {it + 1} Newton iterations"
                break
            if res < cfg.tol:
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
    closure = float(np.max(np.abs(py - y) / s_o))
    if variational and status is Status.SUCCESS:
        # DP at the solution itself (the loop's last one is at the previous iterate)
        try:
            J = pmap.jacobian(y, period)
        except ContinuationError as exc:
            status, msg = Status.NEWTON_FAILED, f"at the solution: {exc}"
        except KeyboardInterrupt:
            return fail(Status.INTERRUPTED, "interrupted during the Newton refinement", last)
    mult = np.linalg.eigvals(J)
    orbit = ShootingOrbit(
        system, params, i, pmap.full(y), section, period, shift, d, mult, closure, tr, status,
        msg, n_transient, time.perf_counter() - t_start, how,
    )  # fmt: skip
    if throw and status not in (Status.SUCCESS, Status.INTERRUPTED):
        raise ContinuationError(f"shoot_orbit: {msg}")
    log.debug("periodic orbit: %s, period %.6g, closure %.2e", msg, period, closure)
    return orbit


__all__ = ["JACOBIANS", "ShootingOrbit", "ReturnMap", "ShootingSettings", "shoot_orbit"]
