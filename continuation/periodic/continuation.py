r"""Continuation of periodic orbits: :func:`continue_periodic` and its helpers.

The branch is computed by the ordinary pseudo-arclength driver
(:func:`~continuation.driver.continue_branch`) on a
:class:`~continuation.periodic.problem.PeriodicOrbitProblem`. Special points of
cycles (see :mod:`continuation.periodic.floquet`):

* ``LPC`` -- fold of cycles: the driver's fold (kind ``fold``, relabelled ``LPC1``...);
* ``BPC`` -- branch point of cycles: the driver's branch point (kind ``bp``, ``BPC1``);
* ``PD`` -- period doubling, a located zero of :math:`\prod (\mu_i + 1)` (kind
  ``pd``, labelled ``"PD"``; ``br.find("pd")``); :func:`switch_period_doubling` starts
  the doubled branch;
* ``NS`` -- Neimark-Sacker, a located zero of :math:`\prod_{i<j} (\mu_i \mu_j - 1)`
  with a complex pair on the unit circle (kind ``ns``, labelled ``"NS"``; neutral
  saddles dropped).

All carry the driver's ``located`` flag and ``bracket``. The driver's Hopf test is
switched off on cycle branches (its eigenvalues are Floquet exponents). PD and NS, like
the driver's built-in tests, are detected by a sign change between rows only (events
with ``slope=False``: no evaluation of the multipliers off the branch); two such points
inside one step cancel and are not seen.

*Period without bound.* With ``period_max``, a terminal event stops the branch where
``T`` reaches it; the branch then ends with ``Status.PERIOD_UNBOUNDED`` and a message
giving the last period and parameter, and :func:`period_limit` fits
:math:`T \approx a - b \ln|p^* - p|` to the last rows (the law of a cycle approaching a
homoclinic or heteroclinic orbit of saddles) and returns the limit ``p*`` with a
guess of the connecting orbit for a connection solver.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import scipy.optimize as so

from .._threads import blas_threads_for
from ..branch import Branch, SpecialKind, SpecialPoint
from ..bvp.accuracy import discretisation_changes
from ..bvp.collocation import CollocationMesh
from ..driver import continue_branch
from ..errors import ConvergenceError
from ..events import Event
from ..params import Params
from ..settings import ContinuationSettings
from ..status import Status
from ..system import as_params
from ..typing import FloatArray
from .orbit import PeriodicOrbit, orbit_from_array, winding_vector
from .problem import PeriodicOrbitProblem
from .solve import (
    CycleSolve,
    adapt_mesh,
    cycle_resolves,
    refine_start,
    refined_intervals,
    solve_orbit,
)

log = logging.getLogger(__name__)

#: Rows whose trivial multiplier is farther than this from 1 have unreliable
#: multipliers (the discretisation error, amplified by the cycle's sensitivity); the
#: branch message says so.
TRIVIAL_TOL = 1e-3


#: Default tolerance of the collocation error estimate of :func:`continue_periodic`
#: (states' units): the mesh adapts and grows to keep every row within it (AUTO-07p, too,
#: adapts its mesh by default).
ERROR_TOL = 1e-6

#: A branch ends with ``Status.PERIOD_UNBOUNDED`` where the period grows without bound and
#: the parameter is within this many times its discretisation error (``|p_{2N} - p_N|``
#: at fixed period) of the limit ``p*`` fitted to ``T = a - b ln|p* - p|`` (beyond that
#: the rows cannot tell on which side of ``p*`` they are).
LIMIT_MARGIN = 10.0

#: Rows count as within ``error_tol`` up to this factor (the row where a segment stopped
#: has the estimate at the tolerance to the locator's accuracy).
ERROR_SLACK = 1.01

#: Label of the terminal event that stops a segment where the error estimate reaches
#: ``error_tol`` (the next segment has more intervals).
_ERR_EVENT = "error_tol"

#: Without ``error_tol``, rows whose collocation error estimate exceeds this fraction of
#: the cycle's range (largest ``max - min`` of a state) are named in the branch's
#: message: a cycle drawn on too coarse a mesh (e.g. a relaxation oscillation whose
#: fast jumps outgrow the mesh as a parameter grows) is not reported silently.
ERROR_NOTE_REL = 1e-4


def _as_orbit(system: Any, start: Any, params: Any, mesh: CollocationMesh | None,
              winding: Any) -> PeriodicOrbit:  # fmt: skip
    if isinstance(start, PeriodicOrbit):
        orb = start
        params = as_params(system, params)
        orb = dataclasses.replace(orb, params=params)
        if mesh is not None and (
            mesh.degree != orb.mesh.degree or mesh.n_intervals != orb.mesh.n_intervals
        ):
            orb = orb.on_mesh(mesh)
        return orb
    if hasattr(start, "t") and hasattr(start, "x"):
        return orbit_from_array(system, params, start.t, start.x, mesh=mesh, winding=winding)
    if isinstance(start, tuple) and len(start) == 2:
        return orbit_from_array(system, params, start[0], start[1], mesh=mesh, winding=winding)
    raise ValueError(
        "`orbit_start` must be a PeriodicOrbit, a (t, x) pair of arrays or a Trajectory, "
        f"got {type(start).__name__}"
    )


def continue_periodic(
    system: Any,
    orbit_start: Any,
    params: Any,
    free: str,
    settings: ContinuationSettings | None = None,
    *,
    mesh: CollocationMesh | None = None,
    winding: Any = None,
    period_max: float | None = None,
    detect_pd: bool = True,
    detect_ns: bool = True,
    events: Sequence[Event] = (),
    direction: Literal["forward", "backward", "both"] = "forward",
    progress: Callable[[Any], None] | None = None,
    throw: bool = False,
    adapt_every: int = 0,
    error_tol: float | None = ERROR_TOL,
    max_intervals: int = 400,
) -> Branch:
    r"""Continue a branch of periodic orbits in the parameter ``free``.

    Parameters
    ----------
    system : System
    orbit_start : PeriodicOrbit, (t, x) pair or Trajectory
        The start cycle or a guess of it (one period of samples, periodic states
        unwrapped); corrected by Newton's method at ``params`` first.
    params : Params, mapping or array
        Parameter values at the start.
    free : str
        Continuation parameter.
    settings : ContinuationSettings, optional
        As for :func:`~continuation.driver.continue_branch`; ``detect.hopf`` is forced
        off (see the module doc).
    mesh : CollocationMesh, optional
        Mesh for a ``(t, x)`` guess (default 40 intervals, degree 4), or a new mesh
        size for a :class:`PeriodicOrbit` start (interpolated onto it).
    winding : mapping of str to int, optional
        Rotation numbers of periodic states for a ``(t, x)`` guess (a
        :class:`PeriodicOrbit` carries its own).
    period_max : float, optional
        Stop where the period reaches this value (``Status.PERIOD_UNBOUNDED``).
    detect_pd, detect_ns : bool
        Monitor the period-doubling and Neimark-Sacker test functions.
    events : sequence of Event
        More user events, ``fn(z, p)`` of the cycle unknowns.
    direction : {"forward", "backward", "both"}
        ``"both"``: backward, then forward from the start cycle, returned as one
        branch from the backward end to the forward end (``max_steps`` per direction;
        the status is the forward run's, the backward run's reason is in the
        message).
    progress : callable, optional
        Called with every accepted :class:`~continuation.branch.BranchPoint`.
    throw : bool
        As for :func:`~continuation.driver.continue_branch`.
    adapt_every : int
        ``> 0``: continue in segments of this many steps and equidistribute the mesh
        (same number of intervals) on the last cycle of each segment before the next
        (:func:`adapt_mesh`); ``settings.max_steps`` counts all steps. The branch's
        ``problem`` is then a :class:`CycleSegments` (one problem per mesh; use
        :func:`problem_at` and :func:`orbit_at`). 0: one mesh throughout (10 with
        ``error_tol``).
    error_tol : float or None
        Tolerance of the collocation error estimate (record ``error``,
        :func:`~continuation.periodic.problem.error_estimate`, in the states' units;
        default :data:`ERROR_TOL`). The start cycle is refined first where its
        estimate exceeds it; a segment stops at the row where the estimate reaches it
        (a terminal event) and the next one continues on a mesh of more intervals,
        :math:`N' = \lceil 1.2 N (2 e/\text{tol})^{1/(m+1)} \rceil` (at most
        ``max_intervals``), so that every row is within the tolerance; where
        ``max_intervals`` cannot keep it, the branch ends there with
        ``Status.DISCRETISATION_ERROR``, and a branch with rows above it never ends
        with an ``ok`` status. Implies ``adapt_every = 10`` when ``adapt_every`` is 0.
        With a tolerance, a branch whose period grows without bound (a cycle
        approaching a homoclinic or heteroclinic orbit) ends with
        ``Status.PERIOD_UNBOUNDED`` even without ``period_max``: where the parameter
        comes within :data:`LIMIT_MARGIN` times its discretisation error of the fitted
        limit, before the rows could pass it. ``None``: one fixed mesh (unless
        ``adapt_every``), as AUTO-07p with ``IAD = 0``; the error of a cycle whose
        period grows or whose jumps sharpen then grows with it, rows whose estimate
        exceeds :data:`ERROR_NOTE_REL` of the cycle's range are named in the branch's
        message (``records["error"]`` holds every row's estimate), and nothing stops a
        branch at a homoclinic end but ``period_max``.
    max_intervals : int
        Cap on the number of intervals for ``error_tol``.

    Returns
    -------
    Branch
        Rows: the unknowns ``[vec X, T]`` (:func:`orbit_at` gives the cycle; where
        ``error_tol`` added intervals, rows of the coarser meshes are NaN-padded), records
        ``T``, ``max_*``, ``min_*``, ``L2``,
        ``mu_max``, ``trivial_error``, ``error``; ``eigenvalues`` are the Floquet
        exponents ``ln|mu| + i arg mu`` (nontrivial ones; :func:`multipliers` gives the
        multipliers); ``stable`` is "all nontrivial ``|mu| < 1``".

    Raises
    ------
    ValueError
        Bad input (names, shapes, ``period_max``, ``direction``).
    ConvergenceError
        With ``throw=True``, if the start cycle does not converge.
    """
    if free not in system.param_names:
        raise ValueError(f"`free` must be one of {system.param_names}, got {free!r}")
    if direction not in ("forward", "backward", "both"):
        raise ValueError(f"`direction` must be 'forward', 'backward' or 'both', got {direction!r}")
    if period_max is not None and not (math.isfinite(period_max) and period_max > 0):
        raise ValueError(f"`period_max` must be a positive number, got {period_max!r}")
    if winding is not None:
        winding_vector(system, winding)
    if isinstance(adapt_every, bool) or not (isinstance(adapt_every, int) and adapt_every >= 0):
        raise ValueError(f"`adapt_every` must be an integer >= 0, got {adapt_every!r}")
    if error_tol is not None:
        if not (isinstance(error_tol, (int, float)) and math.isfinite(error_tol) and error_tol > 0):
            raise ValueError(f"`error_tol` must be a positive number, got {error_tol!r}")
        adapt_every = adapt_every or 10
    if isinstance(max_intervals, bool) or not (
        isinstance(max_intervals, int) and max_intervals >= 2
    ):
        raise ValueError(f"`max_intervals` must be an integer >= 2, got {max_intervals!r}")
    orb = _as_orbit(system, orbit_start, params, mesh, winding)
    if error_tol is not None:
        orb = refine_start(orb, free, error_tol, max_intervals)
    settings = settings if settings is not None else ContinuationSettings()
    settings = dataclasses.replace(
        settings, detect=dataclasses.replace(settings.detect, hopf=False)
    )
    run = dict(period_max=period_max, detect_pd=detect_pd, detect_ns=detect_ns,
               events=events, progress=progress, throw=throw,
               error_tol=error_tol)  # fmt: skip

    def one(st: ContinuationSettings) -> Branch:
        if adapt_every == 0 and error_tol is None:
            return _continue_once(orb, free, st, **run)  # type: ignore[arg-type]
        return _continue_segments(orb, free, st, adapt_every, run, error_tol, max_intervals)

    back = dataclasses.replace(settings, ds=-settings.ds)
    # one BLAS thread for the whole run, the start corrections and mesh adaptations
    # included (the driver limits only its own steps): the blocks are small, and on a
    # loaded 2-core machine OpenBLAS's second thread made the condensed factorisations
    # of AUTO's demo ab up to 100x slower (benchmarks/README.md)
    with blas_threads_for(orb.X.size, sparse=True):
        if direction == "forward":
            br = one(settings)
        elif direction == "backward":
            br = one(back)
        else:
            b, f = one(back), one(settings)
            if len(b) == 0 or len(f) == 0:
                br = f if len(f) else b
            else:
                br = _merge_segments([_reverse(b), f])
                br = dataclasses.replace(
                    br, message=f"{f.message} (backward end: {b.status.name}: {b.message})"
                )
        return _finish(br, free, period_max, error_tol)


def _segments_of(br: Branch) -> tuple[list[PeriodicOrbitProblem], list[int]]:
    prob = br.problem
    if isinstance(prob, CycleSegments):
        return list(prob.problems), list(prob.first_row)
    return [prob], [0]


def _reverse(br: Branch) -> Branch:
    """The branch in the opposite order (rows, steps, special points, segments)."""
    N = len(br)
    probs, first = _segments_of(br)
    ends = [f - 1 for f in first[1:]] + [N - 1]  # last row of each segment
    problem: Any = br.problem
    if len(probs) > 1:
        problem = CycleSegments(tuple(probs[::-1]), tuple(N - 1 - e for e in ends[::-1]))
    return br.reversed(problem=problem)


def _continue_once(
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

        evs.append(Event(_ERR_EVENT, margin, direction="down", terminal=True, slope=False))
    evs.extend(events)

    # the driver runs prob.accept after every accepted row and prob.relabel on the
    # special points (the hooks of continuation.problem.ProblemHooks)
    return continue_branch(
        prob, prob.reference, orb.param(free), settings=settings, events=evs,
        throw=throw, progress=progress, start_fixed=T_col if fix_period else None,
        start_orient=(_period_orient(prob, period_sign) if previous is None
                      else _secant_orient(prob, orb, previous, free)),
    )  # fmt: skip


@dataclass(frozen=True, eq=False)
class CycleSegments:
    """The problems of a cycle branch computed on several meshes (``adapt_every``).

    Attributes
    ----------
    problems : tuple of PeriodicOrbitProblem
        One per segment (each with its own mesh).
    first_row : tuple of int
        Branch row where each segment starts.
    """

    problems: tuple[PeriodicOrbitProblem, ...]
    first_row: tuple[int, ...]

    @property
    def free(self) -> str:
        """The continuation parameter."""
        return self.problems[0].free

    @property
    def system(self) -> Any:
        """The dynamical system."""
        return self.problems[0].system

    @property
    def params(self) -> Params:
        """The parameters of the first segment."""
        return self.problems[0].params

    def at_row(self, k: int) -> PeriodicOrbitProblem:
        """The problem (mesh) of branch row ``k``."""
        i = int(np.searchsorted(np.asarray(self.first_row), k, side="right")) - 1
        return self.problems[max(i, 0)]


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


def _continue_segments(
    orb: PeriodicOrbit,
    free: str,
    settings: ContinuationSettings,
    every: int,
    run: dict[str, Any],
    error_tol: float | None = None,
    max_intervals: int = 400,
) -> Branch:
    """Segments of ``every`` steps, each on an equidistributed mesh, merged into one branch.

    See :func:`continue_periodic`; with ``error_tol`` the number of intervals grows where
    the error estimate of a segment's last cycle exceeds it.

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
    br = _continue_once(orb, free, dataclasses.replace(st, max_steps=min(every, left)), **run)
    while True:
        segs.append(br)
        left -= max(len(br) - 1, 0)
        if error_tol is not None:
            end = _limit_end(_merge_segments(segs), free)
            if end is not None:
                return end
        at_tol = br.status == Status.EVENT and repr(_ERR_EVENT) in br.message
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
        nxt = _continue_once(moved, free, st, previous=prev, **run)
        if len(nxt) == 0:
            log.info("restart on the adapted mesh failed at %s=%.8g: %s", free, br.p[-1],
                     nxt.message)  # fmt: skip
            nxt = _continue_once(moved, free, st, fix_period=True, previous=prev, **run)
        if len(nxt) == 0 and not at_tol:
            log.warning("restart at fixed period failed at %s=%.8g (%s); mesh kept", free,
                        br.p[-1], nxt.message)  # fmt: skip
            nxt = _continue_once(last, free, st, fix_period=True, previous=prev, **run)
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
    return _merge_segments(segs)


def _truncated(br: Branch, k: int, status: Status, message: str) -> Branch:
    """Rows ``0 .. k`` of a cycle branch (with the special points between them)."""
    probs, first = _segments_of(br)
    keep = [i for i, f in enumerate(first) if f <= k] or [0]
    problem: Any = br.problem
    if isinstance(problem, CycleSegments):
        problem = CycleSegments(tuple(probs[i] for i in keep), tuple(first[i] for i in keep))
    return dataclasses.replace(
        br,
        problem=problem,
        p=br.p[: k + 1],
        x=br.x[: k + 1],
        eigenvalues=br.eigenvalues[: k + 1],
        n_unstable=br.n_unstable[: k + 1],
        ds=br.ds[: k + 1],
        newton_iters=br.newton_iters[: k + 1],
        records={name: v[: k + 1] for name, v in br.records.items()},
        special_points=tuple(sp for sp in br.special_points if sp.index < k),
        status=status,
        message=message,
    )


def _limit_end(br: Branch, free: str, n_tail: int = 8) -> Branch | None:
    r"""The end of a branch whose period grows without bound, or None.

    The branch ended where its period grows without bound and its parameter has come within
    its own error of the limit; None while it has not.

    Near a homoclinic or heteroclinic orbit of saddles ``p = p^* + c e^{-T/b}``. Where
    the period grew over the last ``n_tail`` rows and the parameter moved one way (or
    has stalled at round-off), ``p*`` is fitted
    (:func:`period_limit`), and where the parameter has nearly converged to it the
    parameter's discretisation error is estimated by re-solving the last cycle at its
    period on the mesh with every interval halved, ``delta = |p_{2N} - p_N|``. Rows
    within ``LIMIT_MARGIN delta + 1e-12 (1 + |p*|)`` of ``p*`` (the last term the
    round-off of ``p``) cannot tell on which side of the limit they are: the branch is
    cut before the first of them, with ``Status.PERIOD_UNBOUNDED``. A discretised
    cycle does not see the end (on a finite mesh the period stays finite and the rows
    may pass ``p*``, where no cycle exists), so this is where the branch must stop.
    Only where the fit is as good as that bound: a cycle snaking towards a
    saddle-focus loop (Shilnikov; cycles on both sides of ``p*``) is not ended here.
    """
    n = len(br)
    if n < n_tail + 2:
        return None
    T = np.asarray(br.records["T"][-n_tail:], dtype=float)
    p_tail = np.asarray(br.p[-n_tail:], dtype=float)
    if not np.all(np.diff(T) > 0):
        return None
    dp = np.diff(p_tail)
    stalled = float(np.ptp(p_tail)) <= 1e-8 * (1.0 + float(np.max(np.abs(p_tail))))
    if not (np.all(dp > 0) or np.all(dp < 0) or stalled):
        return None  # (the parameter turns: not the monotone approach, e.g. snaking)
    try:
        lim = period_limit(br, n_fit=n_tail)
    except (ValueError, np.linalg.LinAlgError):
        return None
    if not math.isfinite(lim.p_star):
        return None
    # (cheap pre-check before the discretisation estimate: the parameter has nearly
    # converged, its remaining distance small against its last moves or tiny)
    span = float(np.ptp(p_tail))
    if abs(float(p_tail[-1]) - lim.p_star) > max(0.1 * span, 1e-8 * (1.0 + abs(lim.p_star))):
        return None
    last = orbit_at(br, n - 1)
    # the connections' discretisation estimate (safety 1: LIMIT_MARGIN is the margin)
    fine, change = discretisation_changes(
        CycleSolve(last, (free,)), cycle_resolves(free, fix_period=True), 1.0
    )
    if change is None:
        log.debug("no discretisation estimate of %s at T=%.6g: %s", free, last.T, fine.message)
        return None
    delta = change[free]
    thr = LIMIT_MARGIN * delta + 1e-12 * (1.0 + abs(lim.p_star))
    if not lim.fit_residual <= thr:
        # the rows do not follow the monotone law to their accuracy (e.g. the snaking
        # of a cycle near a saddle-focus loop, with cycles on both sides of p*): no end
        return None
    log.debug("period limit %s*=%.15g: delta %.2g, fit rms %.2g, last row %.3g from it",
              free, lim.p_star, delta, lim.fit_residual, float(br.p[-1]) - lim.p_star)  # fmt: skip
    # the side of the rows: that of the rows before the period took off
    T_all = np.asarray(br.records["T"], dtype=float)
    rising = n - 1
    while rising > 0 and T_all[rising - 1] < T_all[rising]:
        rising -= 1
    dist = np.asarray(br.p, dtype=float) - lim.p_star
    side = math.copysign(1.0, float(dist[rising]) if dist[rising] != 0.0 else 1.0)
    dist = side * dist
    close = np.flatnonzero(dist[rising:] <= thr)
    if close.size == 0:
        return None
    k = max(rising + int(close[0]) - 1, 1)
    msg = (
        f"{Status.PERIOD_UNBOUNDED.value} The period grows without bound towards "
        f"{free}*={lim.p_star:.12g} (fit of T = a - b ln|{free}* - {free}|); the rows "
        f"stop {dist[k]:.2g} before it, where the parameter's discretisation error "
        f"({delta:.1g}) no longer tells the side. Last period T={br.records['T'][k]:.10g} "
        f"at {free}={br.p[k]:.12g}."
    )
    log.info(msg)
    return _truncated(br, k, Status.PERIOD_UNBOUNDED, msg)


def _merge_segments(segs: list[Branch]) -> Branch:
    """One branch from consecutive segments.

    The first row of each later segment, the previous segment's last cycle on the new mesh,
    is dropped.
    """
    rows: dict[str, list[Any]] = {k: [] for k in ("p", "x", "eig", "nun", "ds", "it")}
    recs: dict[str, list[float]] = {}
    specials: list[SpecialPoint] = []
    first_row, probs = [], []
    base, s_base = 0, 0.0
    for k, b in enumerate(segs):
        lo = 0 if k == 0 else 1
        sub_p, sub_f = _segments_of(b)
        for q, fr in zip(sub_p, sub_f, strict=True):
            probs.append(q)
            first_row.append(base + max(fr, lo) if k else fr)
        rows["p"].append(b.p[lo:])
        rows["x"].append(b.x[lo:])
        rows["eig"].append(b.eigenvalues[lo:])
        rows["nun"].append(b.n_unstable[lo:])
        rows["ds"].append(b.ds[lo:])
        rows["it"].append(b.newton_iters[lo:])
        for name, col in b.records.items():
            recs.setdefault(name, []).extend(col[lo:].tolist())
        for sp in b.special_points:
            specials.append(dataclasses.replace(sp, index=base + sp.index, s=s_base + sp.s))
        base += len(b) - 1
        s_base += float(b.arclength[-1]) if len(b) else 0.0
    last = segs[-1]
    wide = max(x.shape[1] for x in rows["x"])  # meshes of more intervals: NaN-pad the rest
    rows["x"] = [np.pad(x, ((0, 0), (0, wide - x.shape[1])), constant_values=np.nan)
                 for x in rows["x"]]  # fmt: skip
    ev = [e for e in rows["eig"] if e.size]
    width = max((e.shape[1] for e in ev), default=0)
    eig: np.ndarray = (
        np.vstack([np.pad(e, ((0, 0), (0, width - e.shape[1])), constant_values=np.nan)
                   for e in rows["eig"]]) if width else np.zeros((base + 1, 0))
    )  # fmt: skip
    count = {"LPC": 0, "BPC": 0}
    relabelled = []
    for sp in specials:
        for key in count:
            if sp.label.startswith(key):
                count[key] += 1
                sp = dataclasses.replace(sp, label=f"{key}{count[key]}")
        relabelled.append(sp)
    return Branch(
        problem=CycleSegments(tuple(probs), tuple(first_row)) if len(probs) > 1 else probs[0],
        free=last.free,
        p=np.concatenate(rows["p"]),
        x=np.vstack(rows["x"]),
        eigenvalues=eig,
        n_unstable=np.concatenate(rows["nun"]),
        ds=np.concatenate(rows["ds"]),
        newton_iters=np.concatenate(rows["it"]),
        records={k: np.array(v) for k, v in recs.items()},
        special_points=tuple(relabelled),
        status=last.status,
        message=last.message,
        settings=segs[0].settings,
        state_names=last.state_names,
        param_values=segs[0].param_values,
        event_names=last.event_names,
    )


def _finish(
    br: Branch, free: str, period_max: float | None, error_tol: float | None = None
) -> Branch:
    """Status PERIOD_UNBOUNDED, the multiplier-accuracy and the error-estimate notes."""
    specials = br.special_points
    status, message = br.status, br.message
    if (
        period_max is not None
        and status == Status.EVENT
        and len(br)
        and (br.records["T"][-1] >= period_max * (1 - 1e-6))
    ):
        status = Status.PERIOD_UNBOUNDED
        message = (
            f"{Status.PERIOD_UNBOUNDED.value} Last period T={br.records['T'][-1]:.10g} at "
            f"{free}={br.p[-1]:.10g} (period_max={period_max:g})."
        )
        specials = tuple(s for s in specials if s.label != "T_max")
        log.info(message)
    specials = tuple(s for s in specials if s.label != _ERR_EVENT)
    out = []
    for sp in specials:
        floquet = (SpecialKind.PERIOD_DOUBLING, SpecialKind.NEIMARK_SACKER)
        if sp.kind in floquet and sp.located:
            err = special_problem(br, sp).floquet(sp.x, sp.p).trivial_error
            if err > TRIVIAL_TOL:
                log.warning("%s at %s=%.8g: multipliers unreliable (%.3g); reported as "
                            "bracketed, not located", sp.label, free, sp.p, err)  # fmt: skip
                sp = dataclasses.replace(sp, located=False, data={**sp.data, "trivial_error": err})
        out.append(sp)
    specials = tuple(out)
    if len(br) and "trivial_error" in br.records:
        bad = np.flatnonzero(br.records["trivial_error"] > TRIVIAL_TOL)
        if bad.size:
            worst = float(np.max(br.records["trivial_error"]))
            note = (
                f" Floquet multipliers unreliable at {bad.size} of {len(br)} rows (from "
                f"{free}={br.p[bad[0]]:.8g}; |mu_trivial - 1| up to {worst:.3g} > "
                f"{TRIVIAL_TOL:g}): refine the mesh (more intervals)."
            )
            log.warning(note.strip())
            message = message + note
    if len(br) and error_tol is None and "error" in br.records:
        rel = br.records["error"] / _state_ranges(br)
        over = np.flatnonzero(rel > ERROR_NOTE_REL)
        if over.size:
            k = int(over[np.argmax(rel[over])])
            note = (
                f" Collocation error estimate above {ERROR_NOTE_REL:g} of the cycle's range "
                f"at {over.size} of {len(br)} rows (from {free}={br.p[over[0]]:.8g}; up to "
                f"{float(br.records['error'][k]):.3g}, {float(rel[k]):.2g} of the range, at "
                f"{free}={br.p[k]:.8g}): pass error_tol to refine the mesh."
            )
            log.warning(note.strip())
            message = message + note
    if len(br) and error_tol is not None and "error" in br.records:
        # (the row where a segment stopped has the estimate at the tolerance, to the
        # locator's accuracy)
        over = np.flatnonzero(br.records["error"] > ERROR_SLACK * error_tol)
        if over.size:
            note = (
                f" Collocation error estimate above error_tol={error_tol:g} at {over.size} of "
                f"{len(br)} rows (from {free}={br.p[over[0]]:.8g}; up to "
                f"{float(np.max(br.records['error'])):.3g}): raise max_intervals or lower "
                "adapt_every."
            )
            log.warning(note.strip())
            message = message + note
            if status.ok:
                status = Status.DISCRETISATION_ERROR
    return dataclasses.replace(br, special_points=specials, status=status, message=message)


def _state_ranges(br: Branch) -> FloatArray:
    """Largest ``max - min`` of a state over the cycle at each row, shape ``(len(br),)``.

    1 where no state moves, so that the ratio stays the absolute estimate.
    """
    rec = br.records
    names = problem_at(br, 0).system.state_names
    r = np.max(np.vstack([rec[f"max_{s}"] - rec[f"min_{s}"] for s in names]), axis=0)
    return np.where(r > 0.0, r, 1.0)


def _row(branch: Branch, k: int) -> FloatArray:
    """The unknowns of row ``k`` (rows of meshes with fewer intervals are NaN-padded)."""
    return np.asarray(branch.x[k][: problem_at(branch, k).n_unknowns], dtype=float)


def problem_at(branch: Branch, k: int) -> PeriodicOrbitProblem:
    """The :class:`PeriodicOrbitProblem` (mesh) of row ``k`` of a cycle branch."""
    prob = branch.problem
    if isinstance(prob, CycleSegments):
        return prob.at_row(k)
    if not isinstance(prob, PeriodicOrbitProblem):
        raise ValueError("`branch` must be a branch of periodic orbits (continue_periodic)")
    return prob


def special_problem(branch: Branch, sp: SpecialPoint) -> PeriodicOrbitProblem:
    """The :class:`PeriodicOrbitProblem` (mesh) on which special point ``sp`` was found.

    A point in the first step of a later segment of an adapted branch lies on that
    segment's mesh although its step starts at the previous segment's last row: of the
    meshes of rows ``sp.index`` and ``sp.index + 1`` the one with the right number of
    unknowns and the smaller collocation residual at ``sp``.
    """
    x = np.asarray(sp.x, dtype=float)
    cands: list[PeriodicOrbitProblem] = []
    for k in (sp.index, min(sp.index + 1, len(branch) - 1)):
        prob = problem_at(branch, max(k, 0))
        if prob.n_unknowns == x.size and all(prob is not q for q in cands):
            cands.append(prob)
    if len(cands) == 1:
        return cands[0]
    if not cands:
        raise ValueError("`sp` is not a point of this cycle branch (no mesh of its size)")
    res = [float(np.max(np.abs(q.residual(x, sp.p)[:-1]))) for q in cands]
    return cands[int(np.argmin(res))]


def multipliers(branch: Branch) -> np.ndarray:
    """Nontrivial Floquet multipliers at every row of a cycle branch, ``(N, n - 1)``."""
    with blas_threads_for(branch.x.shape[1] if branch.x.ndim == 2 else 0, sparse=True):
        return np.array([problem_at(branch, k).floquet(_row(branch, k), branch.p[k]).multipliers
                         for k in range(len(branch))])  # fmt: skip


def orbit_at(branch: Branch, k: int | SpecialPoint) -> PeriodicOrbit:
    """The cycle at row ``k`` (or at a special point) of a cycle branch."""
    if isinstance(k, SpecialPoint):
        return special_problem(branch, k).orbit(k.x, k.p)
    k = int(k) + len(branch) if k < 0 else int(k)
    return problem_at(branch, k).orbit(_row(branch, k), branch.p[k])


@dataclass(frozen=True)
class PeriodLimit:
    r"""The end of a cycle branch whose period grows without bound.

    Attributes
    ----------
    p_star : float
        Fitted limit of the parameter, from :math:`T = a - b \ln|p^* - p|` over the
        last rows (NaN if the fit failed).
    rate : float
        ``b``; ``1/b`` estimates the unstable eigenvalue of the saddle that the cycle
        approaches (for a homoclinic orbit of a saddle with ``lambda_u < |lambda_s|``).
        NaN where the last rows do not determine it (the parameter has converged to
        round-off): the fit then uses ``b = 1 / lambda_u``.
    p_last, T_last : float
        Parameter and period of the last row.
    saddle : ndarray, shape (n,)
        The point of the last cycle where ``|f|`` is smallest: a guess of the saddle.
    t, x : ndarray
        The last cycle as one period starting and ending at that point, ``(K,)`` and
        ``(K, n)``: a guess of the connecting orbit for a connection solver.
    fit_residual : float
        RMS residual of the fit in ``p``.
    orbit : PeriodicOrbit
        The last cycle.
    free : str
        The continuation parameter.
    lambda_u : float
        Largest real part of the eigenvalues at :attr:`saddle` (its unstable rate).
    """

    p_star: float
    rate: float
    p_last: float
    T_last: float
    saddle: FloatArray
    t: FloatArray
    x: FloatArray
    fit_residual: float
    orbit: PeriodicOrbit
    free: str
    lambda_u: float = math.nan

    def connection_problem(self, mesh: CollocationMesh | None = None) -> Any:
        """A :class:`~continuation.bvp.HeteroclinicProblem` for the limiting connection.

        The saddle is :attr:`saddle` corrected by Newton's method on ``f = 0``; the
        connection returns to it shifted by the cycle's winding (``x_+ = x_- + k o
        period``, a homoclinic orbit when ``k = 0``); the free parameter is solved for,
        at :attr:`p_last` to start. Solve it with
        ``solve_connection(problem, (limit.t, limit.x))``. ``mesh``: default 80
        intervals of degree 4 over ``T_last``. Only a connection of *one* saddle to
        itself is set up (a cycle approaching a heteroclinic cycle of several saddles
        needs its own problem).

        Raises
        ------
        ConvergenceError
            If Newton's method on the saddle fails.
        """
        from ..bvp import HeteroclinicProblem

        orb = self.orbit
        P = np.array(orb.params.values, dtype=float)
        x = np.array(self.saddle, dtype=float)
        for _ in range(30):
            dx = np.linalg.solve(orb.system.jacobian(x, P), orb.system.f(x, P))
            x = x - dx
            if np.max(np.abs(dx)) <= 1e-13 * (1.0 + np.max(np.abs(x))):
                break
        else:
            raise ConvergenceError("the saddle of the period limit did not converge")
        mesh = mesh if mesh is not None else CollocationMesh(80, 4, self.T_last)
        return HeteroclinicProblem(orb.system, orb.params, free=(self.free,),
                                   saddle_from=x, shift=orb.shift, mesh=mesh)  # fmt: skip


def _log_fit(
    p: FloatArray, T: FloatArray, b_fixed: float | None = None
) -> tuple[float, float, float]:
    """Fit ``p = p* + c exp(-T / b)`` (i.e. ``T = a - b ln|p - p*|``).

    Returns ``(p*, b, rms of the fit in p)``. For fixed ``b`` the fit is linear in ``(p*,
    c)``; ``b`` is found by a bounded scalar search on ``ln b``. Where that search ends on a
    bound or the rows agree to ``1e-10`` relative (``b`` is not determined by the rows), the
    fit with ``b = b_fixed`` is returned, with ``b`` as NaN.
    """
    Tn = T - float(np.min(T))  # exponentials in (0, 1]: no overflow

    def lsq(lb: float) -> tuple[float, float, float]:
        A = np.column_stack([np.ones_like(Tn), np.exp(-Tn / math.exp(lb))])
        coef, *_ = np.linalg.lstsq(A, p, rcond=None)
        r = A @ coef - p
        return float(coef[0]), float(coef[1]), float(np.sqrt(np.mean(r**2)))

    span = float(np.ptp(T)) + 1e-300
    lo, hi = math.log(span) - 8, math.log(span) + 4
    res = so.minimize_scalar(lambda q: lsq(q)[2], bounds=(lo, hi), method="bounded",
                             options={"xatol": 1e-10})  # fmt: skip
    q = float(res.x)
    p_star, _, rms = lsq(q)
    if b_fixed is not None and math.isfinite(b_fixed) and b_fixed > 0:
        # the rate is not determined by these rows where the search ends on a bound or
        # the parameter has converged to round-off: then the fit with the saddle's own
        # rate, and no rate
        p_fix, _, rms_fix = lsq(math.log(b_fixed))
        at_bound = q - lo < 0.05 or hi - q < 0.05
        flat = float(np.ptp(p)) <= 1e-10 * max(1.0, float(np.max(np.abs(p))))
        if at_bound or flat:
            return p_fix, math.nan, rms_fix
    return p_star, math.exp(q), rms


def period_limit(branch: Branch, n_fit: int = 8) -> PeriodLimit:
    """The limit of a cycle branch whose period grows (see :class:`PeriodLimit`).

    Parameters
    ----------
    branch : Branch
        A branch of :func:`continue_periodic` (typically ended with
        ``Status.PERIOD_UNBOUNDED``).
    n_fit : int
        Number of last rows in the fit (at least 4).
    """
    problem_at(branch, 0)  # (checks the branch)
    if not (isinstance(n_fit, int) and n_fit >= 4):
        raise ValueError(f"`n_fit` must be an integer >= 4, got {n_fit!r}")
    if len(branch) < 4:
        raise ValueError("`branch` needs at least 4 rows for the period fit")
    k = min(n_fit, len(branch))
    p = np.asarray(branch.p[-k:], dtype=float)
    T = np.asarray(branch.records["T"][-k:], dtype=float)
    orb = orbit_at(branch, len(branch) - 1)
    F = np.array([orb.system.f(x, orb.params.values) for x in orb.X])
    q = int(np.argmin(np.linalg.norm(F, axis=1)))
    lam_u = _unstable_rate(orb, orb.X[q])
    try:
        p_star, b, rms = _log_fit(p, T, 1.0 / lam_u if lam_u > 0 else None)
    except (ValueError, np.linalg.LinAlgError, FloatingPointError):
        p_star, b, rms = math.nan, math.nan, math.nan
    t0 = float(orb.t[q])
    t = np.linspace(t0, t0 + orb.T, 4 * orb.mesh.n_points)
    x = orb(t)
    return PeriodLimit(p_star, b, float(branch.p[-1]), float(T[-1]), orb.X[q].copy(),
                       t - t0, x, rms, orb, branch.free, lam_u)  # fmt: skip


def _unstable_rate(orb: PeriodicOrbit, x: FloatArray) -> float:
    """Largest real part of the eigenvalues of ``f_x`` at ``x`` (the saddle guess)."""
    try:
        ev = np.linalg.eigvals(orb.system.jacobian(x, np.asarray(orb.params.values, float)))
    except (np.linalg.LinAlgError, ValueError):
        return math.nan
    return float(np.max(ev.real))


__all__ = [
    "PeriodLimit",
    "adapt_mesh",
    "continue_periodic",
    "multipliers",
    "orbit_at",
    "CycleSegments",
    "period_limit",
    "problem_at",
    "solve_orbit",
    "special_problem",
]
