r"""The critical curve: critical Fn against the autopilot course (Umeda 1999, Fig. 23).

The heteroclinic connection of :mod:`ship_models.analysis.critical_bvp` (crest saddle
to the same saddle one wavelength back, ``Fn`` unknown) is solved at ``chi_c = 0`` (or
at a given start) and continued in ``chi_c`` by pseudo-arclength
(:func:`continuation.bvp.continue_connection`) along its *first sheet*: up to its first
fold in ``chi_c``, where the curve turns back (beyond it the branch carries orbits that
are no capsizing boundary, e.g. capsizes past the angle of vanishing stability). Every
requested course on the sheet is then solved with error estimates from the branch's
orbit; the fold is re-located from the last of them (adapted mesh) until no further
course falls below it. Courses beyond the fold, or beyond the end of the crest saddle's
own branch (its fold in ``chi_c`` at the fold's ``Fn``), do not exist and are reported
as such with the reason, not as failures.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from continuation.branch import SpecialKind
from continuation.bvp import continue_connection, solve_connection
from continuation.casadi_compile import compiling
from continuation.errors import ContinuationError
from continuation.settings import ContinuationSettings, NewtonSettings
from continuation.status import Status, StatusResult
from continuation.sweep.backends import check_workers
from continuation.sweep.forked import ForkedTasks
from continuation.typing import FloatArray

from ..contracts import VesselModel
from .boundary_check import boundary_refusal
from .critical_bvp import critical_fn_bvp
from .critical_result import CriticalFn
from .params import course, ship_model, ship_params

log = logging.getLogger(__name__)

#: Courses per task of :func:`critical_curve`: a task's solves share one store of
#: factorised Jacobians, and a task is the unit of work of a forked process.
COURSES_PER_TASK = 8


@dataclass(frozen=True, eq=False)
class CriticalCurve(StatusResult):
    """Critical ``Fn`` against the course: the paper's Fig. 23 line.

    Attributes
    ----------
    chi_c : ndarray, shape (K,)
        Requested courses (rad).
    Fn : ndarray, shape (K,)
        Critical ``Fn`` at each course (nan where not computed).
    residual_norm : ndarray, shape (K,)
        ``max |G|`` of the connection at each course.
    converged : ndarray of bool, shape (K,)
        Whether the point was corrected to the requested course.
    n_unstable : ndarray of int, shape (K,)
        Unstable eigenvalues of the crest saddle at each course (1 for a valid
        codimension-one connection; -1 where not computed).
    branch : Branch or None
        The pseudo-arclength branch of connections in ``chi_c``.
    start : CriticalFn
        The one-shot solve the branch started from.
    status : Status
        ``SUCCESS`` (``success``) when every existing requested course converged to a
        valid boundary.
    message : str
    elapsed : float
        Wall time (s), the start solve included.
    orbits : tuple of ndarray
        With ``keep_orbits``: the orbit ``x (M, 8)`` of every converged course.
    exists : ndarray of bool, shape (K,)
        False for courses beyond the end of the curve (``reasons`` says why).
    reasons : tuple of str, shape (K,)
        Why a course has no value ("" where it has one).
    error : ndarray, shape (K,)
        Error estimate of ``Fn`` (discretisation + truncation) of each course.
    folds : tuple of (float, float)
        ``(chi_c, Fn)`` of the located folds of the curve in ``chi_c`` (rad).
    end_chi_c, end_Fn : float
        End of the first sheet (its first fold); NaN if the range ends before it.
    fold_error : float
        Change of ``end_chi_c`` in its last re-location (rad; NaN/inf if not re-located).
    crest_end_chi_c : float
        Fold of the crest saddle's branch in ``chi_c`` at ``Fn = end_Fn`` (rad; NaN
        if not computed): the crest saddle does not exist beyond it.
    """

    chi_c: FloatArray
    Fn: FloatArray
    residual_norm: FloatArray
    converged: np.ndarray
    n_unstable: np.ndarray
    branch: Any
    start: CriticalFn
    status: Status
    message: str
    elapsed: float = 0.0
    orbits: tuple[FloatArray, ...] = field(default=(), repr=False)
    exists: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    reasons: tuple[str, ...] = ()
    error: FloatArray = field(default_factory=lambda: np.zeros(0))
    folds: tuple[tuple[float, float], ...] = ()
    end_chi_c: float = math.nan
    end_Fn: float = math.nan
    crest_end_chi_c: float = math.nan
    fold_error: float = math.nan

    @property
    def chi_c_deg(self) -> FloatArray:
        """Courses in degrees."""
        return np.degrees(self.chi_c)

    def to_json(self) -> dict[str, Any]:
        """JSON-ready summary."""
        return {
            "chi_c_deg": [round(float(c), 9) for c in self.chi_c_deg],
            "Fn": [None if not np.isfinite(f) else float(f) for f in self.Fn],
            "residual_norm": [float(r) for r in self.residual_norm],
            "converged": [bool(c) for c in self.converged],
            "n_unstable": [int(k) for k in self.n_unstable],
            "exists": [bool(e) for e in self.exists],
            "reasons": list(self.reasons),
            "error": [None if not np.isfinite(e) else float(e) for e in self.error],
            "folds": [{"chi_c_deg": math.degrees(c), "Fn": float(f)} for c, f in self.folds],
            "end_chi_c_deg": _deg_or_none(self.end_chi_c),
            "end_Fn": None if not math.isfinite(self.end_Fn) else float(self.end_Fn),
            "crest_end_chi_c_deg": _deg_or_none(self.crest_end_chi_c),
            "fold_error_deg": _deg_or_none(self.fold_error),
            "status": self.status.name,
            "message": self.message,
            "elapsed_s": self.elapsed,
            "start": self.start.to_json(),
        }

    def to_csv(self, path: str | Path) -> Path:
        """Write ``chi_c_deg, Fn_critical, residual_norm, converged`` rows."""
        path = Path(path)
        rows = ["chi_c_deg,Fn_critical,residual_norm,converged"]
        for c, f, r, ok in zip(
            self.chi_c_deg, self.Fn, self.residual_norm, self.converged, strict=True
        ):
            rows.append(f"{c:.6g},{f:.10f},{r:.3e},{int(bool(ok))}")
        path.write_text("\n".join(rows) + "\n")
        return path


def _deg_or_none(x: float) -> float | None:
    return None if not math.isfinite(x) else math.degrees(x)


class _FoldStop:
    """Progress hook that stops a forward branch one row past its first fold in ``chi_c``.

    The driver has no "stop at fold" setting; the hook raises ``KeyboardInterrupt`` after
    the row beyond the fold (the driver has located the fold by then) and records that
    it did, so the caller tells it from a user's Ctrl-C.
    """

    def __init__(self, sign: float, user: Callable[[Any], None] | None) -> None:
        self.sign, self.user, self.last, self.fired = sign, user, None, False

    def __call__(self, pt: Any) -> None:
        if self.user is not None:
            self.user(pt)
        p = float(pt.p)
        if self.last is not None and self.sign * (p - self.last) < 0:
            self.fired = True
            raise KeyboardInterrupt
        self.last = p


def _first_sheet(branch: Any, sign: float) -> tuple[FloatArray, FloatArray, Any]:
    """Rows of the branch up to its first fold in ``chi_c`` (``P (k,)``, ``Z (k, N)``), fold.

    A located fold is appended as the last row, so that courses between the last row
    before the fold and the fold itself have a bracketing pair of rows.
    """
    P = np.asarray(branch.p, dtype=float)
    Z = np.asarray(branch.x, dtype=float)
    folds = [sp for sp in branch.special_points if sp.kind is SpecialKind.FOLD]
    fold = min(folds, key=lambda sp: sp.index) if folds else None
    k = P.size if fold is None else fold.index + 1
    # cut too at the first turn of p if the fold was not flagged
    d = sign * np.diff(P[:k])
    back = np.nonzero(d < 0)[0]
    if back.size:
        k = int(back[0]) + 1
    P, Z = P[:k], Z[:k]
    if fold is not None and fold.located and sign * (float(fold.p) - P[-1]) > 0:
        P = np.append(P, float(fold.p))
        Z = np.vstack([Z, np.asarray(fold.x, dtype=float)[None, :]])
    return P, Z, fold


def _crest_end(m: Any, params: Any, Fn: float, sign: float) -> float:
    """``chi_c`` (rad) of the crest saddle branch's first fold at ``Fn``; NaN if none."""
    from ship_models.umeda_4dof import follow_in_chi_c

    p0 = ship_params(m, params, chi_c=0.0).replace(Fn=float(Fn))
    r0 = m.find_equilibrium(p0, "crest")
    if not r0.converged:
        return math.nan
    br = follow_in_chi_c(m, r0.z, p0, sign * math.radians(80.0), ds_max=0.05)
    folds = [sp for sp in br.special_points if sp.kind is SpecialKind.FOLD and sp.located]
    return float(folds[0].p) if folds else math.nan


