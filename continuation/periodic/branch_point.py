r"""The branch of cycles crossing a cycle branch at a branch point of cycles (BPC).

At a simple BPC (a nontrivial Floquet multiplier through 1 with the branch going on,
e.g. the symmetry-breaking pitchfork of the symmetric cycles of AUTO-07p's demo
``tor``) the crossing branch is found as for equilibria: the algebraic bifurcation
equation of the collocation system at the point gives its tangent and a first point
on it (:func:`~continuation.switching.switch.switch_branch_rows`, on the mesh the point
was located on). From there the crossing branch is a cycle branch like any other:
:func:`~continuation.periodic.continuation.continue_periodic` continues it with its
Floquet tests (PD, NS; no Hopf test on Floquet exponents), mesh adaptation to
``error_tol`` and period-limit end, leaving the branch point along the secant of the
first step (Doedel, Keller & Kernevez 1991, "Numerical analysis and control of
bifurcation problems (II)", IJBC 1:745-772, Sec. 6; Kuznetsov 2004, Sec. 10.3.3).
"""

from __future__ import annotations

import dataclasses
from typing import Any, Literal

import numpy as np

from ..branch import Branch, SpecialKind, SpecialPoint
from ..settings import ContinuationSettings
from .continuation import continue_periodic
from .rows import merge_segments, orbit_at, reversed_segments, special_problem


def _bpc_point(branch: Branch, which: Any) -> SpecialPoint:
    if isinstance(which, SpecialPoint):
        return which
    bps = [s for s in branch.special_points if s.kind is SpecialKind.BRANCH_POINT]
    if isinstance(which, str):
        for s in bps:
            if s.label == which:
                return s
        raise ValueError(
            f"`point`: no branch point of cycles labelled {which!r}; labels are "
            f"{[s.label for s in bps]}"
        )
    raise ValueError(f"`point` must be a BPC label or SpecialPoint, got {type(which).__name__}")


def _one_mesh_view(branch: Branch, sp: SpecialPoint) -> tuple[Branch, SpecialPoint]:
    """The rows around ``sp`` (``sp.index``, ``sp.index + 1``) on the mesh of ``sp``.

    The generic switching reads the current branch's direction from these two rows; on
    an adapted branch they may lie on different meshes, so both are interpolated onto
    the point's mesh.
    """
    prob = special_problem(branch, sp)
    rows = [k for k in (sp.index, sp.index + 1) if 0 <= k < len(branch)]
    zs = []
    for k in rows:
        o = orbit_at(branch, k).on_mesh(prob.mesh)
        zs.append(prob.layout.join(o.X, o.T))
    view = Branch(
        problem=prob,
        free=branch.free,
        p=branch.p[rows],
        x=np.array(zs),
        eigenvalues=branch.eigenvalues[rows],
        n_unstable=branch.n_unstable[rows],
        ds=branch.ds[rows],
        newton_iters=branch.newton_iters[rows],
        records={},
        special_points=(dataclasses.replace(sp, index=0),),
        status=branch.status,
        message=branch.message,
        settings=branch.settings,
        state_names=branch.state_names,
        param_values=branch.param_values,
    )
    return view, view.special_points[0]


def continue_from_branch_point(
    branch: Branch,
    point: SpecialPoint | str,
    settings: ContinuationSettings | None = None,
    *,
    direction: Literal["forward", "backward", "both"] = "forward",
    amplitude: float | None = None,
    throw: bool = False,
    **kwargs: Any,
) -> Branch:
    """The cycle branch crossing ``branch`` at the branch point of cycles ``point``.

    Parameters
    ----------
    branch : Branch
        A cycle branch of :func:`~continuation.periodic.continuation.continue_periodic`.
    point : SpecialPoint or str
        A located branch point of it (``"BPC1"``...).
    settings : ContinuationSettings, optional
        For the new branch (default ``branch.settings``); ``sign(ds)`` picks its half
        where ``direction`` is ``"forward"`` or ``"backward"``, as in
        :func:`~continuation.switching.switch.switch_branch`.
    direction : {"forward", "backward", "both"}
        One half of the crossing branch, the other, or both (one branch from the
        backward end to the forward end, each half started off the branch point; the
        status is the forward half's, the backward half's is in the message).
    amplitude : float, optional
        Distance of the first point from the branch point (as in
        :func:`~continuation.switching.switch.switch_branch`).
    throw : bool
        Raise instead of returning a failed branch.
    **kwargs
        More keywords of :func:`~continuation.periodic.continuation.continue_periodic`
        (``error_tol``, ``period_max``, ``events``, ...).

    Returns
    -------
    Branch
        A cycle branch (records, multipliers, special points LPC/BPC/PD/NS as for
        :func:`~continuation.periodic.continuation.continue_periodic`), its message
        starting with the switching data; an empty branch with the switching's status
        where no point on the crossing branch was found.
    """
    from ..switching.switch import switch_branch_rows

    if direction not in ("forward", "backward", "both"):
        raise ValueError(f"`direction` must be 'forward', 'backward' or 'both', got {direction!r}")
    sp = _bpc_point(branch, point)
    view, sp0 = _one_mesh_view(branch, sp)
    settings = settings if settings is not None else branch.settings
    settings = settings if settings is not None else ContinuationSettings()
    # two steps of the generic switch: the first points on the crossing branch (no tests)
    det = dataclasses.replace(settings.detect, hopf=False, fold=False, branch_point=False)
    first = dataclasses.replace(settings, max_steps=2, detect=det)
    sides = ("forward", "backward") if direction == "both" else (direction,)
    halves = []
    for side in sides:
        sw = switch_branch_rows(view, sp0, settings=first, direction=side,  # type: ignore[arg-type]
                                amplitude=amplitude, throw=throw)  # fmt: skip
        if len(sw) < 2:
            return sw
        info = sw.message.split("; ")[0]
        # the start: the second point (off the branch point), leaving along the secant
        start, prev = orbit_at(sw, 1), orbit_at(sw, 0)
        br = continue_periodic(start.system, start, start.params, branch.free, settings,
                               previous=prev, throw=throw, **kwargs)  # fmt: skip
        halves.append(dataclasses.replace(br, message=f"{info}; {br.message}"))
    if len(halves) == 1:
        return halves[0]
    f, b = halves  # (in the order of `sides`)
    if len(b) == 0 or len(f) == 0:
        return f if len(f) else b
    # (as continue_periodic's "both": the forward half's status, the backward's in the
    # message; the halves start apart, off the branch point, so every row is kept)
    merged = merge_segments([reversed_segments(b), f], joined=False)
    return dataclasses.replace(
        merged, status=f.status, message=f"{f.message} (backward half: {b.status.name}: "
        f"{b.message})"
    )  # fmt: skip


__all__ = ["continue_from_branch_point"]
