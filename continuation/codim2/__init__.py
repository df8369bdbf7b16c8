"""Two-parameter continuation of fold and Hopf curves of equilibria.

:class:`FoldProblem` (Moore-Spence) and :class:`HopfProblem` (Roose-Hlavacek with a
normalisation that stays regular through Bogdanov-Takens points) are
:class:`~continuation.problem.ContinuationProblem` s with exact CasADi Jacobians;
:func:`continue_codim2` continues a located fold or Hopf point of a branch in a
second parameter and detects cusp, Bogdanov-Takens, zero-Hopf, double-Hopf and
generalised-Hopf points on the way.
"""

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:  # for type checkers; _EXPORTS is what runs (names imported on first use)
    from .curves import RENORMALISE_BELOW, codim2_events, continue_codim2, relabel_codim2
    from .fold import FoldProblem
    from .hopf import HopfProblem, normalisation

#: Sub-module -> the public names it defines (imported on first use: issue 27).
_EXPORTS: dict[str, tuple[str, ...]] = {
    "curves": ("RENORMALISE_BELOW", "codim2_events", "continue_codim2", "relabel_codim2"),
    "fold": ("FoldProblem",),
    "hopf": ("HopfProblem", "normalisation"),
}

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
del TYPE_CHECKING, lazy_exports

__all__ = [
    "RENORMALISE_BELOW",
    "FoldProblem",
    "HopfProblem",
    "codim2_events",
    "continue_codim2",
    "normalisation",
    "relabel_codim2",
]
