r"""One cycle branch over segments: one driver run per mesh.

:func:`continue_once` is one run of the pseudo-arclength driver on one mesh (the PD,
NS, ``T_max`` and ``error_tol`` events); :func:`continue_segments` continues in segments
of a few steps, each on the mesh equidistributed on the last cycle of the one before
(more intervals where the error estimate passed ``error_tol``:
:func:`~continuation.periodic.solve.refined_intervals`), restarts along the secant of the
last step, ends the branch at a period limit (:func:`~continuation.periodic.limit.limit_end`)
or at a Hopf point where its cycles shrink to an equilibrium
(:func:`~continuation.periodic.collapse.hopf_end`) and merges the segments into one
branch (:func:`~continuation.periodic.rows.merge_segments`).
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..branch import Branch
from ..driver import continue_branch
from ..events import Event
from ..settings import ContinuationSettings
from ..status import Status
from ..typing import FloatArray
from .collapse import hopf_end
from .limit import limit_end
from .orbit import PeriodicOrbit
from .problem import PeriodicOrbitProblem
from .rows import merge_segments, orbit_at
from .solve import refine_start, refined_intervals

log = logging.getLogger(__name__)

#: Label of the terminal event that stops a segment where the error estimate reaches
#: ``error_tol`` (the next segment has more intervals).
ERR_EVENT = "error_tol"


def continue_once(
    orb: PeriodicOrbit,
    free: str,
    settings: ContinuationSettings,
    *,
    period_max: float | None,
    detect_pd: bool,
    detect_ns: bool,
    events: Sequence[Event],
    progress: Callable[[Any], None] | None,
    throw: bool,
    fix_period: bool = False,
    period_sign: float = 0.0,
    error_tol: float | None = None,
    previous: PeriodicOrbit | None = None,
) -> Branch:
    """One driver run on one mesh (PD/NS/T_max events, phase reference per step).

    ``fix_period``: the start is corrected at its period rather than its parameter;
    ``period_sign`` (+1/-1): the branch leaves the start with the period growing /
    shrinking (0: by the sign of ``settings.ds`` in the parameter); ``previous``: the
    cycle of the row before ``orb`` on the branch being continued, whose secant
    ``orb - previous`` (on ``orb``'s mesh) the first tangent follows instead (the
    direction of a restart is then right at folds and where the parameter hardly
    moves); ``error_tol``: a terminal event where the error estimate rises through it.
    """
    prob = PeriodicOrbitProblem.from_orbit(orb, free)
    T_col = prob.layout.T_col
    evs: list[Event] = []
    # the Floquet tests cost a condensation each: the sign test at the rows only
    # (no slopes off the branch), as the driver's built-in tests
    if detect_pd:
        evs.append(Event("PD", prob.pd_test, slope=False))
    if detect_ns:
        evs.append(Event("NS", prob.ns_test, slope=False))
    if period_max is not None:
        evs.append(Event("T_max", lambda z, p: period_max - z[T_col], terminal=True))
    if error_tol is not None:
        lay, errw = prob.layout, prob._errw  # type: ignore[attr-defined]

        def margin(z: FloatArray, p: float) -> float:
            return float(error_tol - errw(lay.split(np.asarray(z, dtype=float))[0]))

        evs.append(Event(ERR_EVENT, margin, direction="down", terminal=True, slope=False))
    evs.extend(events)

    # the driver runs prob.accept after every accepted row and prob.relabel on the
    # special points (the hooks of continuation.problem.ProblemHooks)
    return continue_branch(
        prob, prob.reference, orb.param(free), settings=settings, events=evs,
        throw=throw, progress=progress, start_fixed=T_col if fix_period else None,
        start_orient=(_period_orient(prob, period_sign) if previous is None
                      else _secant_orient(prob, orb, previous, free)),
    )  # fmt: skip


def _period_orient(prob: PeriodicOrbitProblem, sign: float) -> FloatArray | None:
    """The unit vector of the period in ``(z, p)`` times ``sign`` (None for 0)."""
    if sign == 0.0:
        return None
    e = np.zeros(prob.n_unknowns + 1)
    e[prob.layout.T_col] = math.copysign(1.0, sign)
    return e


def _secant_orient(
    prob: PeriodicOrbitProblem, orb: PeriodicOrbit, previous: PeriodicOrbit, free: str
) -> FloatArray:
    """The secant ``(z, p)`` from ``previous`` to ``orb``, both on ``orb``'s mesh."""
    prev = previous.on_mesh(orb.mesh)
    dz = prob.layout.join(orb.X - prev.X, orb.T - prev.T)
    return np.append(dz, orb.param(free) - previous.param(free))


