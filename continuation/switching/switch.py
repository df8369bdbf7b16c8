r"""Switch onto the branch crossing a computed one at a simple branch point.

:func:`switch_branch` checks its input, solves the algebraic bifurcation equation
(:func:`~continuation.switching.bifurcation_equation.crossing_tangents`), rejects
degenerate points by the size of its coefficients against the rows around the point,
corrects a start point on the crossing branch (:mod:`~continuation.switching.start`)
and continues from there with :func:`~continuation.driver.continue_branch`, the
tangent oriented along :math:`\pm t_{new}`. With ``direction="both"`` the run towards
:math:`u^*` passes through the branch point (where the driver detects it again, on the
new branch) into the other half; the rows next to :math:`u^*` are checked to lie on
the crossing branch (their offset from the current branch,
:math:`\langle\varphi_2, u - u^*\rangle_\theta`, must be at least half of
:math:`S \langle t_{new}, u - u^*\rangle_\theta`). Equations and references:
:mod:`continuation.switching`.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable, Sequence
from typing import Any, Literal

import numpy as np

from ..algorithms.base import ContinuationAlgorithm, theta_norm, theta_weights
from ..branch import Branch, BranchPoint, SpecialKind, SpecialPoint
from ..driver import check_run_arguments, continue_branch
from ..errors import ContinuationError, ConvergenceError
from ..events import Event
from ..problem import difference, linearize
from ..settings import ContinuationSettings
from ..status import Status
from ..typing import FloatArray
from .bifurcation_equation import CrossingTangents, solve_crossing_tangents
from .kernel import DENSE_KERNEL_MAX, dense
from .start import OrientedStart, offset_direction, start_point

log = logging.getLogger(__name__)

#: Rows near the branch point must have at least this fraction of the off-branch
#: offset that the crossing tangent predicts.
CROSSING_RATIO = 0.5

#: The ABE coefficients must be at least this fraction of their size estimated from the
#: rows around the point (``sigma_N(A) / distance``, which is first order in the distance
#: at a simple branch point); else the point is degenerate (e.g. cubic tangency).
ABE_DEGENERATE = 1e-3

#: Start points tried, the amplitude divided by 4 after each failure (a failed start
#: costs a few Newton iterations).
N_START_ATTEMPTS = 8

#: Runs tried through the branch point, the amplitude divided by 4 after a run that
#: fails the row check next to the branch point.
N_CROSSING_ATTEMPTS = 2

#: Below this sine of the crossing angle the default amplitude shrinks in proportion
#: (the start corrector's basin and the separation of the two branches near the branch
#: point scale with ``amplitude * sin(angle)``).
SMALL_ANGLE_SIN = 0.1

Direction = Literal["forward", "backward", "both"]


# ---------------------------------------------------------------------------- checks
def _check_crossing(
    br: Branch, ct: CrossingTangents, t_new: FloatArray, w: FloatArray, k0: int, side: float,
    amplitude: float,
) -> tuple[bool, int, float]:  # fmt: skip
    r"""Did the run from row ``k0`` through the branch point stay on the crossing branch?

    The run is the one on the ``side`` half of the crossing branch.

    Walks from row ``k0`` towards the branch point (decreasing row numbers for
    ``side = +1``) and checks every row within ``4 amplitude`` of ``u*`` and the first
    row past it: with ``d = u - u*``, ``s = <t_new, d>_theta`` and ``h = <phi2, d>_theta``,
    a row on the crossing branch has ``h ~ S s`` while one on the current branch has
    ``h ~ 0`` (``S = sin`` of the crossing angle). Returns ``(ok, first bad row, h / (S
    s) there)``; ``(True, -1, nan)`` when every checked row passes.
    """
    u_star = np.append(ct.z, ct.p)
    phi2, S = offset_direction(ct, t_new, w)
    step = -1 if side > 0 else 1
    k = k0 + step
    radius = 4.0 * amplitude
    while 0 <= k < len(br):
        d = _delta(br.problem, br.x[k], br.p[k], u_star[:-1], u_star[-1])
        s = float((w * t_new).dot(d))
        past = s * side <= 0
        near = theta_norm(d, w) <= radius
        if abs(s) > 1e-6 * amplitude and (near or past):
            ratio = float((w * phi2).dot(d)) / (S * s)
            if ratio < CROSSING_RATIO:
                return False, k, ratio
        if past and not near:
            break  # the first row past u* beyond the radius was the last one checked
        k += step
    return True, -1, math.nan


def _delta(problem: Any, z1: FloatArray, p1: float, z0: FloatArray, p0: float) -> FloatArray:
    """``(z1, p1) - (z0, p0)``, periodic states reduced modulo their period."""
    diff = difference(problem)
    dz = diff(z1, z0) if diff is not None else np.asarray(z1) - np.asarray(z0)
    return np.append(np.asarray(dz, dtype=float), float(p1) - float(p0))


def _slice(br: Branch, lo: int, hi: int) -> Branch:
    """Rows ``lo:hi`` of ``br`` with its special points inside them re-indexed."""
    s0 = float(br.arclength[lo]) if len(br) else 0.0
    ds = np.array(br.ds[lo:hi])
    if ds.size:
        ds[0] = 0.0
    sps = tuple(
        dataclasses.replace(sp, index=sp.index - lo, s=sp.s - s0)
        for sp in br.special_points
        if lo <= sp.index and sp.index + 1 < hi
    )
    return dataclasses.replace(
        br,
        p=br.p[lo:hi],
        x=br.x[lo:hi],
        eigenvalues=br.eigenvalues[lo:hi],
        n_unstable=br.n_unstable[lo:hi],
        ds=ds,
        newton_iters=br.newton_iters[lo:hi],
        records={k: v[lo:hi] for k, v in br.records.items()},
        special_points=sps,
    )


# ---------------------------------------------------------------------------- public API
def _resolve_point(branch: Branch, point: SpecialPoint | str) -> SpecialPoint:
    labels = [s.label for s in branch.special_points if s.label]
    if isinstance(point, str):
        matches = [s for s in branch.special_points if s.label == point]
        if not matches:
            raise ValueError(
                f"`point`: no special point labelled {point!r} on this branch; labels are {labels}"
            )
        sp_ = matches[0]
    elif isinstance(point, SpecialPoint):
        same = [
            s
            for s in branch.special_points
            if s is point
            or (
                s.kind == point.kind
                and s.label == point.label
                and s.p == point.p
                and np.shape(s.x) == np.shape(point.x)
                and np.array_equal(s.x, point.x)
            )
        ]
        if not same:
            raise ValueError(
                f"`point` ({point.label or point.kind.value} at p={point.p:.6g}) is not a "
                f"special point of `branch`; its special points are {labels}"
            )
        sp_ = point
    else:
        raise ValueError(
            f"`point` must be a SpecialPoint of `branch` or its label, got {type(point).__name__}"
        )
    if sp_.kind is not SpecialKind.BRANCH_POINT:
        raise ValueError(
            f"`point` must be a branch point (kind 'bp'), got {sp_.kind.value!r} "
            f"({sp_.label or '?'})"
        )
    if not sp_.located:
        raise ValueError(
            f"`point` {sp_.label or ''} was only bracketed, not located; branch switching "
            "needs a located branch point (tighten DetectionSettings or recompute the branch)"
        )
    return sp_


def _reference_tangent(branch: Branch, point: SpecialPoint, w: FloatArray) -> FloatArray:
    """Direction of the current branch at the point: the chord of the two rows around it.

    The tangent the locator stored is ill-determined exactly at a branch point, where the
    bordered matrix is singular.
    """
    i = int(point.index)
    if 0 <= i and i + 1 < len(branch):
        chord = _delta(branch.problem, branch.x[i + 1], branch.p[i + 1], branch.x[i], branch.p[i])
        if np.all(np.isfinite(chord)) and theta_norm(chord, w) > 0:
            return chord / theta_norm(chord, w)
    if point.tangent is not None and np.all(np.isfinite(point.tangent)):
        t = np.asarray(point.tangent, dtype=float)
        if t.shape == w.shape and theta_norm(t, w) > 0:
            return t / theta_norm(t, w)
    raise ValueError(
        f"`point` {point.label}: no rows of `branch` around it and no tangent, so the "
        "current branch's direction is unknown"
    )


def _row_abe_scale(problem: Any, branch: Branch, point: SpecialPoint, w: FloatArray) -> float:
    r"""Size of the ABE coefficients expected from the rows around the point.

    Along the current branch ``u(s) = u* + s t_old + ...`` the smallest singular value
    of ``A(u(s)) W^{-1/2}`` is ``|s| |c| + O(s^2)`` at a simple branch point (``c`` the
    ABE coefficients in a ``theta``-orthonormal basis), so ``sigma_N / ||u - u*||`` at
    the two rows estimates ``|c|``; returns the larger estimate (NaN when the problem is
    too large for dense SVDs or no row is usable).
    """
    n = int(problem.n_unknowns)
    if n > DENSE_KERNEL_MAX:
        return math.nan
    u_star = np.append(point.x, point.p)
    s = 1.0 / np.sqrt(w)
    est = math.nan
    for i in (point.index, point.index + 1):
        if not 0 <= i < len(branch):
            continue
        u = np.append(branch.x[i], branch.p[i])
        d = theta_norm(_delta(problem, u[:-1], u[-1], u_star[:-1], u_star[-1]), w)
        if not d > 1e-8 * max(1.0, theta_norm(u_star, w)):
            continue
        _, Gz, Gp = linearize(problem, u[:-1], float(u[-1]))
        A = np.column_stack((dense(Gz), Gp)) * s[None, :]
        try:
            sv = np.linalg.svd(A, compute_uv=False)
        except np.linalg.LinAlgError:
            continue
        e = float(sv[-1]) / d
        if math.isfinite(e):
            est = e if not math.isfinite(est) else max(est, e)
    return est


def _orient(t: FloatArray, sign_ds: float) -> FloatArray:
    """``t`` with ``sign(dp/ds) = sign_ds``.

    If ``t`` is (numerically) vertical, with its largest state component positive: the first
    of the components within a relative ``1e-3`` of the largest magnitude, so that mirror-
    symmetric problems (an antisymmetric kernel vector has two largest components of
    opposite sign, told apart only by round-off or by the point's own asymmetry, ~1e-5) are
    oriented the same way on every machine.
    """
    if abs(float(t[-1])) > 1e-6:
        return t if t[-1] * sign_ds > 0 else -t
    mag = np.abs(t[:-1])
    k = int(np.argmax(mag >= (1.0 - 1e-3) * mag.max()))
    return t if t[k] > 0 else -t


def _empty(
    branch: Branch, problem: Any, status: Status, message: str, settings: ContinuationSettings,
    events: Sequence[Event],
) -> Branch:  # fmt: skip
    n = int(problem.n_unknowns)
    return Branch(
        problem=problem,
        free=branch.free,
        p=np.zeros(0),
        x=np.zeros((0, n)),
        eigenvalues=np.zeros((0, n), dtype=complex),
        n_unstable=np.zeros(0, dtype=int),
        ds=np.zeros(0),
        newton_iters=np.zeros(0, dtype=int),
        records={},
        special_points=(),
        status=status,
        message=message,
        settings=settings,
        state_names=branch.state_names,
        param_values=branch.param_values,
        event_names=tuple(e.name for e in events),
    )


def switch_branch(
    branch: Branch,
    point: SpecialPoint | str,
    *,
    settings: ContinuationSettings | None = None,
    direction: Direction = "both",
    events: Sequence[Event] = (),
    amplitude: float | None = None,
    algorithm: ContinuationAlgorithm | None = None,
    throw: bool = False,
    progress: Callable[[BranchPoint], None] | None = None,
) -> Branch:
    r"""Continue the branch that crosses ``branch`` at the simple branch point ``point``.

    On a branch of cycles (``continue_periodic``) the crossing branch is a cycle branch
    continued by :func:`~continuation.periodic.branch_point.continue_from_branch_point`
    (Floquet tests, mesh adaptation, period limit; ``algorithm`` is not used there);
    otherwise :func:`switch_branch_rows` below does the whole continuation.
    """
    if isinstance(branch, Branch) and getattr(branch.problem, "is_cycle_problem", False):
        from ..periodic.branch_point import continue_from_branch_point

        return continue_from_branch_point(
            branch, point, settings, direction=direction, amplitude=amplitude, throw=throw,
            events=events, progress=progress,
        )  # fmt: skip
    return switch_branch_rows(
        branch, point, settings=settings, direction=direction, events=events,
        amplitude=amplitude, algorithm=algorithm, throw=throw, progress=progress,
    )  # fmt: skip


def switch_branch_rows(
    branch: Branch,
    point: SpecialPoint | str,
    *,
    settings: ContinuationSettings | None = None,
    direction: Direction = "both",
    events: Sequence[Event] = (),
    amplitude: float | None = None,
    algorithm: ContinuationAlgorithm | None = None,
    throw: bool = False,
    progress: Callable[[BranchPoint], None] | None = None,
) -> Branch:
    r"""The crossing branch at a simple branch point, continued by the driver itself.

    :func:`switch_branch` for any problem; on a cycle branch only its first rows serve
    (the driver alone would test the Floquet exponents for Hopf points and miss PD, NS
    and the mesh adaptation).

    The tangent of the crossing branch is the root of the algebraic bifurcation
    equation (module notes)

    .. math::

        c_{11}\alpha^2 + 2 c_{12}\alpha\beta + c_{22}\beta^2 = 0, \qquad
        c_{ij} = \psi^T D^2G(u^*)[q_i, q_j],

    that is not the current branch's (Keller 1977; Doedel, Keller & Kernevez 1991;
    Govaerts 2000; Kuznetsov 2004, Sec. 10.2). A start point at distance
    ``amplitude`` along it is corrected on a hyperplane parallel to the current branch,
    checked to lie on the crossing branch, and continued with
    :func:`~continuation.driver.continue_branch`.

    Parameters
    ----------
    branch : Branch
        A branch holding its problem (computed in this session, or loaded with
        ``Branch.load(path, problem)``).
    point : SpecialPoint or str
        A located branch point of ``branch`` (kind ``"bp"``), or its label, e.g.
        ``"BP1"``.
    settings : ContinuationSettings, optional
        Default ``branch.settings``. Bounds, ``ds_max``, ``max_steps`` (per direction),
        corrector and detection apply to the new branch; the first step is
        ``0.7 * amplitude`` (so that no step lands on the singular point) and grows
        from there. ``sign(ds)`` orients the new branch (below).
    direction : {"both", "forward", "backward"}
        ``"forward"``: the half of the crossing branch along ``+t_new``, the crossing
        tangent oriented so that ``sign(dp/ds) = sign(settings.ds)`` (where the
        crossing branch is vertical, ``dp/ds = 0``, as at a pitchfork: so that its
        largest state component is positive, the first one of those within 1e-3 of the
        largest magnitude); it starts at distance ``amplitude``
        from the branch point. ``"backward"``: the other half. ``"both"``: one branch
        ordered from the backward end through the branch point (detected again there,
        with any fold of the new branch at it) to the forward end.
    events : sequence of Event
        User events monitored along the new branch.
    amplitude : float, optional
        Distance (``theta`` norm, as ``ds``) of the start point from the branch
        point along the crossing tangent; default ``min(|ds|, 0.01 max(1,
        ||u*||_theta))``, times ``sin(angle) / 0.1`` when the branches cross at less
        than ~5.7 degrees. Divided by 4 after a start that cannot be corrected onto the
        crossing branch (up to 7 times) and after a run through the branch point that
        fails the row check (once).
    algorithm : ContinuationAlgorithm, optional
        Default :class:`~continuation.algorithms.palc.PALC`.
    throw : bool
        Raise :class:`~continuation.errors.ContinuationError` (a
        :class:`~continuation.errors.ConvergenceError` when no start point converges)
        instead of returning a failed branch.
    progress : callable, optional
        ``progress(BranchPoint)`` after every accepted point.

    Returns
    -------
    Branch
        The crossing branch; its message starts with the switching data (crossing
        angle). On failure an empty branch (or, if the run through the branch point
        left the crossing branch, the verified part on the start side) with
        ``status`` ``SINGULAR`` (not a simple branch point: degenerate ABE or kernel),
        ``NEWTON_FAILED`` (no start point on the crossing branch, or the run fell back
        onto ``branch``) or ``PARAM_BOUND`` (the requested half lies outside
        ``[p_min, p_max]``).

    Raises
    ------
    ValueError
        ``branch`` without a problem; ``point`` not a located branch point of
        ``branch``, or an unknown label; ``amplitude <= 0`` or not finite; unknown
        ``direction``; ``settings``/``algorithm`` of the wrong type.
    """
    if not isinstance(branch, Branch):
        raise ValueError(f"`branch` must be a Branch, got {type(branch).__name__}")
    problem = branch.problem
    if problem is None:
        raise ValueError(
            "`branch` has no problem (loaded from disk?): reload it with "
            "Branch.load(path, problem) to switch branches"
        )
    sp_ = _resolve_point(branch, point)
    if direction not in ("forward", "backward", "both"):
        raise ValueError(f"`direction` must be 'forward', 'backward' or 'both', got {direction!r}")
    if amplitude is not None:
        try:
            amplitude = float(amplitude)
        except (TypeError, ValueError):
            raise ValueError(f"`amplitude` must be a positive number, got {amplitude!r}") from None
        if not (math.isfinite(amplitude) and amplitude > 0):
            raise ValueError(f"`amplitude` must be a positive finite number, got {amplitude!r}")
    if settings is None:
        settings = branch.settings if branch.settings is not None else ContinuationSettings()
    settings, algorithm, events = check_run_arguments(settings, algorithm, events)
    n = int(problem.n_unknowns)
    z_star = np.asarray(sp_.x, dtype=float)
    if z_star.shape != (n,) or not np.all(np.isfinite(z_star)):
        raise ValueError(f"`point` has a state of shape {z_star.shape}, expected finite ({n},)")

    w = theta_weights(n, settings.theta)
    label = sp_.label or "the branch point"

    def fail(status: Status, msg: str, exc: type[ContinuationError] = ContinuationError) -> Branch:
        msg = f"branch switching at {label} ({branch.free}={sp_.p:.10g}) failed: {msg}"
        log.warning(msg)
        if throw:
            raise exc(msg)
        return _empty(branch, problem, status, msg, settings, events)

    ref = _reference_tangent(branch, sp_, w)
    ct = solve_crossing_tangents(
        problem, z_star, sp_.p, ref, settings.theta, "auto", False, DENSE_KERNEL_MAX
    )
    if ct.status is not Status.SUCCESS:
        return fail(ct.status, ct.message)
    est = _row_abe_scale(problem, branch, sp_, w)
    cmax = max(abs(c) for c in ct.coefficients)
    if math.isfinite(est) and est > 0 and cmax < ABE_DEGENERATE * est:
        return fail(
            Status.SINGULAR,
            f"the algebraic bifurcation equation is degenerate: its coefficients "
            f"(max {cmax:.3g}) are {cmax / est:.2g} times their size estimated from the "
            f"rows around the point ({est:.3g}); not a simple branch point",
        )
    sign_ds = 1.0 if settings.ds > 0 else -1.0
    t_new = _orient(ct.t_new, sign_ds)
    u_star = np.append(z_star, sp_.p)
    amp = amplitude
    if amp is None:
        amp = min(abs(settings.ds), 1e-2 * max(1.0, theta_norm(u_star, w)))
        amp *= min(1.0, ct.sin_angle / SMALL_ANGLE_SIN)
    info = (
        f"switched at {label} ({branch.free}={sp_.p:.10g}) onto the crossing branch "
        f"(angle {ct.angle_deg:.4g} deg, ABE coefficients "
        f"({ct.coefficients[0]:.4g}, {ct.coefficients[1]:.4g}, {ct.coefficients[2]:.4g}))"
    )
    if direction == "both":
        sides: tuple[float, ...] = (1.0, -1.0)  # either start will do; the other is spare
    else:
        sides = (1.0,) if direction == "forward" else (-1.0,)

    last_reason = ""
    n_start_fail = n_cross_fail = 0
    while n_start_fail < N_START_ATTEMPTS and n_cross_fail < N_CROSSING_ATTEMPTS:
        start: FloatArray | None = None
        side = 0.0
        out_of_bounds = 0
        for sd in sides:
            u, reason = start_point(problem, ct, t_new, amp, sd, w, settings.newton)
            if u is None:
                last_reason = reason
                continue
            if not settings.p_min <= u[-1] <= settings.p_max:
                out_of_bounds += 1
                last_reason = f"the start point {branch.free}={u[-1]:.10g} is outside the bounds"
                continue
            start, side = u, sd
            break
        if start is None:
            if out_of_bounds == len(sides):
                msg = (
                    f"the requested half of the crossing branch leaves [p_min, p_max] at "
                    f"once ({last_reason})"
                )
                return fail(Status.PARAM_BOUND, msg)
            log.info("amplitude %.3g: %s", amp, last_reason)
            n_start_fail += 1
            amp /= 4.0
            continue
        ds0 = min(max(0.7 * amp, settings.ds_min), settings.ds_max)
        run_settings = dataclasses.replace(settings, ds=ds0)
        br = continue_branch(
            problem,
            start[:-1],
            float(start[-1]),
            OrientedStart(algorithm, t_new),
            run_settings,
            events=events,
            direction=direction,
            throw=False,
            progress=progress,
        )
        if not len(br):
            if br.status is Status.INTERRUPTED:
                return br
            last_reason = br.message
            n_start_fail += 1
            amp /= 4.0
            continue
        if direction == "both" and br.status is not Status.INTERRUPTED:
            dist = [
                theta_norm(_delta(problem, br.x[k], br.p[k], start[:-1], start[-1]), w)
                for k in range(len(br))
            ]
            k0 = int(np.argmin(dist))
            ok, k_bad, ratio = _check_crossing(br, ct, t_new, w, k0, side, amp)
            if not ok:
                last_reason = (
                    f"the continuation through the branch point left the crossing branch "
                    f"(row {k_bad} at {branch.free}={br.p[k_bad]:.10g} has {ratio:.3g} of "
                    "the predicted offset from the current branch)"
                )
                log.info("amplitude %.3g: %s", amp, last_reason)
                n_cross_fail += 1
                if n_cross_fail < N_CROSSING_ATTEMPTS:
                    amp /= 4.0
                    continue
                kept = _slice(br, k_bad + 1, len(br)) if side > 0 else _slice(br, 0, k_bad)
                msg = (
                    f"{info}; {last_reason}: only the part on the start side is kept. "
                    "Try a smaller `amplitude` or `ds_max`."
                )
                log.warning(msg)
                if throw:
                    raise ContinuationError(msg)
                return dataclasses.replace(kept, status=Status.NEWTON_FAILED, message=msg)
        br = dataclasses.replace(br, message=f"{info}; {br.message}")
        log.info("%s: %d points, status %s", info, len(br), br.status.name)
        if throw and not br.status.ok and br.status is not Status.INTERRUPTED:
            raise ContinuationError(br.message)
        return br
    return fail(
        Status.NEWTON_FAILED,
        f"no start point on the crossing branch (amplitude down to {amp * 4:.3g}): {last_reason}",
        ConvergenceError,
    )


__all__ = ["DENSE_KERNEL_MAX", "Direction", "switch_branch", "switch_branch_rows"]