@compiling
def critical_curve(
    chi_c_values: Sequence[float] | FloatArray | None = None,
    *,
    model: VesselModel | None = None,
    params: Any = None,
    start: CriticalFn | None = None,
    ds: float = 0.02,
    ds_max: float = 0.1,
    tol: float = 1e-9,
    keep_orbits: bool = False,
    throw: bool = False,
    progress: Callable[[Any], None] | None = None,
    max_relocations: int = 3,
    fold_tol: float = math.radians(0.02),
    workers: int = 1,
    **bvp_options: Any,
) -> CriticalCurve:
    r"""Critical ``Fn`` over a range of courses along the first sheet of the curve.

    1. Start: the connection at ``chi_c = 0`` (:func:`critical_fn_bvp`; the simulated
       guess is easiest there, the roll is decoupled), or ``start``.
    2. Continue it in ``chi_c`` (:func:`continuation.bvp.continue_connection`, away
       from 0) and stop one row past the first fold of the branch in ``chi_c``.
    3. Every requested course on the sheet (between the start and the fold) is solved
       by :func:`continuation.bvp.solve_connection` at fixed ``chi_c`` from the branch's
       orbit interpolated there, on the branch's own mesh (which the start solve
       adapted; refined by the solver where it misses the tolerance), the Jacobians
       shared between courses: error estimates (``error``) and the capsizing-boundary
       check (:func:`~ship_models.analysis.boundary_check.boundary_refusal`). The row
       located at the fold is appended to the sheet, so that courses between the last
       row and the fold are interpolated, not extrapolated; courses within 1 deg
       of the fold wait for its last re-location.
    4. The fold located on the start mesh is only as good as that mesh: the branch is
       continued again from a solve 0.5 deg before the fold (or half-way from the
       branch's start to it, if nearer), on a mesh adapted to the orbit there, and
       steps 3-4 repeat (at most ``max_relocations`` times) until the fold moves by
       less than ``fold_tol`` and no course remains below it.
    5. The end: the first fold is reported in ``folds`` and as ``end_chi_c``,
       ``end_Fn``; the crest saddle's own branch is followed in ``chi_c`` at ``end_Fn``
       (``crest_end_chi_c``). Courses beyond the fold have ``exists = False`` with the
       reason (the curve folds back there / the crest saddle does not exist).

    The courses of step 3 are solved in tasks of :data:`COURSES_PER_TASK` consecutive
    courses, each with its own store of Jacobians, so a course's result does not depend
    on which process solved it or on ``workers``. With ``workers > 1`` the tasks of a
    sheet run on ``workers - 1`` forked copies of this process
    (:class:`continuation.sweep.forked.ForkedTasks`; they inherit the branch and the
    compiled functions) while this one re-locates the fold, and then on this one too.

    It runs inside :func:`continuation.casadi_compile.allow_compilation`: the model's
    collocation functions are compiled to C once per machine (cached), which pays
    off over the hundreds of Newton steps of a curve.

    Parameters
    ----------
    chi_c_values : array_like, shape (K,), optional
        Courses (rad), all of one sign (0 allowed); default 0, 1, ..., 30 degrees.
    model, params
        As for :func:`critical_fn_bvp`.
    start : CriticalFn, optional
        A converged connection on the first sheet (default: solved at ``chi_c = 0``).
    ds, ds_max : float
        Pseudo-arclength step (initial and largest).
    tol : float
        Newton tolerance of the continuation corrector.
    keep_orbits : bool
        Store the orbit ``x (M, 8)`` of every converged course in ``orbits``.
    throw : bool
        Raise :class:`~continuation.errors.ContinuationError` if an existing course fails.
    progress : callable, optional
        Called with every accepted branch point.
    max_relocations : int
        Re-continuations from a solve near the fold to re-locate it (step 4).
    fold_tol : float
        Stop re-locating when the fold moves by less than this (rad); the last move
        is ``fold_error``.
    workers : int
        Processes solving the courses, this one included (``1``: all here; more:
        forked copies where :func:`continuation.sweep.forked.can_fork`, else here).
    **bvp_options
        Passed to :func:`critical_fn_bvp` for the start solve.

    Returns
    -------
    CriticalCurve
        ``SUCCESS`` when every course that exists is a valid boundary within its error
        estimate; otherwise the status of the first failing course, or ``INTERRUPTED``.
    """
    t_start = time.perf_counter()
    if chi_c_values is None:
        chis = np.radians(np.arange(0.0, 31.0))
    else:
        chis = np.atleast_1d(np.asarray(chi_c_values, dtype=float))
        if chis.ndim != 1 or chis.size == 0:
            raise ValueError("`chi_c_values` must be a non-empty 1-D array of courses (rad)")
        for c in chis:
            course(c, "chi_c_values")
    if np.any(chis > 0) and np.any(chis < 0):
        raise ValueError("`chi_c_values` must all have one sign (the curve starts at 0)")
    if check_workers(workers) is None:
        raise ValueError("`workers` must be a positive integer, got None")
    if not (math.isfinite(ds) and ds > 0 and math.isfinite(ds_max) and ds_max >= ds):
        raise ValueError(f"`ds` and `ds_max` must satisfy 0 < ds <= ds_max, got {ds}, {ds_max}")
    sign = -1.0 if np.any(chis < 0) else 1.0
    m = ship_model(model)
    if start is None:
        start = critical_fn_bvp(0.0, model=m, params=params, **bvp_options)
    elif not isinstance(start, CriticalFn):
        raise ValueError(f"`start` must be a CriticalFn, got {type(start).__name__}")
    K = chis.size
    nan = np.full(K, np.nan)
    Fn, res_n, err = nan.copy(), nan.copy(), nan.copy()
    ok = np.zeros(K, dtype=bool)
    exists = np.ones(K, dtype=bool)
    reasons = [""] * K
    n_unst = np.full(K, -1, dtype=int)
    orbit_of: dict[int, FloatArray] = {}
    if not start.success:
        msg = f"the start connection did not converge: {start.message}"
        if throw:
            raise ContinuationError(msg)
        return CriticalCurve(
            chis, nan, nan.copy(), ok, n_unst, None, start, start.status, msg,
            time.perf_counter() - t_start, exists=exists, reasons=tuple(reasons), error=err,
        )  # fmt: skip
    far = float(np.max(np.abs(chis)))
    margin = math.radians(2.0)
    status = Status.SUCCESS
    solved: dict[int, CriticalFn] = {}
    branch = None
    fold = None
    end_chi, end_Fn = math.nan, math.nan
    folds: list[tuple[float, float]] = []
    fold_error = math.inf
    fold_offset = math.radians(0.5)
    # the fold's re-location solves share their factorised Jacobians (the courses'
    # tasks have stores of their own, _solve_task)
    store: dict[Any, Any] = {}
    sheets: list[tuple[Any, FloatArray, FloatArray]] = []  # (problem, P, Z) per branch
    pending = list(range(K))
    for k in range(K):
        if abs(chis[k] - start.chi_c) < 1e-12:  # the start is a checked solve there
            solved[k] = start
    pending = [k for k in pending if k not in solved]

    batches: list[ForkedTasks[list[int], list[_Solved]]] = []

    def solve_courses(todo: Sequence[int]) -> None:
        # tasks of consecutive courses from the sheets as they are now; with workers,
        # forked copies start on them at once and this process goes on
        tasks = [
            list(todo[i : i + COURSES_PER_TASK]) for i in range(0, len(todo), COURSES_PER_TASK)
        ]
        if not tasks:
            return
        snapshot = tuple(sheets)
        batch: ForkedTasks[list[int], list[_Solved]] = ForkedTasks(
            lambda ks: _solve_task(m, params, snapshot, chis, ks, keep_orbits),
            tasks,
            children=min(workers - 1, len(tasks)) if len(tasks) > 1 else 0,
        )
        batches.append(batch)
        if batch.n_children == 0:
            batch.run_rest()

    def collect(cancel: bool = False) -> None:
        while batches:  # a batch leaves the list only once collected
            batch = batches[0]
            done = batch.cancel() if cancel else batch.results()
            batches.pop(0)
            for rows in done.values():
                for k, r, x in rows:
                    solved[k] = r
                    if x is not None:
                        orbit_of[k] = x

    try:
        # courses between 0 and a start away from 0: a backward branch
        near = [k for k in pending if sign * chis[k] < sign * start.chi_c - 1e-12]
        if near:
            settings = _settings(ds, ds_max, tol, sign, 0.0, start.chi_c, margin)
            back = continue_connection(
                start.orbit, "chi_c", settings, direction="backward", progress=progress
            )
            if back.status is Status.INTERRUPTED:
                raise KeyboardInterrupt
            P, Z, _ = _first_sheet(back, -sign)
            sheets.append((back.problem, P, Z))
            solve_courses(near)
            sheets.clear()
            pending = [k for k in pending if k not in near]
        cur = start
        for n_reloc in range(max_relocations + 1):
            hook = _FoldStop(sign, progress)
            settings = _settings(ds, ds_max, tol, sign, cur.chi_c, far, margin)
            branch = continue_connection(
                cur.orbit, "chi_c", settings, direction="forward", progress=hook
            )
            if branch.status is Status.INTERRUPTED and not hook.fired:
                raise KeyboardInterrupt
            P, Z, fold = _first_sheet(branch, sign)
            sheets.append((branch.problem, P, Z))
            sheet_end = float(P[-1]) if fold is None else float(fold.p)
            if fold is not None:
                if math.isfinite(end_chi):
                    fold_error = abs(float(fold.p) - end_chi)
                end_chi = float(fold.p)
                end_Fn = float(branch.problem.unpack(np.asarray(fold.x))["params"]["Fn"])
                folds = [(end_chi, end_Fn)]
            below = [k for k in pending if sign * chis[k] <= sign * sheet_end + 1e-12]
            # courses near the fold wait for its last re-location (a branch from a
            # solve near it): solved now, they may lie beyond the fold found later
            defer = 2.0 * fold_offset if fold is not None else -1.0
            todo = [k for k in below if sign * (sheet_end - chis[k]) > defer]
            todo.sort(key=lambda k: sign * chis[k])
            solve_courses(todo)
            pending = [k for k in pending if k not in todo]
            if fold is None or fold_error <= fold_tol or n_reloc == max_relocations:
                break
            # re-locate the fold from an adapted solve near it (its mesh and T there)
            c_aux = end_chi - sign * min(fold_offset, 0.5 * abs(end_chi - float(P[0])))
            # a pending course may serve as that solve, but only one at least as far
            # from the fold as the offset: one nearer may lie beyond the re-located fold
            # (its solve then fails, after a costly Newton fallback)
            near_fold = [
                k for k in pending
                if -1e-12 <= sign * (c_aux - chis[k]) <= fold_offset
            ]  # fmt: skip
            k_aux = max(near_fold, key=lambda k: sign * chis[k]) if near_fold else None
            if k_aux is not None:
                c_aux = float(chis[k_aux])
            nxt = _solve_from_sheets(m, params, sheets, c_aux, store, adapt=None)
            if k_aux is not None and (nxt is None or not nxt.success):
                # that course may lie beyond the better-located fold: from the offset
                c_aux = end_chi - sign * min(fold_offset, 0.5 * abs(end_chi - float(P[0])))
                k_aux = None
                nxt = _solve_from_sheets(m, params, sheets, c_aux, store, adapt=None)
            if nxt is None or not nxt.success:
                break
            if k_aux is not None:
                solved[k_aux] = nxt
                pending.remove(k_aux)
            cur = nxt
        if math.isfinite(end_chi):  # the deferred courses below the last fold
            solve_courses(
                sorted(
                    (k for k in pending if sign * chis[k] <= sign * end_chi + 1e-12),
                    key=lambda k: -sign * chis[k],
                )
            )
        collect()
    except KeyboardInterrupt:
        status = Status.INTERRUPTED
        collect(cancel=True)
    finally:  # any other exception: no forked process outlives the call
        for batch in batches:
            batch.cancel()
    crest_end = math.nan
    if math.isfinite(end_Fn) and status is not Status.INTERRUPTED:
        crest_end = _crest_end(m, params, end_Fn, sign)
    first_bad: Status | None = None
    for k in range(K):
        r = solved.get(k)
        if math.isfinite(end_chi) and sign * chis[k] > sign * end_chi:
            r = None  # solved before the fold was re-located below it: no boundary there
        if r is None:
            if status is Status.INTERRUPTED or not math.isfinite(end_chi):
                reasons[k] = (
                    "not computed"
                    if status is Status.INTERRUPTED
                    else ("not reached by the branch")
                )
                if status is not Status.INTERRUPTED:
                    first_bad = first_bad or (branch.status if branch is not None else None)
                continue
            exists[k] = False
            if math.isfinite(crest_end) and sign * chis[k] > sign * crest_end:
                reasons[k] = (
                    f"the crest saddle does not exist beyond chi_c = "
                    f"{math.degrees(crest_end):.1f} deg at Fn {end_Fn:.4f}"
                )
            else:
                reasons[k] = (
                    f"beyond the end of the critical curve: it folds back at chi_c = "
                    f"{math.degrees(end_chi):.2f} deg (Fn {end_Fn:.4f})"
                )
            continue
        res_n[k] = r.residual_norm
        if r.success:
            Fn[k], ok[k] = r.Fn, True
            err[k] = math.nan if r.error is None else r.error
            n_unst[k] = 1
            if keep_orbits and k not in orbit_of and r.orbit is not None:
                orbit_of[k] = np.asarray(r.orbit.x, dtype=float)
        else:
            reasons[k] = r.message
            first_bad = first_bad or r.status
    n_ok = int(ok.sum())
    n_exist = int(exists.sum())
    if status is not Status.INTERRUPTED and first_bad is not None:
        status = first_bad if first_bad is not Status.SUCCESS else Status.NEWTON_FAILED
    message = f"{n_ok}/{n_exist} existing courses"
    if math.isfinite(end_chi):
        message += (
            f"; the critical curve ends at its fold chi_c = {math.degrees(end_chi):.2f} deg, "
            f"Fn = {end_Fn:.4f}"
        )
        if math.isfinite(crest_end):
            message += (
                f"; the crest saddle does not exist beyond chi_c = "
                f"{math.degrees(crest_end):.1f} deg at Fn {end_Fn:.4f}"
            )
    if n_exist < K:
        message += f"; {K - n_exist} course(s) beyond the end do not exist"
    if throw and status is not Status.SUCCESS and status is not Status.INTERRUPTED:
        raise ContinuationError(f"critical curve incomplete: {message}")
    orbits = tuple(orbit_of[k] for k in sorted(orbit_of) if ok[k])
    return CriticalCurve(
        chis, Fn, res_n, ok, n_unst, branch, start, status, message,
        time.perf_counter() - t_start, orbits, exists=exists, reasons=tuple(reasons),
        error=err, folds=tuple(folds), end_chi_c=end_chi, end_Fn=end_Fn,
        crest_end_chi_c=crest_end, fold_error=fold_error if math.isfinite(end_chi) else math.nan,
    )  # fmt: skip


