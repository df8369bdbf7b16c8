r"""The global picture of the ship's phase space as a graph: fixed points, attractors, manifolds.

Umeda (1999) reads the global topology of the 8-dimensional phase space off the
unstable manifolds of the saddles: where each branch goes (capsize, a periodic
attractor, stable surf-riding), and which saddles it passes on the way. This module
puts that picture into a :class:`networkx.MultiDiGraph` (Hagberg, Schult & Swart
2008, "Exploring network structure, dynamics, and function using NetworkX", Proc.
SciPy 2008):

- one node per fixed point (its label; attributes ``kind="fixed_point"``,
  ``saddle_index``, ``stable``, ``x``);
- one node per attractor that is not a fixed point: ``"capsize"``, ``"periodic"``,
  ``"recurrent"``, ``"undecided"`` (attribute ``kind`` the same name);
- one edge per branch of the unstable manifold of every saddle of index 1, from the
  saddle to its fate (key = branch name ``"downslope"``/``"upslope"``; attributes
  ``fate``, ``t`` (s), ``via`` (the saddles visited, as ``"label@shift"``),
  ``period``, ``drift``, ``shift`` for a fixed point reached).

Saddles of higher index (their unstable manifolds are not curves) are nodes with
``manifold="dimension k, not computed"``. :func:`compare_pictures` lists what changed
between two parameter values: a changed edge target (or a changed ``via``) marks a
global bifurcation between them, e.g. the heteroclinic bifurcation of the paper.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import networkx as nx
import numpy as np

from continuation.params import Params

from ..contracts import VesselModel
from .fixed_points import FixedPoint, fixed_points
from .manifold import ShipManifold, unstable_manifold
from .outcomes import ShipOutcome
from .params import ship_params


def _via(fate: Any) -> tuple[str, ...]:
    return tuple(f"{v.label}@{v.shift:+d}" for v in fate.visits)


def build_global_picture(
    model: VesselModel,
    params: Params | None = None,
    *,
    points: Sequence[FixedPoint] | None = None,
    manifolds: Mapping[str, ShipManifold] | None = None,
    eps: float = 1e-6,
    t_max: float = 600.0,
    progress: Callable[[str, str, float], None] | None = None,
    **classify: Any,
) -> nx.MultiDiGraph:
    """Fixed points, attractors and unstable-manifold branches of the ship at ``params``.

    Parameters
    ----------
    model : VesselModel
    params : Params, optional
        Default: the model's defaults.
    points : sequence of FixedPoint, optional
        Default: :func:`~ship_models.analysis.fixed_points` at ``params``.
    manifolds : mapping of str to ShipManifold, optional
        Unstable manifolds already computed at ``params`` (by
        :func:`~ship_models.analysis.manifold.unstable_manifold` with the same
        ``eps``, ``t_max`` and classification options), by saddle label: used instead
        of computing them again. Each must have both branches, the same ``params``
        and ``eps``, and its saddle at the state of the point of that label.
    eps, t_max, **classify
        Passed to :func:`~ship_models.analysis.manifold.unstable_manifold`.
    progress : callable, optional
        ``progress(saddle_label, branch_name, t)`` during the simulations.

    Returns
    -------
    networkx.MultiDiGraph
        Graph attributes: ``params`` (dict), ``manifolds`` (dict label ->
        :class:`~ship_models.analysis.manifold.ShipManifold`).

    Raises
    ------
    ValueError
        If a manifold of ``manifolds`` does not belong to ``params``, ``eps`` and the
        saddle of its label, or lacks a branch.
    """
    par = ship_params(model, params)
    pts = tuple(points) if points is not None else tuple(fixed_points(model, par))
    given = dict(manifolds or {})
    for label, pre in given.items():
        _check_given(label, pre, pts, par, eps)
    g = nx.MultiDiGraph(params=par.as_dict(), manifolds={})
    for fp in pts:
        g.add_node(
            fp.label,
            kind="fixed_point",
            saddle_index=fp.saddle_index,
            stable=fp.stable,
            x=[float(v) for v in fp.x],
        )
    for fp in pts:
        if fp.saddle_index == 0:
            continue
        if fp.saddle_index > 1 or fp.eigen.values[0].imag != 0.0:
            g.nodes[fp.label]["manifold"] = f"dimension {fp.saddle_index}, not computed"
            continue
        cb = None if progress is None else (lambda b, t, _l=fp.label: progress(_l, b, t))
        man: ShipManifold = given.get(fp.label) or unstable_manifold(
            model, par, fp, eps=eps, t_max=t_max, points=pts, progress=cb, **classify
        )
        g.graph["manifolds"][fp.label] = man
        for name, br in man.branches.items():
            fate = br.fate
            target = (
                fate.equilibrium
                if fate.kind in (ShipOutcome.EQUILIBRIUM, ShipOutcome.SADDLE)
                else fate.kind
            )
            if target not in g:
                g.add_node(target, kind=fate.kind)
            g.add_edge(
                fp.label,
                target,
                key=name,
                fate=fate.label,
                t=fate.t,
                via=_via(fate),
                period=fate.period,
                drift=fate.drift,
                shift=fate.shift,
            )
    return g


def _check_given(
    label: str, man: ShipManifold, pts: Sequence[FixedPoint], par: Params, eps: float
) -> None:
    """Refuse a precomputed manifold that is not the one :func:`build_global_picture` needs."""
    match = [fp for fp in pts if fp.label == label]
    why = ""
    if not match:
        why = "no fixed point has this label"
    elif not np.array_equal(np.asarray(man.saddle.x), np.asarray(match[0].x)):
        why = "its saddle is not the fixed point of this label"
    elif not np.array_equal(np.asarray(man.params.values), np.asarray(par.values)):
        why = "it was computed at other parameters"
    elif man.eps != float(eps):
        why = f"it was computed with eps={man.eps!r}, not {eps!r}"
    elif set(man.branches) != {"downslope", "upslope"}:
        why = f"it has the branches {sorted(man.branches)}, not both"
    if why:
        raise ValueError(f"`manifolds`: the manifold given for {label!r} does not fit: {why}")


@dataclass(frozen=True)
class PictureDiff:
    """What changed between two global pictures.

    Attributes
    ----------
    added_nodes, removed_nodes : tuple of str
    changed_edges : tuple of (source, branch, old_target, new_target)
        Branches whose fate changed.
    changed_via : tuple of (source, branch, old_via, new_via)
        Branches with the same fate that now pass different saddles.
    """

    added_nodes: tuple[str, ...]
    removed_nodes: tuple[str, ...]
    changed_edges: tuple[tuple[str, str, str | None, str | None], ...]
    changed_via: tuple[tuple[str, str, tuple[str, ...], tuple[str, ...]], ...]

    @property
    def changed(self) -> bool:
        """True when the topology (nodes or edge targets) differs."""
        return bool(self.added_nodes or self.removed_nodes or self.changed_edges)


def compare_pictures(g1: nx.MultiDiGraph, g2: nx.MultiDiGraph) -> PictureDiff:
    """Differences between two pictures from :func:`build_global_picture`.

    A branch present in only one graph appears in ``changed_edges`` with ``None`` on
    the other side.
    """

    def edges(g: nx.MultiDiGraph) -> dict[tuple[str, str], tuple[str, tuple[str, ...]]]:
        return {
            (u, k): (v, tuple(d.get("via", ()))) for u, v, k, d in g.edges(keys=True, data=True)
        }

    e1, e2 = edges(g1), edges(g2)
    changed, via = [], []
    for key in sorted(set(e1) | set(e2)):
        a, b = e1.get(key), e2.get(key)
        if a is None or b is None or a[0] != b[0]:
            changed.append((key[0], key[1], a[0] if a else None, b[0] if b else None))
        elif a[1] != b[1]:
            via.append((key[0], key[1], a[1], b[1]))
    n1, n2 = set(g1.nodes), set(g2.nodes)
    return PictureDiff(tuple(sorted(n2 - n1)), tuple(sorted(n1 - n2)), tuple(changed), tuple(via))


__all__ = ["PictureDiff", "compare_pictures", "build_global_picture"]
