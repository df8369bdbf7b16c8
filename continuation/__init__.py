"""broachkit's generic continuation and bifurcation engine.

Knows nothing of ships. The public API is exactly what this module exports.
"""

from .algorithms import PALC, ContinuationAlgorithm, Natural, StepOutcome, StepState
from .api import continue_equilibria
from .branch import Branch, BranchPoint, SpecialKind, SpecialPoint
from .bvp import (
    CollocationMesh,
    ConnectionResult,
    ConvergenceCheck,
    HeteroclinicProblem,
    JacobianCache,
    PinPhase,
    check_convergence,
    connection_at,
    continue_connection,
    simplified_newton,
    solve_connection,
)
from .codim2 import FoldProblem, HopfProblem, continue_codim2
from .driver import continue_branch
from .dynamics import (
    BisectionResult,
    EdgeChange,
    EquilibriumTracker,
    EventHits,
    Fate,
    FateClassifier,
    FateKind,
    GraphDiff,
    ManifoldBranch,
    ManifoldResult,
    PoincareSection,
    SaddleVisit,
    SimEvent,
    Simulator,
    Trajectory,
    bisect_fate,
    build_global_graph,
    classify_fate,
    compare_graphs,
    manifold_fate_function,
    passage_side,
    simulate,
    unstable_manifold,
)
from .equilibria import EquilibriumResult, solve_equilibrium, unique_equilibria
from .errors import ContinuationError, ConvergenceError, ModelError
from .events import Event
from .newton import NewtonResult, newton
from .ops import CASADI_OPS, NUMPY_OPS, Ops
from .params import Params
from .problem import ContinuationProblem, EquilibriumProblem
from .settings import ContinuationSettings, DetectionSettings, NewtonSettings
from .stability import (
    EigenResult,
    count_unstable,
    dense_stability,
    eigen,
    eigenvalues,
    n_unstable,
    sort_eigenvalues,
)
from .status import Status
from .switching import CrossingTangents, crossing_tangents, switch_branch
from .system import DynamicalSystem, System, check_jacobian

__all__ = [
    "dense_stability",
    "JacobianCache",
    "simplified_newton",
    "passage_side",
    "simulate",
    "Simulator",
    "SimEvent",
    "PoincareSection",
    "Trajectory",
    "EventHits",
    "unstable_manifold",
    "ManifoldResult",
    "ManifoldBranch",
    "classify_fate",
    "FateClassifier",
    "Fate",
    "FateKind",
    "SaddleVisit",
    "build_global_graph",
    "compare_graphs",
    "GraphDiff",
    "EdgeChange",
    "bisect_fate",
    "BisectionResult",
    "EquilibriumTracker",
    "manifold_fate_function",
    "PALC",
    "Branch",
    "BranchPoint",
    "ContinuationAlgorithm",
    "EigenResult",
    "EquilibriumResult",
    "Event",
    "Natural",
    "StepOutcome",
    "StepState",
    "n_unstable",
    "sort_eigenvalues",
    "SpecialKind",
    "SpecialPoint",
    "CollocationMesh",
    "ConnectionResult",
    "ConvergenceCheck",
    "HeteroclinicProblem",
    "PinPhase",
    "check_convergence",
    "connection_at",
    "continue_connection",
    "solve_connection",
    "FoldProblem",
    "HopfProblem",
    "continue_branch",
    "continue_codim2",
    "switch_branch",
    "crossing_tangents",
    "CrossingTangents",
    "continue_equilibria",
    "count_unstable",
    "eigen",
    "eigenvalues",
    "solve_equilibrium",
    "unique_equilibria",
    "CASADI_OPS",
    "NUMPY_OPS",
    "ContinuationError",
    "ContinuationProblem",
    "ContinuationSettings",
    "ConvergenceError",
    "DetectionSettings",
    "DynamicalSystem",
    "EquilibriumProblem",
    "ModelError",
    "NewtonResult",
    "NewtonSettings",
    "Ops",
    "Params",
    "Status",
    "System",
    "check_jacobian",
    "newton",
]
