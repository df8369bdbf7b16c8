"""broachkit's generic continuation and bifurcation engine.

Knows nothing of ships. This module is the designed front door: the names a user of the
engine needs to define a model, follow its equilibria, switch branches, follow fold and
Hopf points in two parameters, compute connecting orbits and integrate in time.
Everything else is importable from its sub-module (``continuation.stability``,
``continuation.newton``, ``continuation.algorithms``, ``continuation.bvp``, ...).
"""

# Names are imported on first use (issue 27: a single command-line query must not
# load the whole engine, SciPy's optimisation and integration packages, ...):
# ``from continuation import System`` imports continuation.system alone. The static
# imports below are for type checkers; _EXPORTS is what runs (tests/test_import_light.py
# checks that the two and __all__ agree).
# ruff: noqa: I001

from typing import TYPE_CHECKING

from ._lazy import lazy_exports

if TYPE_CHECKING:  # (grouped by topic, as in __all__, not sorted)
    # the model: a system, its parameter values, its operator set
    from .system import System
    from .params import Params
    from .ops import Ops

    # one-parameter continuation: entry points, settings, algorithms, events, problems
    from .api import continue_equilibria
    from .driver import continue_branch
    from .equilibria import solve_equilibrium
    from .settings import ContinuationSettings, DetectionSettings, NewtonSettings
    from .algorithms import PALC, Natural
    from .events import Event
    from .problem import ContinuationProblem, EquilibriumProblem
    from .check import ProblemCheck, check_problem

    # results, status and errors
    from .branch import Branch, BranchPoint, SpecialKind, SpecialPoint
    from .status import Status
    from .errors import ContinuationError, ConvergenceError, ModelError

    # branch switching at branch points
    from .switching import crossing_tangents, switch_branch

    # two-parameter continuation of folds and Hopf points
    from .codim2 import FoldProblem, HopfProblem, continue_codim2

    # connecting orbits (boundary-value problems)
    from .bvp import (
        ConnectionResult,
        HeteroclinicProblem,
        continue_connection,
        find_connection,
        solve_connection,
    )

    # periodic orbits (collocation, Floquet multipliers, cycle bifurcations)
    from .periodic import continue_from_hopf, continue_periodic, periodic_orbit_from_hopf

    # time domain (continuation.dynamics): simulation, manifolds, fates
    from .dynamics import (
        FateKind,
        Trajectory,
        bisect_fate,
        classify_fate,
        simulate,
        unstable_manifold,
    )

#: Sub-module -> the public names it defines.
_EXPORTS: dict[str, tuple[str, ...]] = {
    "system": ("System",),
    "params": ("Params",),
    "ops": ("Ops",),
    "api": ("continue_equilibria",),
    "driver": ("continue_branch",),
    "equilibria": ("solve_equilibrium",),
    "settings": ("ContinuationSettings", "DetectionSettings", "NewtonSettings"),
    "algorithms": ("PALC", "Natural"),
    "events": ("Event",),
    "problem": ("ContinuationProblem", "EquilibriumProblem"),
    "check": ("ProblemCheck", "check_problem"),
    "branch": ("Branch", "BranchPoint", "SpecialKind", "SpecialPoint"),
    "status": ("Status",),
    "errors": ("ContinuationError", "ConvergenceError", "ModelError"),
    "switching": ("crossing_tangents", "switch_branch"),
    "codim2": ("FoldProblem", "HopfProblem", "continue_codim2"),
    "bvp": (
        "ConnectionResult",
        "HeteroclinicProblem",
        "continue_connection",
        "find_connection",
        "solve_connection",
    ),
    "periodic": ("continue_from_hopf", "continue_periodic", "periodic_orbit_from_hopf"),
    "dynamics": (
        "FateKind",
        "Trajectory",
        "bisect_fate",
        "classify_fate",
        "simulate",
        "unstable_manifold",
    ),
}

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
del TYPE_CHECKING, lazy_exports

__all__ = [
    # the model
    "System",
    "Params",
    "Ops",
    # one-parameter continuation
    "continue_equilibria",
    "continue_branch",
    "solve_equilibrium",
    "ContinuationSettings",
    "NewtonSettings",
    "DetectionSettings",
    "PALC",
    "Natural",
    "Event",
    "ContinuationProblem",
    "EquilibriumProblem",
    "check_problem",
    "ProblemCheck",
    # results, status and errors
    "Branch",
    "BranchPoint",
    "SpecialPoint",
    "SpecialKind",
    "Status",
    "ContinuationError",
    "ConvergenceError",
    "ModelError",
    # branch switching
    "switch_branch",
    "crossing_tangents",
    # two-parameter continuation
    "continue_codim2",
    "FoldProblem",
    "HopfProblem",
    # connecting orbits
    "find_connection",
    "solve_connection",
    "continue_connection",
    "HeteroclinicProblem",
    "ConnectionResult",
    # periodic orbits
    "continue_periodic",
    "continue_from_hopf",
    "periodic_orbit_from_hopf",
    # time domain
    "simulate",
    "Trajectory",
    "unstable_manifold",
    "classify_fate",
    "FateKind",
    "bisect_fate",
]
