"""Two-parameter continuation of fold and Hopf curves of equilibria."""

from .fold import FoldProblem
from .hopf import HopfProblem

__all__ = ["FoldProblem", "HopfProblem"]
