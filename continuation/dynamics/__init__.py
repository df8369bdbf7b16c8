r"""Time-domain tools: simulation, unstable manifolds, fates and global bifurcations.

Simulation of :math:`\dot x = f(x, p)` (:mod:`.simulate`, the loop; :mod:`.integrators`,
the CVODES and SciPy back-ends; :mod:`.events`, events and Poincare sections;
:mod:`.trajectory`, the result and its files); local analysis of saddles
(:mod:`.saddles`); their one-dimensional unstable manifolds (:mod:`.manifolds`); where a
trajectory goes (:mod:`.fates`, the outcome; :mod:`.classifier`, the classifier;
:mod:`.fate_scan`, its per-segment tests); the parameter value where a fate switches
(:mod:`.fate_bisection`); and the global phase portrait as a graph (:mod:`.global_graph`).
"""

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:  # for type checkers; _EXPORTS is what runs (names imported on first use)
    from .classifier import FateClassifier, classify_fate
    from .events import PoincareSection, SimEvent
    from .fate_bisection import (
        BisectionResult,
        EquilibriumTracker,
        bisect_fate,
        fate_label,
        manifold_fate_function,
    )
    from .fates import Fate, FateKind, KnownEquilibrium, SaddleVisit, passage_side
    from .global_graph import EdgeChange, GraphDiff, build_global_graph, compare_graphs
    from .integrators import DEFAULT_ATOL, DEFAULT_RTOL, METHODS
    from .manifolds import ManifoldBranch, ManifoldResult, unstable_manifold
    from .saddles import oriented_unstable_direction, refine_equilibrium
    from .shooting import ReturnMap, ShootingOrbit, ShootingSettings, shoot_orbit
    from .simulate import Simulator, simulate
    from .trajectory import EventHits, Trajectory

#: Sub-module -> the public names it defines (imported on first use: issue 27).
_EXPORTS: dict[str, tuple[str, ...]] = {
    "classifier": ("FateClassifier", "classify_fate"),
    "events": ("PoincareSection", "SimEvent"),
    "fate_bisection": (
        "BisectionResult",
        "EquilibriumTracker",
        "bisect_fate",
        "fate_label",
        "manifold_fate_function",
    ),
    "fates": ("Fate", "FateKind", "KnownEquilibrium", "SaddleVisit", "passage_side"),
    "global_graph": ("EdgeChange", "GraphDiff", "build_global_graph", "compare_graphs"),
    "integrators": ("DEFAULT_ATOL", "DEFAULT_RTOL", "METHODS"),
    "manifolds": ("ManifoldBranch", "ManifoldResult", "unstable_manifold"),
    "saddles": ("oriented_unstable_direction", "refine_equilibrium"),
    "shooting": ("ReturnMap", "ShootingOrbit", "ShootingSettings", "shoot_orbit"),
    "simulate": ("Simulator", "simulate"),
    "trajectory": ("EventHits", "Trajectory"),
}

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
del TYPE_CHECKING, lazy_exports

__all__ = [
    # periodic orbits by return-map shooting
    "shoot_orbit",
    "ShootingOrbit",
    "ShootingSettings",
    "ReturnMap",
    # simulation
    "simulate",
    "Simulator",
    "SimEvent",
    "PoincareSection",
    "Trajectory",
    "EventHits",
    "METHODS",
    "DEFAULT_RTOL",
    "DEFAULT_ATOL",
    # saddles
    "refine_equilibrium",
    "oriented_unstable_direction",
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
    "KnownEquilibrium",
    "passage_side",
    # fate bisection (global bifurcations)
    "bisect_fate",
    "fate_label",
    "BisectionResult",
    "EquilibriumTracker",
    "manifold_fate_function",
    # global graph
    "build_global_graph",
    "compare_graphs",
    "GraphDiff",
    "EdgeChange",
]