def continue_segments(
    orb: PeriodicOrbit,
    free: str,
    settings: ContinuationSettings,
    every: int,
    run: dict[str, Any],
    error_tol: float | None = None,
    max_intervals: int = 400,
    previous: PeriodicOrbit | None = None,
) -> Branch:
    """Segments of ``every`` steps, each on an equidistributed mesh, merged into one branch.

    See :func:`continue_periodic`; with ``error_tol`` the number of intervals grows where
    the error estimate of a segment's last cycle exceeds it. ``previous``: as for
    :func:`continue_once`, for the first segment.

    Each segment after the first starts from the last cycle interpolated onto the
    equidistributed mesh; the driver's start correction (at fixed parameter) solves it
    there. Where that fails (near a homoclinic orbit the period is far more sensitive
    than the parameter) the start is corrected at fixed period instead, and where
    that fails too the old mesh is kept. Where the parameter hardly moves, the next
    segment leaves in the direction of growing (shrinking) period as the last did.
    """
    segs: list[Branch] = []
    left = settings.max_steps
    st = settings
    br = continue_once(orb, free, dataclasses.replace(st, max_steps=min(every, left)),
                       previous=previous, **run)  # fmt: skip
    checked = 0  # rows before this one were examined for a Hopf end
    while True:
        segs.append(br)
        left -= max(len(br) - 1, 0)
        merged = merge_segments(segs)
        end = hopf_end(merged, free, start=checked)
        if end is not None:
            return end
        checked = max(len(merged) - 1, 0)
        if error_tol is not None:
            end = limit_end(merged, free)
            if end is not None:
                return end
        at_tol = br.status == Status.EVENT and repr(ERR_EVENT) in br.message
        if at_tol and (left <= 0 or len(br) < 2):
            segs[-1] = dataclasses.replace(br, status=Status.MAX_STEPS,
                                           message=Status.MAX_STEPS.value)  # fmt: skip
        if not (br.status == Status.MAX_STEPS or at_tol) or left <= 0 or len(br) < 2:
            break
        last = orbit_at(br, len(br) - 1)
        err = float(br.records["error"][-1])
        if at_tol:  # (the row where the estimate reached the tolerance: grow the mesh)
            err = max(err, (1.0 + 1e-3) * error_tol)  # type: ignore[operator]
        n_new = refined_intervals(last, err, error_tol, max_intervals)
        if at_tol and n_new is None:
            msg = (
                f"{Status.DISCRETISATION_ERROR.value} The collocation error estimate reaches "
                f"error_tol={error_tol:g} at {free}={br.p[-1]:.10g} on "
                f"{last.mesh.n_intervals} intervals (max_intervals={max_intervals}); the "
                "branch up to there is kept."
            )
            log.warning(msg)
            segs[-1] = dataclasses.replace(br, status=Status.DISCRETISATION_ERROR, message=msg)
            break
        sgn = 1.0 if br.p[-1] >= br.p[-2] else -1.0
        ds = min(max(abs(float(br.ds[-1])), abs(st.ds)), st.ds_max)
        st = dataclasses.replace(st, ds=sgn * ds, max_steps=min(every, left))
        moved = last.on_mesh(last.mesh.equidistributed(last.X, n_new))
        if error_tol is not None:
            # the restart cycle itself within the tolerance (else the next segment's
            # rows start above it, and no crossing of it stops them)
            moved = refine_start(moved, free, error_tol, max_intervals, fix_period=True)
        # the restart leaves along the secant of the last step (at a fold, or near a
        # homoclinic orbit where the parameter hardly moves, its sign in p is noise)
        prev = orbit_at(br, len(br) - 2)
        nxt = continue_once(moved, free, st, previous=prev, **run)
        if len(nxt) == 0:
            log.info("restart on the adapted mesh failed at %s=%.8g: %s", free, br.p[-1],
                     nxt.message)  # fmt: skip
            nxt = continue_once(moved, free, st, fix_period=True, previous=prev, **run)
        if len(nxt) == 0 and not at_tol:
            log.warning("restart at fixed period failed at %s=%.8g (%s); mesh kept", free,
                        br.p[-1], nxt.message)  # fmt: skip
            nxt = continue_once(last, free, st, fix_period=True, previous=prev, **run)
        if len(nxt) == 0:
            # the restart on the new mesh failed (e.g. near a homoclinic orbit, where the
            # start correction at fixed parameter is ill-conditioned): keep the branch
            msg = (
                f"the restart after mesh adaptation failed at {free}={last.param(free):.10g} "
                f"({nxt.message}); the branch up to there is kept."
            )
            log.warning(msg)
            segs[-1] = dataclasses.replace(segs[-1], status=nxt.status, message=msg)
            break
        br = nxt
    return merge_segments(segs)


__all__ = ["ERR_EVENT", "continue_once", "continue_segments"]