def _settings(
    ds: float, ds_max: float, tol: float, sign: float, a: float, b: float, margin: float
) -> ContinuationSettings:
    """Continuation settings between courses ``a`` and ``b`` (``margin`` beyond ``b``)."""
    lo, hi = sorted((a, b + sign * margin))
    return ContinuationSettings(
        ds=ds,
        ds_max=ds_max,
        p_min=lo - (1e-3 if sign > 0 else 0.0),
        p_max=hi + (1e-3 if sign < 0 else 0.0),
        max_steps=400,
        newton=NewtonSettings(tol=tol, step_tol=1e-8, max_iter=8),
    )


def _predict(P: FloatArray, Z: FloatArray, c: float) -> FloatArray | None:
    """Linear interpolation of the branch rows ``Z`` at ``chi_c = c`` (first bracketing pair)."""
    if P.size == 0:
        return None
    for i in range(P.size - 1):
        a, b = P[i], P[i + 1]
        if min(a, b) <= c <= max(a, b) and a != b:
            w = (c - a) / (b - a)
            return (1 - w) * Z[i] + w * Z[i + 1]
    j = int(np.argmin(np.abs(P - c)))
    if abs(P[j] - c) < 1e-6:
        return Z[j].copy()
    return None


#: One solved course of a task: index, result without its orbit, orbit samples or None.
_Solved = tuple[int, CriticalFn, FloatArray | None]


