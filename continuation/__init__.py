"""broachkit's generic continuation and bifurcation engine.

Knows nothing of ships. The public API is exactly what this module exports.
"""

from .errors import ContinuationError, ConvergenceError, ModelError
from .newton import NewtonResult, newton
from .ops import CASADI_OPS, NUMPY_OPS, Ops
from .params import Params
from .problem import ContinuationProblem, EquilibriumProblem
from .settings import ContinuationSettings, DetectionSettings, NewtonSettings
from .status import Status
from .system import DynamicalSystem, System, check_jacobian

__all__ = [
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
