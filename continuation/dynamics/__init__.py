"""Time-domain tools: simulation, unstable manifolds, fates and global bifurcations.

Simulation (:mod:`.simulate`) of :math:`\\dot x = f(x, p)` with events and Poincare
sections; the one-dimensional unstable manifolds of saddles (:mod:`.manifolds`); where a
trajectory goes (:mod:`.fates`); the parameter value where a fate switches
(:mod:`.fate_bisection`); and the global phase portrait as a graph (:mod:`.global_graph`).
"""

from .fate_bisection import (
    BisectionResult,
    EquilibriumTracker,
    bisect_fate,
    manifold_fate_function,
)
from .fates import Fate, FateClassifier, FateKind, SaddleVisit, classify_fate, passage_side
from .global_graph import EdgeChange, GraphDiff, build_global_graph, compare_graphs
from .manifolds import ManifoldBranch, ManifoldResult, unstable_manifold
from .simulate import EventHits, PoincareSection, SimEvent, Simulator, Trajectory, simulate

__all__ = [
    # simulation
    "simulate",
    "Simulator",
    "SimEvent",
    "PoincareSection",
    "Trajectory",
    "EventHits",
    # unstable manifolds
    "unstable_manifold",
    "ManifoldResult",
    "ManifoldBranch",
    # fates
    "classify_fate",
    "FateClassifier",
    "Fate",
    "FateKind",
    "SaddleVisit",
    "passage_side",
    # fate bisection (global bifurcations)
    "bisect_fate",
    "BisectionResult",
    "EquilibriumTracker",
    "manifold_fate_function",
    # global graph
    "build_global_graph",
    "compare_graphs",
    "GraphDiff",
    "EdgeChange",
]
