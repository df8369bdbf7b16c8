r"""The one entry point of one-parameter continuation: :func:`continue_branch`.

``continue_branch(problem, z0, p0, algorithm, settings)`` corrects the start point,
then repeats ``algorithm.step`` with adaptive step length, computing at every accepted
point the stability eigenvalues (once), the records and the test functions of the
special points and events; special points are detected by sign changes between
consecutive rows and located inside the step (:mod:`continuation.detection`). It stops at
``max_steps``, at a parameter bound (the last row is then exactly on the bound), at a
terminal event, when the branch closes on itself (periodic states compared modulo their
periods) or when the step falls below ``ds_min``; the reason is ``Branch.status``.

This module holds the entry point, the loop of one run (:func:`_run`), the merging of
the two directions and the assembly of the :class:`~continuation.branch.Branch`; the
rows and special points are :mod:`continuation.detection`'s, the eigenvalues of the
rows :mod:`continuation.row_eigs`'s and the step-size rule
:func:`~continuation.algorithms.base.adapt_ds`.
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from ._threads import blas_threads_for
from .algorithms.base import RETRY, ContinuationAlgorithm, adapt_ds
from .algorithms.corrector import CorrectorResult, correct
from .algorithms.palc import PALC
from .algorithms.point import oriented_point
from .arguments import finite_number
from .branch import Branch, BranchPoint, SpecialKind, SpecialPoint
from .detection import ProgressFn, Row, RunContext
from .errors import ContinuationError, ConvergenceError
from .events import Event
from .problem import (
    accept_hook,
    is_sparse,
    jacobian_is_stability,
    param_values,
    relabel,
    state_names,
)
from .row_eigs import run_checked
from .settings import ContinuationSettings
from .status import Status
from .typing import FloatArray

log = logging.getLogger(__name__)


#: ``|dp/ds|`` of the unit start tangent below which the start point counts as a fold
#: (the sign rule of the direction is then arbitrary; a warning says so).
_FOLD_START_TAU = 1e-8

_PREFIX = {
    SpecialKind.FOLD: "F",
    SpecialKind.HOPF: "H",
    SpecialKind.BRANCH_POINT: "BP",
}


@dataclass(eq=False)
class _Run:
    rows: list[Row] = field(default_factory=list)
    specials: list[SpecialPoint] = field(default_factory=list)
    status: Status = Status.MAX_STEPS
    message: str = ""
    arclength: float = 0.0


# ---------------------------------------------------------------------------- one run
def _run(
    ctx: RunContext,
    z0: FloatArray,
    p0: float,
    iters0: int,
    orient: FloatArray | None = None,
    warn_fold: bool = True,
) -> _Run:
    """One direction from ``(z0, p0)``.

    ``orient``: a direction the start tangent must point along (``theta``-inner product >
    0), overriding the sign rule of ``dp/ds``; ``warn_fold``: warn when the start point is a
    fold (the sign rule is arbitrary).
    """
    s = ctx.settings
    run = _Run()
    try:
        state = ctx.algorithm.init(ctx.problem, z0, p0, s)
        if orient is not None:
            state.point = oriented_point(state.point, state.w, orient)
    except np.linalg.LinAlgError as exc:
        run.status, run.message = Status.SINGULAR, f"no tangent at the start point: {exc}"
        return run
    if warn_fold and abs(float(state.point.tau[-1])) < _FOLD_START_TAU:
        log.warning(
            "the start point %s=%.10g is (numerically) a fold: dp/ds = %.1e there, so the "
            "direction of p does not tell the two halves of the branch apart; use "
            'direction="both" to follow both',
            ctx.problem.free,
            p0,
            float(state.point.tau[-1]),
        )
    state.point.iters = iters0
    row0 = ctx.make_row(state.point, 0.0)
    run.rows.append(row0)
    if ctx.progress is not None:
        ctx.progress(_branch_point(row0, 0))
    w = state.w
    far = 0.0
    grow_iters = ctx.grow_iters
    # (locals for the hot loop)
    step, problem, make_row, detect = ctx.algorithm.step, ctx.problem, ctx.make_row, ctx.detect
    stop_point, distance_to_start = ctx.stop_point, ctx.distance_to_start
    rows, max_steps = run.rows, s.max_steps
    # the eigenvalues are those of G_z itself (equilibria): a real one crossing zero is a
    # fold or branch point of this branch (not so for augmented codim-2 problems)
    count_guard = jacobian_is_stability(problem)
    p_at_bound = (p0 >= s.p_max and state.direction > 0) or (p0 <= s.p_min and state.direction < 0)
    if p_at_bound:
        run.status, run.message = Status.PARAM_BOUND, "the start point is on the parameter bound"
        return run
    try:
        while state.n_steps < max_steps:
            new_state, outcome = step(problem, state, s)
            if not outcome.converged:
                ds_new = adapt_ds(state.ds, outcome, s, grow_iters=grow_iters)
                log.debug(
                    "step rejected at p=%.6g (ds=%.3g): %s",
                    state.point.p,
                    state.ds,
                    outcome.message,
                )
                if ds_new < s.ds_min:
                    run.status = Status.DS_MIN
                    run.message = (
                        f"{Status.DS_MIN.value} Last point p={state.point.p:.10g}; last "
                        f"failure: {outcome.message}"
                    )
                    break
                state.ds = ds_new
                continue
            a = rows[-1]
            sigma_b = outcome.sigma
            b = make_row(new_state.point, sigma_b)
            ac, bc = a.counts, b.counts
            if (
                count_guard
                and ac is not None
                and bc is not None
                and abs(bc[0] - ac[0]) >= 2
                and bc[1] == ac[1]
                and state.ds > s.ds_min * (1 + 1e-12)
            ):
                # two or more real eigenvalues of G_z crossed zero in one step (the
                # complex count is unchanged, so no real pair merged into a complex one):
                # their folds / branch points cancel in the sign tests; shorten the step
                log.debug(
                    "%d real eigenvalues crossed 0 between p=%.8g and p=%.8g: step retried shorter",
                    abs(bc[0] - ac[0]),
                    a.p,
                    b.p,
                )
                state.ds = max(adapt_ds(state.ds, RETRY, s), s.ds_min)
                continue
            stop = stop_point(a, b, sigma_b, w)
            if stop is False:  # a bound crossed but not located: never keep a row outside
                ds_new = adapt_ds(state.ds, RETRY, s)
                if ds_new < s.ds_min:
                    run.status = Status.DS_MIN
                    run.message = (
                        f"{Status.DS_MIN.value} Last point p={state.point.p:.10g}; the "
                        "parameter bound was crossed but could not be located"
                    )
                    break
                state.ds = ds_new
                continue
            terminal = None
            if stop is not None:
                r, status, msg, k_event = stop
                if r.sigma < sigma_b:
                    b = ctx.make_row(r.point, r.sigma)
                    sigma_b = r.sigma
                run.status, run.message = status, msg
                if k_event is not None:
                    terminal = (k_event, r)
            index = len(rows) - 1
            if sigma_b > 0:
                found = detect(a, b, sigma_b, w, index, run.arclength, terminal)
                if found:
                    run.specials.extend(found)
            if stop is None or sigma_b > 0:
                rows.append(b)
                run.arclength += sigma_b
                if ctx.progress is not None:
                    ctx.progress(_branch_point(b, len(run.rows) - 1))
            if stop is not None:
                break
            dist0 = distance_to_start(rows[0], b, w)
            if (
                far >= 3.0 * sigma_b
                and dist0 <= 2.0 * sigma_b
                and ctx.closed(run.rows[0], a, b, w, far)
            ):
                run.status, run.message = Status.CLOSED_LOOP, Status.CLOSED_LOOP.value
                break
            far = max(far, dist0)
            new_state.ds = adapt_ds(new_state.ds, outcome, s, grow_iters=grow_iters)
            state = new_state
        else:
            run.status, run.message = Status.MAX_STEPS, Status.MAX_STEPS.value
    except KeyboardInterrupt:
        run.status, run.message = Status.INTERRUPTED, Status.INTERRUPTED.value
        log.warning("continuation interrupted after %d points", len(run.rows))
    return run


def _branch_point(row: Row, index: int) -> BranchPoint:
    ev = row.eig if row.eig is not None else np.zeros(0, complex)
    nu = -1 if row.counts is None else row.counts[0] + 2 * row.counts[1]
    return BranchPoint(
        index=index,
        p=row.p,
        x=row.z,
        eigenvalues=ev,
        n_unstable=nu,
        stable=nu == 0,
        ds=row.ds,
        newton_iters=row.iters,
        records=dict(row.records),
    )


# ---------------------------------------------------------------------------- assembling
def _relabel(specials: list[SpecialPoint]) -> tuple[SpecialPoint, ...]:
    count: dict[SpecialKind, int] = {}
    out = []
    for sp in specials:
        if sp.kind in _PREFIX:
            count[sp.kind] = count.get(sp.kind, 0) + 1
            sp = dataclasses.replace(sp, label=f"{_PREFIX[sp.kind]}{count[sp.kind]}")
        out.append(sp)
    return tuple(out)


def _merge(back: _Run, fwd: _Run) -> tuple[list[Row], list[float], list[SpecialPoint]]:
    """Rows ordered from the backward end to the forward end (start row once)."""
    m = len(back.rows) - 1
    rows: list[Row] = []
    ds: list[float] = []
    for j in range(m, 0, -1):
        rows.append(back.rows[j])
        ds.append(0.0 if j == m else back.rows[j + 1].ds)
    specials: list[SpecialPoint] = []
    s_back = back.arclength
    for sp in back.specials:
        specials.append(sp.reversed(m - sp.index - 1, s_back - sp.s))
    specials.reverse()
    for k, row in enumerate(fwd.rows):
        rows.append(row)
        ds.append((back.rows[1].ds if m >= 1 else 0.0) if k == 0 else row.ds)
    for sp in fwd.specials:
        specials.append(dataclasses.replace(sp, index=sp.index + m, s=sp.s + s_back))
    return rows, ds, specials


def _make_branch(
    problem: Any,
    rows: list[Row],
    ds: list[float],
    specials: list[SpecialPoint],
    status: Status,
    message: str,
    settings: ContinuationSettings,
    p0: float,
    n: int,
    events: Sequence[Event] = (),
) -> Branch:
    N = len(rows)
    eigs = [r.eig for r in rows]
    width = max((e.size for e in eigs if e is not None), default=0)
    if N and width and all(e is not None and e.size == width for e in eigs):
        eig = np.array(eigs, dtype=complex).reshape(N, width)  # (the common case at once)
    else:
        eig = np.full((N, width), np.nan + 0j)
        for k, e in enumerate(eigs):
            if e is not None:
                eig[k, : e.size] = e
    nun = np.array(
        [-1 if r.counts is None else r.counts[0] + 2 * r.counts[1] for r in rows], dtype=int
    ).reshape(N)
    keys: list[str] = []
    for r in rows:
        for key in r.records:
            if key not in keys:
                keys.append(key)
    records = {key: np.array([r.records.get(key, np.nan) for r in rows]) for key in keys}
    return Branch(
        problem=problem,
        free=str(problem.free),
        p=np.array([r.p for r in rows], dtype=float),
        x=np.array([r.z for r in rows], dtype=float).reshape(N, n),
        eigenvalues=eig,
        n_unstable=nun,
        ds=np.array(ds, dtype=float),
        newton_iters=np.array([r.iters for r in rows], dtype=int),
        records=records,
        special_points=relabel(problem, _relabel(specials)),
        status=status,
        message=message,
        settings=settings,
        state_names=state_names(problem, n),
        param_values=param_values(problem, p0),
        event_names=tuple(e.name for e in events),
    )


def _empty_branch(
    problem: Any,
    n: int,
    status: Status,
    message: str,
    settings: ContinuationSettings,
    p0: float,
    events: Sequence[Event] = (),
) -> Branch:
    return _make_branch(problem, [], [], [], status, message, settings, p0, n, events)


# ---------------------------------------------------------------------------- entry point
def check_run_arguments(
    settings: ContinuationSettings | None,
    algorithm: ContinuationAlgorithm | None,
    events: Sequence[Event],
) -> tuple[ContinuationSettings, ContinuationAlgorithm, tuple[Event, ...]]:
    """The checked ``settings``, ``algorithm`` and ``events`` of a continuation run.

    ``None`` gives the defaults (:class:`ContinuationSettings`, :class:`PALC`).

    Raises
    ------
    ValueError
        One line naming the argument of the wrong type.
    """
    settings = settings if settings is not None else ContinuationSettings()
    if not isinstance(settings, ContinuationSettings):
        raise ValueError(f"`settings` must be a ContinuationSettings, got {type(settings)}")
    algorithm = algorithm if algorithm is not None else PALC()
    if not isinstance(algorithm, ContinuationAlgorithm):
        raise ValueError(f"`algorithm` must be a ContinuationAlgorithm, got {algorithm!r}")
    events = tuple(events)
    for e in events:
        if not isinstance(e, Event):
            raise ValueError(f"`events` must contain Event instances, got {e!r}")
    return settings, algorithm, events


def continue_branch(
    problem: Any,
    z0: Any,
    p0: float,
    algorithm: ContinuationAlgorithm | None = None,
    settings: ContinuationSettings | None = None,
    *,
    events: Sequence[Event] = (),
    direction: Literal["forward", "backward", "both"] = "forward",
    throw: bool = False,
    progress: ProgressFn | None = None,
    start_fixed: int | None = None,
    start_orient: Any = None,
) -> Branch:
    r"""Continue the solutions of ``G(z, p) = 0`` in the free parameter ``p``.

    Parameters
    ----------
    problem : ContinuationProblem
        Residual, Jacobians, stability and records (:mod:`continuation.problem`).
    z0 : array_like, shape (N,)
        Start point, or a guess: it is first corrected by Newton's method at fixed
        ``p0`` (``settings.newton``).
    p0 : float
        Start value of the free parameter; must lie in ``[p_min, p_max]``.
    algorithm : ContinuationAlgorithm, optional
        Default :class:`~continuation.algorithms.palc.PALC`.
    settings : ContinuationSettings, optional
        Step control, bounds, corrector and detection settings. ``sign(ds)`` is the
        "forward" direction of ``p`` at the start.
    events : sequence of Event
        User events, detected and located like the built-in special points.
    direction : {"forward", "backward", "both"}
        ``"forward"`` follows ``sign(ds)``; ``"backward"`` the opposite; ``"both"`` runs
        backward, then forward, and returns ONE branch ordered from the backward end
        to the forward end (the start point appears once, at row ``len(backward) - 1``);
        special points are re-indexed and their ``bracket``, ``delta_unstable`` and
        ``tangent`` follow that order. ``max_steps`` applies to each direction.
    throw : bool
        Raise :class:`~continuation.errors.ConvergenceError` if the start point does
        not converge, and :class:`~continuation.errors.ContinuationError` if the branch
        ends in a numerical failure (``DS_MIN``, ``SINGULAR``, ...). Otherwise failures
        are reported in ``Branch.status``.
    progress : callable, optional
        ``progress(BranchPoint)`` after every accepted point (``index`` counts within
        the current direction).
    start_fixed : int, optional
        Index of an unknown of ``z`` held fixed in the start correction instead of
        ``p`` (then ``p0`` is corrected too): for a start where ``p`` is the better
        determined unknown, e.g. the period of a cycle near a homoclinic orbit, which
        is far more sensitive to ``p`` than ``p`` to it.
    start_orient : array_like, shape (N + 1,), optional
        A direction in ``(z, p)`` the first tangent of the forward run points along
        (positive ``theta``-weighted product; the backward run the opposite), instead
        of the sign of ``ds`` in ``p``: for a start where ``dp/ds`` is about zero
        (a fold, or a cycle near a homoclinic orbit). Not with ``direction="both"``.

    Returns
    -------
    Branch
        ``status`` says why it stopped; ``Status.INTERRUPTED`` (Ctrl-C) keeps the points
        computed so far.

    Raises
    ------
    ValueError
        Bad input: ``z0`` of the wrong shape or not finite, ``p0`` not finite or out of
        bounds, ``direction`` unknown, ``events`` not :class:`Event` instances.
    """
    settings, algorithm, events, z, p0 = _checked_inputs(
        problem, z0, p0, algorithm, settings, events, direction
    )
    n = z.size

    if start_fixed is not None and not (
        isinstance(start_fixed, (int, np.integer)) and -n <= int(start_fixed) < n
    ):
        raise ValueError(f"`start_fixed` must be an index of z (size {n}), got {start_fixed!r}")
    orient0 = None
    if start_orient is not None:
        if direction == "both":
            raise ValueError('`start_orient` cannot be used with direction="both"')
        orient0 = np.asarray(start_orient, dtype=float).reshape(-1)
        if orient0.shape != (n + 1,) or not np.all(np.isfinite(orient0)):
            raise ValueError(f"`start_orient` must be a finite vector of size {n + 1}")
    start = _correct_start(problem, z, p0, settings, start_fixed)
    if not start.converged:
        msg = f"start point did not converge at {problem.free}={p0:.10g}: {start.message}"
        log.warning(msg)
        if throw:
            raise ConvergenceError(msg)
        return _empty_branch(problem, n, Status.NEWTON_FAILED, msg, settings, p0, events)
    if start_fixed is not None:
        p0 = float(start.p)  # corrected with z[start_fixed] held

    accept = accept_hook(problem)  # the problem's life cycle: after every accepted row
    if accept is not None:
        user_progress = progress

        def on_row(bp: BranchPoint) -> None:
            accept(np.asarray(bp.x), float(bp.p))
            if user_progress is not None:
                user_progress(bp)

        progress = on_row
    ctx_args = (problem, algorithm)
    ds_abs = abs(settings.ds)
    sgn = 1.0 if settings.ds > 0 else -1.0

    def run_dir(sign: float, orient: FloatArray | None, rightmost: bool) -> _Run:
        st = dataclasses.replace(settings, ds=sign * ds_abs)
        ctx = RunContext(*ctx_args, st, events, progress, rightmost)
        return _run(ctx, start.z, p0, start.iters, orient,
                    warn_fold=direction != "both" and orient is None)  # fmt: skip

    def run_all(rightmost: bool) -> Branch:
        if direction == "both":
            back = run_dir(-sgn, None, rightmost)
            if back.status in (Status.INTERRUPTED, Status.CLOSED_LOOP) or not back.rows:
                # a closed loop is complete already; an interrupt stops everything
                fwd = _Run(rows=back.rows[:1], status=back.status, message=back.message)
            else:
                # the forward run leaves opposite to the backward one, whatever dp/ds is
                # (at a fold the sign of dp/ds cannot tell the two halves apart)
                fwd = run_dir(sgn, -back.rows[0].point.tau, rightmost)
            if back.rows:
                rows, ds, specials = _merge(back, fwd)
            else:
                rows, ds, specials = fwd.rows, [r.ds for r in fwd.rows], fwd.specials
            status, message = _combine(back, fwd)
        else:
            fwd_dir = direction == "forward"
            o = None if orient0 is None else (orient0 if fwd_dir else -orient0)
            one = run_dir(sgn if fwd_dir else -sgn, o, rightmost)
            rows, ds, specials = one.rows, [r.ds for r in one.rows], one.specials
            status, message = one.status, one.message
        return _make_branch(problem, rows, ds, specials, status, message, settings, p0, n, events)

    with blas_threads_for(n, is_sparse(problem)):
        br = run_checked(problem, settings, run_all)
    return _finish(br, throw)


def _checked_inputs(
    problem: Any,
    z0: Any,
    p0: Any,
    algorithm: ContinuationAlgorithm | None,
    settings: ContinuationSettings | None,
    events: Sequence[Event],
    direction: str,
) -> tuple[ContinuationSettings, ContinuationAlgorithm, tuple[Event, ...], FloatArray, float]:
    """The arguments of :func:`continue_branch` checked and with their defaults.

    Returns ``(settings, algorithm, events, z0 as float array (N,), p0 as float)``.

    Raises
    ------
    ValueError
        One line naming the argument (see :func:`continue_branch`).
    """
    settings, algorithm, events = check_run_arguments(settings, algorithm, events)
    if direction not in ("forward", "backward", "both"):
        raise ValueError(f"`direction` must be 'forward', 'backward' or 'both', got {direction!r}")
    n = int(problem.n_unknowns)
    z = np.asarray(z0, dtype=float)
    if z.shape != (n,):
        raise ValueError(f"`z0` must have shape ({n},), got {z.shape}")
    if not np.all(np.isfinite(z)):
        raise ValueError(f"`z0` contains NaN or inf: {z}")
    p0 = finite_number("p0", p0)
    if not settings.p_min <= p0 <= settings.p_max:
        raise ValueError(
            f"`p0`={p0} lies outside [p_min, p_max] = [{settings.p_min}, {settings.p_max}]"
        )
    return settings, algorithm, events, z, p0


def _correct_start(
    problem: Any,
    z: FloatArray,
    p0: float,
    settings: ContinuationSettings,
    fixed: int | None = None,
) -> CorrectorResult:
    """Newton's method on ``G(z, p0) = 0`` at fixed ``p0`` (bordered with ``e_p``).

    Or with the unknown ``z[fixed]`` held instead (bordered with its unit vector).
    """
    u0 = np.append(z, p0)
    e_p = np.zeros(u0.size)
    e_p[-1 if fixed is None else int(fixed) % z.size] = 1.0
    res = correct(problem, u0, u0, e_p, 0.0, settings.newton)
    if not res.converged and not res.message:
        res.message = "Newton did not converge"
    return res


def _combine(back: _Run, fwd: _Run) -> tuple[Status, str]:
    if Status.INTERRUPTED in (back.status, fwd.status):
        return Status.INTERRUPTED, Status.INTERRUPTED.value
    message = f"backward: {back.message}; forward: {fwd.message}"
    for run in (fwd, back):
        if not run.status.ok:
            return run.status, message
    return fwd.status, message


def _finish(branch: Branch, throw: bool) -> Branch:
    n_sp = len(branch.special_points)
    log.info(
        "branch in %s: %d points, %d special points, status %s",
        branch.free,
        len(branch),
        n_sp,
        branch.status.name,
    )
    if throw and not branch.status.ok and branch.status is not Status.INTERRUPTED:
        raise ContinuationError(branch.message or branch.status.value)
    return branch


__all__ = ["continue_branch"]
