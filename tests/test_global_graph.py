"""Tests of continuation.dynamics.global_graph on systems whose global phase portraits are known."""

from __future__ import annotations

import itertools

import networkx as nx
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from continuation.dynamics import GraphDiff, SimEvent, build_global_graph, compare_graphs
from continuation.status import Status
from continuation.system import System


def _pendulum(x, p, ops):
    return ops.stack([x[1], -ops.sin(x[0]) - p[0] * x[1] + p[1]])


def _switch(x, p, ops):
    # x' = 1 - x^2, y' = x y + mu - c x^2: the + branch of the saddle L = (-1, mu - c)
    # escapes upwards for mu > c/2 and downwards for mu < c/2 (closed form, see
    # tests/test_fates.py); at mu = c/2 it connects to the saddle R = (1, c - mu).
    return ops.stack([1 - x[0] ** 2, x[0] * x[1] + p[0] - p[1] * x[0] ** 2])


def _square(x, p, ops):
    # x' = x - x^3, y' = y - y^3: decoupled; every manifold lies on a grid line
    return ops.stack([x[0] - x[0] ** 3, x[1] - x[1] ** 3])


PEND = System(_pendulum, ("theta", "omega"), ("gamma", "F"), periodic={"theta": 2 * np.pi})
SWITCH = System(_switch, ("x", "y"), ("mu", "c"))
SQUARE = System(_square, ("x", "y"), ())
C = 1.3
SWITCH_EVENTS = (
    SimEvent("y_up", lambda t, x: x[1] - 20.0, terminal=True, direction=1),
    SimEvent("y_down", lambda t, x: x[1] + 20.0, terminal=True, direction=-1),
    SimEvent("x_escape", lambda t, x: x[0] + 5.0, terminal=True, direction=-1),
)


def _edges(g):
    return {(u, k): (v, d["shift"]) for u, v, k, d in g.edges(keys=True, data=True)}


def _driven(F, g=0.25):
    th = np.arcsin(F)
    return build_global_graph(
        PEND, [g, F], {"down": [th, 0.0], "up": [np.pi - th, 0.0]}, t_max=600.0
    )


def test_damped_pendulum_graph():
    calls = []
    g = build_global_graph(
        PEND,
        [0.5, 0.0],
        {"down": [0.0, 0.0], "up": [np.pi, 0.0]},
        t_max=200.0,
        progress=lambda s, b, f: calls.append((s, b, f.label)),
    )
    assert isinstance(g, nx.MultiDiGraph)
    assert set(g.nodes) == {"down", "up"}
    assert g.nodes["down"]["stable"] and g.nodes["down"]["n_unstable"] == 0
    assert g.nodes["up"]["n_unstable"] == 1
    assert _edges(g) == {("up", "+"): ("down", (1,)), ("up", "-"): ("down", (0,))}
    assert g.number_of_edges() == 2
    assert g.graph["status"] is Status.SUCCESS
    assert calls == [("up", 1, "equilibrium:down@+1"), ("up", -1, "equilibrium:down")]
    assert not compare_graphs(g, g)
    assert compare_graphs(g, g).summary() == "no change"


def test_decoupled_square_graph_matches_grid_lines():
    # equilibria at {-1, 0, 1}^2: (0,0) a source (index 2, skipped), the four (+-1, 0),
    # (0, +-1) saddles, the four corners sinks. The unstable manifold of (a, 0) is the
    # line x = a, ending at (a, +-1); that of (0, b) the line y = b, ending at (+-1, b).
    pts = {f"({a},{b})": [float(a), float(b)] for a, b in itertools.product((-1, 0, 1), repeat=2)}
    g = build_global_graph(SQUARE, [], pts, t_max=100.0)
    assert g.nodes["(0,0)"]["n_unstable"] == 2 and "manifold" in g.nodes["(0,0)"]
    for name in ("(1,1)", "(1,-1)", "(-1,1)", "(-1,-1)"):
        assert g.nodes[name]["stable"]
    expected = {}
    for a in (-1, 1):
        expected[(f"({a},0)", "+")] = (f"({a},1)", ())
        expected[(f"({a},0)", "-")] = (f"({a},-1)", ())
        expected[(f"(0,{a})", "+")] = (f"(1,{a})", ())
        expected[(f"(0,{a})", "-")] = (f"(-1,{a})", ())
    assert _edges(g) == expected
    assert set(g.nodes) == set(pts)


