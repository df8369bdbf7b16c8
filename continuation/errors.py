"""Exception types of the continuation engine.

Bad input raises :class:`ValueError` (or the subclass :class:`ModelError`) at once.
A numerical failure is reported as a :class:`~continuation.status.Status` on the
result, and raised as :class:`ConvergenceError` only when the caller asks for it
(``throw=True``).
"""

from __future__ import annotations


class ContinuationError(RuntimeError):
    """Base class of numerical failures of the engine."""


class ConvergenceError(ContinuationError):
    """A Newton solve (or another iteration) did not converge."""


class ModelError(ValueError):
    """A model returned a non-finite value or has an inconsistent definition."""


__all__ = ["ContinuationError", "ConvergenceError", "ModelError"]
