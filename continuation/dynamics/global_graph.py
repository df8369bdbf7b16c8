r"""The global phase portrait as a graph: saddles, attractors, and manifold branches.

Nodes are the known equilibria (keyed by name, identified modulo the periods of
periodic states, with their stability and saddle index), the periodic attractors found,
and the terminal events reached (e.g. ``"capsize"``), plus ``"escape"``/``"undecided"``
when they occur. Each index-1 saddle contributes two edges, one per branch of its
unstable manifold, from the saddle to the branch's fate; an edge carries the branch
sign, the shift in periods of the target, the saddles visited on the way, and the time.

Comparing the graphs at two parameter values (:func:`compare_graphs`) shows what changed:
an edge whose target changed between ``p1`` and ``p2`` means a global bifurcation in
between (a heteroclinic or homoclinic connection), which :mod:`continuation.dynamics.fate_bisection`
then locates. This is the picture of Umeda (1999, Sec. "Unstable manifolds and numerical
experiments"): the upslope branch of the crest saddle goes to a periodic attractor below
the critical Froude number and to capsizing above it.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..status import Status
from .classifier import FateClassifier
from .fates import Fate, FateKind, _with_shift

if TYPE_CHECKING:  # (networkx is imported where a graph is built or compared: ~0.2 s)
    import networkx as nx
from .manifolds import unstable_manifold

log = logging.getLogger(__name__)


def _periodic_node(graph: nx.MultiDiGraph, clf: FateClassifier, fate: Fate, match: float) -> str:
    """Name of the periodic-attractor node ``fate`` belongs to (added if new)."""
    tr = fate.trajectory
    sec = clf.section
    pts = None
    if tr is not None and sec is not None and sec.name in tr.events:
        hits = tr.events[sec.name]
        m = fate.multiplicity or 1
        pts = hits.x[-m:] if len(hits) >= m else hits.x
    if pts is None or len(pts) == 0:
        pts = np.asarray(fate.x)[None, :]
    for node, data in graph.nodes(data=True):
        if data.get("kind") != "periodic":
            continue
        for q in data["section_points"]:
            if min(clf.distance(q, x) for x in pts) <= match:
                return str(node)
    k = sum(1 for _, d in graph.nodes(data=True) if d.get("kind") == "periodic")
    name = f"P{k}"
    graph.add_node(
        name,
        kind="periodic",
        period=fate.period,
        multiplicity=fate.multiplicity,
        winding=fate.shift,
        section_points=np.array(pts),
    )
    return name


def _target(graph: nx.MultiDiGraph, clf: FateClassifier, fate: Fate, match: float) -> str:
    if fate.kind in (FateKind.EQUILIBRIUM, FateKind.SADDLE) and fate.index is not None:
        return clf.equilibria[fate.index].name
    if fate.kind is FateKind.EQUILIBRIUM:  # a stable equilibrium that was not given
        xe = fate.x_equilibrium if fate.x_equilibrium is not None else fate.x
        for node, data in graph.nodes(data=True):
            if data.get("kind") == "equilibrium" and clf.distance(data["x"], xe) <= match:
                return str(node)
        k = sum(1 for _, d in graph.nodes(data=True) if d.get("discovered"))
        name = f"new{k}"
        graph.add_node(
            name, kind="equilibrium", x=np.array(xe), n_unstable=0, stable=True, discovered=True
        )
        return name
    if fate.kind is FateKind.PERIODIC:
        return _periodic_node(graph, clf, fate, match)
    name = fate.name if fate.kind is FateKind.EVENT else fate.kind.value
    if name not in graph:
        graph.add_node(name, kind=fate.kind.value)
    return name


def build_global_graph(
    system: Any,
    params: Any,
    equilibria: Sequence[Any] | Mapping[str, Any],
    *,
    eps: float = 1e-6,
    match_tol: float | None = None,
    orient: str | int | None = None,
    progress: Callable[[str, int, Fate], None] | None = None,
    **classifier_options: Any,
) -> nx.MultiDiGraph:
    r"""Build the graph of equilibria, attractors and unstable-manifold branches.

    Parameters
    ----------
    system : System
        The dynamical system.
    params : Params, mapping or array_like, shape (m,)
        Parameter values.
    equilibria : sequence of array_like (n,) or mapping of str to array_like
        The equilibria (named ``E0, E1, ...`` unless a mapping), each once modulo the
        periods. Their stability is computed; the unstable manifold of every saddle of
        index 1 is computed and classified.
    eps : float
        Start distance of the manifold branches.
    match_tol : float, optional
        Scaled distance below which two periodic fates are the same attractor (compared
        at their section points); default ``1000 * tol``.
    orient : str or int, optional
        Orientation of the unstable eigenvectors (see :mod:`continuation.dynamics.manifolds`).
    progress : callable, optional
        ``progress(saddle_name, sign, fate)`` after each branch.
    **classifier_options
        The options of :class:`~continuation.dynamics.fates.FateClassifier`
        (``events``, ``poincare``, ``tol``, ``saddle_radius``, ``scale``, ``t_max``,
        ``segment``, ``dt``, ``method``, ...), with its defaults.

    Returns
    -------
    networkx.MultiDiGraph
        Nodes: equilibria (``kind="equilibrium"``, ``x``, ``eigenvalues``,
        ``n_unstable``, ``stable``), periodic attractors (``kind="periodic"``,
        ``period``, ``winding``, ``section_points``), events (``kind="event"``) and
        ``"escape"``/``"undecided"``. Edges ``saddle -> target`` with key ``"+"`` or
        ``"-"`` and attributes ``branch`` (+1/-1), ``shift``, ``visits`` (labels of the
        saddles passed), ``t``, ``kind``, ``fate``. ``graph.graph`` holds ``params``,
        ``state_names``, ``eps`` and ``status`` (``INTERRUPTED`` if stopped early).
    """
    clf = FateClassifier(system, params, equilibria=equilibria, **classifier_options)
    match = float(match_tol) if match_tol is not None else 1e3 * clf.tol
    if not match > 0:
        raise ValueError(f"`match_tol` must be positive, got {match_tol!r}")
    import networkx as nx

    g = nx.MultiDiGraph(
        params=np.array(clf.p),
        state_names=tuple(system.state_names),
        eps=float(eps),
        status=Status.SUCCESS,
    )
    for e in clf.equilibria:
        g.add_node(
            e.name,
            kind="equilibrium",
            x=np.array(e.x),
            eigenvalues=np.array(e.eigenvalues),
            n_unstable=e.n_unstable,
            stable=e.stable,
            discovered=False,
        )
    for e in clf.equilibria:
        if e.n_unstable != 1:
            if e.n_unstable > 1:
                g.nodes[e.name]["manifold"] = f"not computed (unstable dimension {e.n_unstable})"
                log.info("%s has a %d-D unstable manifold: skipped", e.name, e.n_unstable)
            continue
        try:
            res = unstable_manifold(
                system, clf.p, e.x, eps=eps, classify=clf, orient=orient, refine=False
            )
        except KeyboardInterrupt:
            g.graph["status"] = Status.INTERRUPTED
            break
        for br in res.branches:
            fate = br.fate
            if fate is None or fate.status is Status.INTERRUPTED:
                continue  # an interrupted branch has no fate: no edge
            target = _target(g, clf, fate, match)
            g.add_edge(
                e.name,
                target,
                key="+" if br.sign > 0 else "-",
                branch=br.sign,
                shift=fate.shift,
                visits=tuple(v.label for v in fate.visits),
                t=fate.t,
                kind=fate.kind.value,
                fate=fate,
            )
            if progress is not None:
                progress(e.name, br.sign, fate)
        if res.status is Status.INTERRUPTED:
            g.graph["status"] = Status.INTERRUPTED
            break
    return g


@dataclass(frozen=True)
class EdgeChange:
    """A manifold branch whose fate differs between two graphs.

    Attributes
    ----------
    source : str
        The saddle.
    branch : str
        ``"+"`` or ``"-"``.
    old, new : tuple
        ``(target, shift, visits)`` in the first and the second graph.
    """

    source: str
    branch: str
    old: tuple[str, tuple[int, ...], tuple[str, ...]]
    new: tuple[str, tuple[int, ...], tuple[str, ...]]

    @property
    def target_changed(self) -> bool:
        """True when the end point (target node or its shift) changed."""
        return self.old[:2] != self.new[:2]

    def __str__(self) -> str:
        def fmt(v: tuple[str, tuple[int, ...], tuple[str, ...]]) -> str:
            via = f" via {' -> '.join(v[2])}" if v[2] else ""
            return f"{_with_shift(v[0], v[1])}{via}"

        return f"{self.source}[{self.branch}]: {fmt(self.old)}  =>  {fmt(self.new)}"


@dataclass(frozen=True)
class GraphDiff:
    """Differences between two global graphs (from ``g1`` to ``g2``).

    Attributes
    ----------
    nodes_added, nodes_removed : tuple of str
        Nodes only in ``g2`` / only in ``g1``.
    stability_changed : tuple of (str, int, int)
        Equilibria in both whose saddle index changed: ``(name, old, new)`` (a local
        bifurcation in between).
    edges_changed : tuple of EdgeChange
        Branches present in both whose target, shift or visited saddles changed (a
        global bifurcation in between when the target changed).
    edges_added, edges_removed : tuple of (str, str)
        Branches ``(saddle, "+"|"-")`` only in ``g2`` / only in ``g1``.
    """

    nodes_added: tuple[str, ...] = ()
    nodes_removed: tuple[str, ...] = ()
    stability_changed: tuple[tuple[str, int, int], ...] = ()
    edges_changed: tuple[EdgeChange, ...] = ()
    edges_added: tuple[tuple[str, str], ...] = ()
    edges_removed: tuple[tuple[str, str], ...] = ()

    @property
    def changed(self) -> bool:
        """True if anything differs."""
        return bool(
            self.nodes_added
            or self.nodes_removed
            or self.stability_changed
            or self.edges_changed
            or self.edges_added
            or self.edges_removed
        )

    @property
    def global_bifurcation(self) -> bool:
        """True if a branch present in both graphs changed its target."""
        return any(c.target_changed for c in self.edges_changed)

    def __bool__(self) -> bool:
        return self.changed

    def summary(self) -> str:
        """Human-readable multi-line description."""
        if not self.changed:
            return "no change"
        lines = []
        if self.nodes_added:
            lines.append(f"nodes added: {', '.join(self.nodes_added)}")
        if self.nodes_removed:
            lines.append(f"nodes removed: {', '.join(self.nodes_removed)}")
        for name, a, b in self.stability_changed:
            lines.append(f"{name}: saddle index {a} -> {b}")
        lines.extend(str(c) for c in self.edges_changed)
        if self.edges_added:
            lines.append(f"branches added: {self.edges_added}")
        if self.edges_removed:
            lines.append(f"branches removed: {self.edges_removed}")
        return "\n".join(lines)


def _edges(
    g: nx.MultiDiGraph,
) -> dict[tuple[str, str], tuple[str, tuple[int, ...], tuple[str, ...]]]:
    out = {}
    for u, v, k, d in g.edges(keys=True, data=True):
        out[(str(u), str(k))] = (str(v), tuple(d.get("shift", ())), tuple(d.get("visits", ())))
    return out


def compare_graphs(g1: nx.MultiDiGraph, g2: nx.MultiDiGraph) -> GraphDiff:
    """What changed from ``g1`` to ``g2`` (graphs from :func:`build_global_graph`).

    Nodes are matched by name (so give the equilibria the same names at both parameter
    values, e.g. by following them with
    :class:`~continuation.dynamics.fate_bisection.EquilibriumTracker`); branches by
    ``(saddle, sign)``.

    Returns
    -------
    GraphDiff
    """
    import networkx as nx

    for name, g in (("g1", g1), ("g2", g2)):
        if not isinstance(g, nx.MultiDiGraph):
            raise ValueError(f"`{name}` must be a networkx.MultiDiGraph, got {type(g).__name__}")
    n1, n2 = set(map(str, g1.nodes)), set(map(str, g2.nodes))
    stab = []
    for name in sorted(n1 & n2):
        a, b = g1.nodes[name].get("n_unstable"), g2.nodes[name].get("n_unstable")
        if a is not None and b is not None and a != b:
            stab.append((name, int(a), int(b)))
    e1, e2 = _edges(g1), _edges(g2)
    changed = tuple(
        EdgeChange(key[0], key[1], e1[key], e2[key])
        for key in sorted(set(e1) & set(e2))
        if e1[key] != e2[key]
    )
    return GraphDiff(
        nodes_added=tuple(sorted(n2 - n1)),
        nodes_removed=tuple(sorted(n1 - n2)),
        stability_changed=tuple(stab),
        edges_changed=changed,
        edges_added=tuple(sorted(set(e2) - set(e1))),
        edges_removed=tuple(sorted(set(e1) - set(e2))),
    )


__all__ = ["EdgeChange", "GraphDiff", "build_global_graph", "compare_graphs"]