def test_homoclinic_bifurcation_of_driven_pendulum_changes_the_graph():
    # g = 0.25: below the homoclinic bifurcation (F_c ~ 4 g / pi ~ 0.32 by Melnikov's
    # method) the + branch of the saddle falls to the next hanging equilibrium; above
    # it, to the running periodic orbit that coexists with the equilibrium.
    g_low, g_high = _driven(0.1), _driven(0.6)
    assert _edges(g_low) == {("up", "+"): ("down", (1,)), ("up", "-"): ("down", (0,))}
    assert _edges(g_high) == {("up", "+"): ("P0", (1,)), ("up", "-"): ("down", (0,))}
    p0 = g_high.nodes["P0"]
    assert p0["kind"] == "periodic" and p0["winding"] == (1,)
    # the running orbit exists at F = 0.6, independently: SciPy from its section point
    x0 = p0["section_points"][0]
    sol = solve_ivp(
        lambda t, y: [y[1], -np.sin(y[0]) - 0.25 * y[1] + 0.6],
        (0, p0["period"]),
        x0,
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
    )
    np.testing.assert_allclose(sol.y[:, -1], x0 + [2 * np.pi, 0.0], atol=1e-5)
    diff = compare_graphs(g_low, g_high)
    assert isinstance(diff, GraphDiff) and diff.changed and diff.global_bifurcation
    assert diff.nodes_added == ("P0",) and diff.nodes_removed == ()
    assert len(diff.edges_changed) == 1
    ch = diff.edges_changed[0]
    assert (ch.source, ch.branch) == ("up", "+")
    assert ch.old[:2] == ("down", (1,)) and ch.new[:2] == ("P0", (1,))
    assert "up[+]: down@+1  =>  P0@+1" in diff.summary()


def test_heteroclinic_switch_changes_exactly_one_edge():
    def graph(mu):
        eqs = {"L": [-1.0, mu - C], "R": [1.0, C - mu]}
        return build_global_graph(SWITCH, [mu, C], eqs, events=SWITCH_EVENTS, t_max=60.0)

    below, above = graph(C / 2 - 0.05), graph(C / 2 + 0.05)
    assert _edges(below) == {
        ("L", "+"): ("y_down", ()),
        ("L", "-"): ("x_escape", ()),
        ("R", "+"): ("y_up", ()),
        ("R", "-"): ("y_down", ()),
    }
    diff = compare_graphs(below, above)
    assert diff.global_bifurcation
    assert [(c.source, c.branch, c.old[0], c.new[0]) for c in diff.edges_changed] == [
        ("L", "+", "y_down", "y_up")
    ]
    assert below.nodes["y_up"]["kind"] == "event"
    # far from mu* the branch stays away from R; close to it, it passes R on the way,
    # which the edge records (and compare_graphs reports as a change of path)
    assert above.edges["L", "y_up", "+"]["visits"] == ()
    near = graph(C / 2 + 1e-5)
    assert near.edges["L", "y_up", "+"]["visits"] == ("R",)
    ch = compare_graphs(above, near).edges_changed
    assert len(ch) == 1 and not ch[0].target_changed and ch[0].new[2] == ("R",)


def test_compare_graphs_reports_nodes_and_stability():
    g1 = nx.MultiDiGraph()
    g1.add_node("A", n_unstable=1)
    g1.add_node("B", n_unstable=0)
    g1.add_edge("A", "B", key="+", shift=(), visits=())
    g2 = nx.MultiDiGraph()
    g2.add_node("A", n_unstable=2)
    g2.add_node("C", n_unstable=0)
    diff = compare_graphs(g1, g2)
    assert diff.nodes_added == ("C",) and diff.nodes_removed == ("B",)
    assert diff.stability_changed == (("A", 1, 2),)
    assert diff.edges_removed == (("A", "+"),) and not diff.global_bifurcation
    with pytest.raises(ValueError, match="g1"):
        compare_graphs(nx.Graph(), g2)


def test_build_global_graph_bad_input():
    with pytest.raises(ValueError, match="match_tol"):
        build_global_graph(PEND, [0.5, 0.0], [[0.0, 0.0]], match_tol=-1.0)
    with pytest.raises(ValueError, match="equilibria"):
        build_global_graph(PEND, [0.5, 0.0], [[1.0, 1.0]])
