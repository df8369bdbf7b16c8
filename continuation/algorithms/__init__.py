"""Continuation algorithms: pseudo-arclength (:class:`PALC`) and natural stepping."""

from .base import ContinuationAlgorithm, StepOutcome, StepState, adapt_ds
from .natural import Natural
from .palc import PALC

__all__ = ["PALC", "ContinuationAlgorithm", "Natural", "StepOutcome", "StepState", "adapt_ds"]
