r"""Continuation of periodic orbits: :func:`continue_periodic` and its helpers.

The branch is computed by the ordinary pseudo-arclength driver
(:func:`~continuation.driver.continue_branch`) on a
:class:`~continuation.periodic.problem.PeriodicOrbitProblem`. Special points of
cycles (see :mod:`continuation.periodic.floquet`):

* ``LPC`` -- fold of cycles: the driver's fold (kind ``fold``, relabelled ``LPC1``...);
* ``BPC`` -- branch point of cycles: the driver's branch point (kind ``bp``, ``BPC1``);
  ``switch_branch`` continues the crossing branch
  (:func:`~continuation.periodic.branch_point.continue_from_branch_point`);
* ``PD`` -- period doubling, a located zero of :math:`\prod (\mu_i + 1)` (kind
  ``pd``, labelled ``"PD"``; ``br.find("pd")``; located only with a multiplier within
  ``PD_TOL`` of -1); :func:`switch_period_doubling` starts the doubled branch;
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
from typing import Any, Literal

import numpy as np

from .._threads import blas_threads_for
from ..branch import Branch, SpecialKind
from ..bvp.collocation import CollocationMesh
from ..events import Event
from ..settings import ContinuationSettings
from ..status import Status
from ..system import as_params
from ..typing import FloatArray
from .collapse import hopf_end
from .limit import LIMIT_MARGIN, PeriodLimit, period_limit
from .orbit import PeriodicOrbit, orbit_from_array, winding_vector
from .rows import (
    CycleSegments,
    merge_segments,
    multipliers,
    orbit_at,
    problem_at,
    reversed_segments,
    special_problem,
)
from .segments import ERR_EVENT, continue_once, continue_segments
from .solve import adapt_mesh, refine_start, solve_orbit

log = logging.getLogger(__name__)

#: Rows whose trivial multiplier is farther than this from 1 have unreliable
#: multipliers (the discretisation error, amplified by the cycle's sensitivity); the
#: branch message says so.
TRIVIAL_TOL = 1e-3


#: Default tolerance of the collocation error estimate of :func:`continue_periodic`
#: (states' units): the mesh adapts and grows to keep every row within it (AUTO-07p, too,
#: adapts its mesh by default).
ERROR_TOL = 1e-6

#: Rows count as within ``error_tol`` up to this factor (the row where a segment stopped
#: has the estimate at the tolerance to the locator's accuracy).
ERROR_SLACK = 1.01

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
    previous: PeriodicOrbit | None = None,
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
    previous : PeriodicOrbit, optional
        A cycle of the same branch just before the start: the first step then follows
        the secant from it to the start (``direction`` ``"forward"``; ``"backward"``
        the opposite way) instead of the sign of ``settings.ds`` in the parameter, as
        where the branch is vertical in ``free`` (a pitchfork of cycles:
        :func:`~continuation.periodic.branch_point.continue_from_branch_point`).

    A branch whose cycles shrink onto an equilibrium (a Hopf point: their amplitude
    passes through zero between two rows) ends at the row before, with
    ``Status.EVENT`` and a Hopf point ``"H"`` bracketed there
    (:func:`~continuation.periodic.collapse.hopf_end`): beyond it the rows would retrace
    the branch, with a false fold of cycles at the Hopf point.

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

    def one(st: ContinuationSettings, prev: PeriodicOrbit | None) -> Branch:
        if adapt_every == 0 and error_tol is None:
            br = continue_once(orb, free, st, previous=prev, **run)  # type: ignore[arg-type]
            return hopf_end(br, free) or br
        return continue_segments(orb, free, st, adapt_every, run, error_tol, max_intervals,
                                 previous=prev)  # fmt: skip

    back = dataclasses.replace(settings, ds=-settings.ds)
    # the mirror of `previous` through the start: its secant points the other way
    prev_back = None if previous is None else _mirrored(previous, orb, free)
    # one BLAS thread for the whole run, the start corrections and mesh adaptations
    # included (the driver limits only its own steps): the blocks are small, and on a
    # loaded 2-core machine OpenBLAS's second thread made the condensed factorisations
    # of AUTO's demo ab up to 100x slower (benchmarks/README.md)
    with blas_threads_for(orb.X.size, sparse=True):
        if direction == "forward":
            br = one(settings, previous)
        elif direction == "backward":
            br = one(back, prev_back)
        else:
            b, f = one(back, prev_back), one(settings, previous)
            if len(b) == 0 or len(f) == 0:
                br = f if len(f) else b
            else:
                br = merge_segments([reversed_segments(b), f])
                br = dataclasses.replace(
                    br, message=f"{f.message} (backward end: {b.status.name}: {b.message})"
                )
        return _finish(br, free, period_max, error_tol)


#: A branch that fails (``DS_MIN``, ``NEWTON_FAILED``) at a row whose largest multiplier
#: exceeds this says so in its message: the collocation system's condition grows with
#: it, towards the limit of double precision (``1/eps ~ 4.5e15``), as for the cycles of
#: a snake deep towards a saddle-focus loop.
MU_ILL_CONDITIONED = 1e12


def _mirrored(previous: PeriodicOrbit, orb: PeriodicOrbit, free: str) -> PeriodicOrbit:
    """``2 orb - previous`` on ``orb``'s mesh (the secant from it to ``orb`` reversed)."""
    prev = previous.on_mesh(orb.mesh)
    params = orb.params.replace(**{free: 2 * orb.param(free) - previous.param(free)})
    return dataclasses.replace(prev, X=2 * orb.X - prev.X, T=2 * orb.T - prev.T, params=params)


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
    specials = tuple(s for s in specials if s.label != ERR_EVENT)
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
    if (
        len(br)
        and status in (Status.DS_MIN, Status.NEWTON_FAILED)
        and "mu_max" in br.records
        and br.records["mu_max"][-1] > MU_ILL_CONDITIONED
    ):
        note = (
            f" The last cycle ({free}={br.p[-1]:.10g}, T={br.records['T'][-1]:.6g}) has a "
            f"multiplier of {br.records['mu_max'][-1]:.2g}: its collocation system is "
            "ill-conditioned in proportion, near the limit of double precision, which "
            "may be why the corrector fails here."
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


#: The public names of the cycle continuation (those defined in the modules split off
#: from this one stay importable from here: :mod:`~continuation.periodic.solve`,
#: :mod:`~continuation.periodic.rows`, :mod:`~continuation.periodic.limit`).
__all__ = [
    "LIMIT_MARGIN",
    "CycleSegments",
    "PeriodLimit",
    "adapt_mesh",
    "continue_periodic",
    "multipliers",
    "orbit_at",
    "period_limit",
    "problem_at",
    "solve_orbit",
    "special_problem",
]