def _solve_task(
    m: Any,
    params: Any,
    sheets: Sequence[tuple[Any, FloatArray, FloatArray]],
    chis: FloatArray,
    ks: Sequence[int],
    keep_orbits: bool,
) -> list[_Solved]:
    """Solve the courses ``chis[ks]`` in order, sharing one store of Jacobians.

    Returns picklable rows (the result's ``orbit``, whose problem holds CasADi
    functions, is replaced by its samples ``x (M, 8)`` when ``keep_orbits``).

    Raises
    ------
    KeyboardInterrupt
        When a solve was interrupted (its status ``INTERRUPTED``): the remaining courses
        are not started, so one Ctrl-C stops the curve instead of one course each.
    """
    store: dict[Any, Any] = {}
    rows: list[_Solved] = []
    for k in ks:
        r = _solve_from_sheets(m, params, sheets, float(chis[k]), store)
        if r is None:
            continue
        if r.status is Status.INTERRUPTED:  # Ctrl-C: stop here, not at every course
            raise KeyboardInterrupt
        if not r.success:
            log.warning("course %.4g deg: %s", math.degrees(chis[k]), r.message)
        x = np.asarray(r.orbit.x, dtype=float) if keep_orbits and r.orbit is not None else None
        rows.append((k, dataclasses.replace(r, orbit=None), x))
    return rows


