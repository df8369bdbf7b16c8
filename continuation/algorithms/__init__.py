"""Continuation algorithms: pseudo-arclength (:class:`PALC`) and natural stepping."""

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:  # for type checkers; _EXPORTS is what runs (names imported on first use)
    from .base import ContinuationAlgorithm, StepOutcome, StepState, adapt_ds
    from .natural import Natural
    from .palc import PALC

#: Sub-module -> the public names it defines (imported on first use: issue 27).
_EXPORTS: dict[str, tuple[str, ...]] = {
    "base": ("ContinuationAlgorithm", "StepOutcome", "StepState", "adapt_ds"),
    "natural": ("Natural",),
    "palc": ("PALC",),
}

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
del TYPE_CHECKING, lazy_exports

__all__ = ["PALC", "ContinuationAlgorithm", "Natural", "StepOutcome", "StepState", "adapt_ds"]
