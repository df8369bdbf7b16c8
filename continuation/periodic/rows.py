r"""The rows of a cycle branch: its meshes and the cycle at a row.

A branch of :func:`~continuation.periodic.continue_periodic` whose mesh adapts is made
of segments, one :class:`~continuation.periodic.problem.PeriodicOrbitProblem` (mesh)
each, held by :class:`CycleSegments`; rows of coarser meshes are NaN-padded. Here:

* the accessors :func:`problem_at`, :func:`special_problem`, :func:`orbit_at` and
  :func:`multipliers`;
* the bookkeeping of segments: :func:`merge_segments` (one branch from consecutive
  segments), :func:`reversed_segments` and :func:`truncated`.
"""

from __future__ import annotations

import dataclasses
import logging
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from .._threads import blas_threads_for
from ..branch import Branch, SpecialPoint
from ..params import Params
from ..status import Status
from ..typing import FloatArray
from .orbit import PeriodicOrbit
from .problem import PeriodicOrbitProblem

log = logging.getLogger(__name__)


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

    #: Marks the problem of a cycle branch (``switch_branch`` hands it to the cycles').
    is_cycle_problem: ClassVar[bool] = True

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


def segments_of(br: Branch) -> tuple[list[PeriodicOrbitProblem], list[int]]:
    """The problems of a cycle branch and the row where each starts (one: ``[0]``)."""
    prob = br.problem
    if isinstance(prob, CycleSegments):
        return list(prob.problems), list(prob.first_row)
    return [prob], [0]


def reversed_segments(br: Branch) -> Branch:
    """The branch in the opposite order (rows, steps, special points, segments)."""
    N = len(br)
    probs, first = segments_of(br)
    ends = [f - 1 for f in first[1:]] + [N - 1]  # last row of each segment
    problem: Any = br.problem
    if len(probs) > 1:
        problem = CycleSegments(tuple(probs[::-1]), tuple(N - 1 - e for e in ends[::-1]))
    return br.reversed(problem=problem)


def truncated(br: Branch, k: int, status: Status, message: str) -> Branch:
    """Rows ``0 .. k`` of a cycle branch (with the special points between them)."""
    probs, first = segments_of(br)
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


def merge_segments(segs: list[Branch], *, joined: bool = True) -> Branch:
    """One branch from consecutive segments.

    ``joined``: the first row of each later segment is the previous segment's last cycle
    on the new mesh, and is dropped; else (two halves started apart, on either side of
    a branch point) every row is kept.
    """
    rows: dict[str, list[Any]] = {k: [] for k in ("p", "x", "eig", "nun", "ds", "it")}
    recs: dict[str, list[float]] = {}
    specials: list[SpecialPoint] = []
    first_row, probs = [], []
    base, s_base = 0, 0.0
    for k, b in enumerate(segs):
        lo = 1 if k and joined else 0
        sub_p, sub_f = segments_of(b)
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
        base += len(b) - 1 if joined else len(b)
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


__all__ = [
    "CycleSegments",
    "merge_segments",
    "multipliers",
    "orbit_at",
    "problem_at",
    "reversed_segments",
    "segments_of",
    "special_problem",
    "truncated",
]