def _solve_from_sheets(
    m: Any,
    params: Any,
    sheets: Sequence[tuple[Any, FloatArray, FloatArray]],
    c: float,
    store: dict[Any, Any],
    adapt: int | None = 0,
) -> CriticalFn | None:
    """The connection at course ``c`` from the latest branch whose rows bracket it."""
    for prob, P, Z in reversed(sheets):
        r = _solve_at(m, params, prob, P, Z, c, store, adapt)
        if r is not None:
            return r
    return None


def _solve_at(
    m: Any,
    params: Any,
    prob: Any,
    P: FloatArray,
    Z: FloatArray,
    c: float,
    store: dict[Any, Any] | None = None,
    adapt: int | None = 0,
) -> CriticalFn | None:
    """The connection at course ``c`` from the branch orbit interpolated there.

    Solved by :func:`continuation.bvp.solve_connection` (error estimates: the mesh
    halved, ``T`` lengthened) on the branch's problem at fixed ``chi_c = c``, which
    keeps its compiled functions (a new problem, as :func:`critical_fn_bvp` builds,
    costs several times the solve); then the capsizing-boundary check. ``adapt=0``
    (the courses): on the branch's own mesh, which the start solve adapted, with the
    Jacobians shared through ``store`` (all courses have the same mesh); ``None``
    (the re-locations of the fold): adapted to the orbit at ``c``. Either way the
    error estimate is that of the mesh used; a mesh that misses the tolerance is
    refined by the solver.
    """
    t0 = time.perf_counter()
    z0 = _predict(P, Z, c)
    if z0 is None:
        return None
    parts = prob.unpack(z0)
    fixed = prob.replace(
        vary=None, reference=None, params=prob.params.replace(chi_c=c, **parts["params"])
    )
    guess = (np.asarray(prob.mesh.t, dtype=float), np.asarray(parts["X"], dtype=float))
    res = solve_connection(fixed, guess, method="broyden", adapt=adapt, jacobians=store)
    status, message = res.status, res.message
    if res.success or res.status in (Status.DISCRETISATION_ERROR, Status.TRUNCATION_ERROR):
        why = boundary_refusal(m, res.x, res.x_from, fixed.params.replace(**res.params))
        if why:
            status, message = Status.REJECTED, f"not a capsizing boundary: {why}"
    errs = res.errors
    return CriticalFn(
        chi_c=c, Fn=float(res.params["Fn"]), method="bvp", status=status, message=message,
        error=None if errs is None else float(errs.total("Fn")),
        elapsed=time.perf_counter() - t0, orbit=res, residual_norm=float(res.residual_norm),
    )  # fmt: skip


__all__ = ["CriticalCurve", "critical_curve"]
