r"""The upslope branch of the crest saddle's unstable manifold: one run, its fate, a guess.

Umeda (1999), Figs. 10-15: the *upslope* branch of the one-dimensional unstable
manifold of the crest saddle (``xi_G`` decreasing: the ship falls behind the crest and
the wave overtakes it) either passes the next crest (periodic, overtaken motion, below
the critical Fn) or is captured by the wave (it turns back down the slope into
broaching and capsize, or stable surf-riding at ``chi_c = 0``). Between the two it
lands on the neighbouring crest saddle one wavelength back: the heteroclinic
connection of :mod:`ship_models.analysis.critical_bvp`.

:func:`upslope_branch` integrates the branch through the engine's
:func:`continuation.dynamics.manifolds.unstable_manifold` (start ``x_s + eps v_u`` on the
tangent, ``v_u`` the unit eigenvector with ``xi_G`` decreasing) with terminal events
that decide its fate as soon as it is known. :func:`connection_guess` cuts such a run
into a starting orbit of the collocation solve, and :func:`guess_run` finds a run that
is usable as one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from continuation.dynamics import SimEvent, Trajectory
from continuation.dynamics import unstable_manifold as engine_unstable_manifold
from continuation.errors import ContinuationError
from continuation.params import Params
from continuation.status import Status
from continuation.typing import FloatArray

from ..contracts import VesselModel
from .crest_saddle import crest_saddle
from .events import capsize_event
from .fixed_points import FixedPoint
from .outcomes import ShipOutcome

#: Shift of ``xi_G/lambda`` from the crest saddle to the saddle the upslope branch meets.
UPSLOPE_SHIFT = -1.0
#: Largest distance (2-norm of the state) of a usable guess from the shifted saddle.
GUESS_REACH = 0.5
#: Bracket width at which the coarse search of :func:`guess_run` stops.
GUESS_WIDTH = 5e-3


@dataclass(frozen=True)
class UpslopeRun:
    """One simulation of the upslope branch of the crest saddle's unstable manifold.

    Attributes
    ----------
    trajectory : Trajectory
        From ``x_s + eps v_u`` (``xi_G`` unwrapped).
    saddle : FixedPoint
        The crest saddle (:func:`~ship_models.analysis.crest_saddle.crest_saddle`).
    params : Params
        The parameters of the run.
    fate : ShipOutcome
        ``PERIODIC`` (passed the next crest: ``xi_G < xi_s - 1.5``), ``CAPTURED``
        (capsized, turned back down the slope of the next wave: ``xi_G`` rose again
        above ``xi_s - 0.8``, or went down the slope of the same wave:
        ``xi_G > xi_s + 0.2``), or ``UNDECIDED`` (``t_max`` reached first, or failure).
    """

    trajectory: Trajectory
    saddle: FixedPoint
    fate: ShipOutcome
    params: Params

    @property
    def shift(self) -> float:
        """Shift of ``xi_G`` to the neighbouring saddle the branch passes closest to.

        ``-1`` (one wavelength back, :data:`UPSLOPE_SHIFT`) for the upslope branch of
        the paper; ``+1`` would mean the branch heads for the saddle ahead instead.
        """
        x = np.asarray(self.trajectory.x, dtype=float)
        i = list(self.trajectory.state_names).index("xi_G")
        d = {}
        for k in (-1.0, 1.0):
            target = self.saddle.x.copy()
            target[i] += k
            d[k] = float(np.min(np.linalg.norm(x - target, axis=1)))
        return -1.0 if d[-1.0] <= d[1.0] else 1.0

    def shifted_saddle(self) -> FloatArray:
        """The saddle ``x_s + shift e_xi``, shape (8,)."""
        target = self.saddle.x.copy()
        target[list(self.trajectory.state_names).index("xi_G")] += self.shift
        return target


def upslope_branch(
    model: VesselModel,
    params: Params,
    *,
    eps: float = 1e-6,
    t_max: float = 600.0,
    dt: float = 0.05,
    rtol: float = 1e-9,
    atol: float = 1e-11,
    saddle: FixedPoint | None = None,
) -> UpslopeRun:
    r"""Simulate the upslope branch ``x_s + eps v_u`` and classify its fate.

    The branch is integrated by :func:`continuation.dynamics.manifolds.unstable_manifold`
    (the ``-`` branch with ``v_u`` oriented so that ``xi_G`` increases, i.e. the start
    ``x_s - eps v_u``, saddle not refined again). Terminal events: capsize (``|phi|``
    beyond the angle of vanishing stability,
    :func:`~ship_models.analysis.events.capsize_event`), ``xi_G`` falling below
    ``xi_s - 1.5`` (beyond the neighbouring crest saddle: periodic motion), and
    ``xi_G`` rising back through ``xi_s - 0.8`` (the branch came down the slope of
    the next wave: surf-riding or broaching).

    Raises
    ------
    ValueError
        For ``eps`` outside (0, 1e-2) or a non-positive ``t_max``.
    ContinuationError
        No index-1 crest saddle at ``params``.
    KeyboardInterrupt
        If the integration was interrupted.
    """
    if not (math.isfinite(eps) and 0 < eps < 1e-2):
        raise ValueError(f"`eps` must be in (0, 1e-2), got {eps!r}")
    if not (math.isfinite(t_max) and t_max > 0):
        raise ValueError(f"`t_max` must be positive, got {t_max!r}")
    s = crest_saddle(model, params) if saddle is None else saddle
    i_xi = model.state_index("xi_G")
    xi_s = float(s.x[i_xi])
    passed = SimEvent(
        "passed",
        lambda t, x: x[..., i_xi] - (xi_s - 1.5),
        terminal=True,
        direction=-1,
        vectorized=True,
    )
    returned = SimEvent(
        "returned",
        lambda t, x: x[..., i_xi] - (xi_s - 0.8),
        terminal=True,
        direction=1,
        vectorized=True,
    )
    downslope = SimEvent(
        "downslope",
        lambda t, x: x[..., i_xi] - (xi_s + 0.2),
        terminal=True,
        direction=1,
        vectorized=True,
    )
    try:
        man = engine_unstable_manifold(
            model,
            np.asarray(params.values, dtype=float),
            s.x,
            eps=eps,
            t_max=t_max,
            events=[capsize_event(model), passed, returned, downslope],
            branches=(-1,),
            orient="xi_G",
            dt=dt,
            rtol=rtol,
            atol=atol,
            refine=False,
        )
    except ValueError as exc:  # not an index-1 saddle by the engine's test
        raise ContinuationError(f"upslope branch at {dict(params.items())}: {exc}") from None
    if man.minus is None or man.minus.trajectory.status is Status.INTERRUPTED:
        raise KeyboardInterrupt
    traj = man.minus.trajectory
    if traj.terminal_event == "passed":
        fate = ShipOutcome.PERIODIC
    elif traj.terminal_event in ("capsize", "returned", "downslope"):
        fate = ShipOutcome.CAPTURED
    else:
        fate = ShipOutcome.UNDECIDED
    return UpslopeRun(traj, s, fate, params)


def connection_guess(
    run: UpslopeRun, *, start_distance: float = 1e-3
) -> tuple[FloatArray, FloatArray]:
    """Cut an upslope-branch simulation into a guess of the connecting orbit.

    Starts where the branch is ``start_distance`` from the saddle and ends where it
    passes closest to the shifted saddle ``x_s + Delta``.

    Returns
    -------
    t : ndarray, shape (K,)
    x : ndarray, shape (K, 8)
    """
    tr = run.trajectory
    x = np.asarray(tr.x, dtype=float)
    d0 = np.linalg.norm(x - run.saddle.x, axis=1)
    d1 = np.linalg.norm(x - run.shifted_saddle(), axis=1)
    i1 = int(np.argmin(d1))
    far = np.nonzero(d0 >= start_distance)[0]
    i0 = int(far[0]) if far.size else 0
    if i1 - i0 < 4:
        raise ContinuationError(
            "the upslope branch does not travel towards the neighbouring crest saddle; "
            "no connection guess"
        )
    return np.asarray(tr.t[i0 : i1 + 1]), x[i0 : i1 + 1]


def _try_guess(
    model: VesselModel, params: Params, reasons: list[str] | None = None
) -> tuple[UpslopeRun | None, ShipOutcome]:
    """The upslope branch at ``params`` and its fate; the run is None if unusable as a guess.

    Where the branch cannot be computed (no crest saddle of index 1 there, ...), the
    reason is appended to ``reasons``."""
    try:
        # a guess needs no accuracy: start 1e-4 off the saddle (integrator errors
        # ~1e-6 stay well below that), sample every 0.1 s
        run = upslope_branch(model, params, eps=1e-4, rtol=1e-7, atol=1e-9, dt=0.1)
    except ContinuationError as exc:
        if reasons is not None:
            reasons.append(f"{float(params['Fn']):.6g}|{str(exc).split(':')[0]}")
        return None, ShipOutcome.UNDECIDED
    x = np.asarray(run.trajectory.x, dtype=float)
    far = np.min(np.linalg.norm(x - run.shifted_saddle(), axis=1)) > GUESS_REACH
    if run.fate is ShipOutcome.UNDECIDED or far:
        return None, run.fate
    return run, run.fate


def _failed_attempts(reasons: list[str], attempts: int) -> str:
    """Why the branch could not be computed: the first reason where every attempt failed
    (e.g. no crest saddle at any Fn tried), else the Fn values where it failed."""
    if not reasons:
        return ""
    if len(reasons) == attempts:
        return f" ({reasons[0].split('|', 1)[1]}; likewise at every Fn tried)"
    fns = ", ".join(r.split("|", 1)[0] for r in reasons)
    return f" (no upslope branch could be computed at Fn = {fns})"


def guess_run(model: VesselModel, params: Params, bracket: tuple[float, float]) -> UpslopeRun:
    """A simulated upslope branch near the critical ``Fn``, usable as a connection guess.

    The branch at ``params`` if it comes within :data:`GUESS_REACH` of the shifted
    saddle; otherwise a coarse search of ``Fn`` in ``bracket``, halving on the fate of
    the midpoint until the interval is :data:`GUESS_WIDTH` wide, keeping the last usable
    branch. (Not a fate bisection: the ends are not simulated, only the midpoints, and
    it stops at the first undecided fate with what it has.)

    Raises
    ------
    ValueError
        For a bad ``bracket``.
    ContinuationError
        If no simulated branch approaches the shifted saddle.
    """
    reasons: list[str] = []
    run, _ = _try_guess(model, params, reasons)
    if run is not None:
        return run
    lo, hi = (float(b) for b in bracket)
    if not (0 < lo < hi and math.isfinite(hi)):
        raise ValueError(f"`guess_bracket` must be (Fn_lo, Fn_hi) with 0 < lo < hi, got {bracket}")
    best: UpslopeRun | None = None
    attempts = 1
    while hi - lo > GUESS_WIDTH:
        mid = 0.5 * (lo + hi)
        attempts += 1
        r, fate = _try_guess(model, params.replace(Fn=mid), reasons)
        best = r or best
        if fate is ShipOutcome.PERIODIC:
            lo = mid
        elif fate is ShipOutcome.CAPTURED:
            hi = mid
        else:
            break
    if best is None:
        raise ContinuationError(
            f"no usable guess of the connection at chi_c = "
            f"{math.degrees(float(params['chi_c'])):.4g} deg: the upslope branch does not "
            f"approach the shifted crest saddle at Fn_guess = {float(params['Fn']):.6g} nor "
            f"for Fn in ({float(bracket[0]):.6g}, {float(bracket[1]):.6g})"
            + _failed_attempts(reasons, attempts)
        )
    return best


__all__ = [
    "GUESS_REACH",
    "UPSLOPE_SHIFT",
    "UpslopeRun",
    "connection_guess",
    "guess_run",
    "upslope_branch",
]
